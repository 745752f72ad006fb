"""``livedrummer transcribe FILE.wav -o out.mid``: a recording's drum hits as a MIDI file.

The offline twin of ``input --audio``: the same detector (:mod:`livedrummer.acoustic.detector`)
over the whole file, from a mix (every class from one signal: the channels are averaged) or,
with ``--channels 1=kick,2=snare,...``, one microphone per drum. Prints what it found per
drum; a file it cannot read, a silent file and a channel map that names a channel the file
does not have are one line and exit status 2; clipping is one warning line (the hits are
still transcribed, their velocities capped).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .parsing import Subparsers, add_command

SILENCE_DBFS = -70.0


def add_audio_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--audio-profile",
        metavar="P",
        default=None,
        help="audio profile name or .toml path (from livedrummer audio learn); default the "
        "generic General MIDI profile",
    )
    p.add_argument(
        "--channels",
        metavar="MAP",
        default=None,
        help="one microphone per drum: 1=kick,2=snare,3=hihat,... (channels from 1; drums: "
        "kick snare hihat hihat_open tom_high tom_mid tom_low crash ride); default: a mix",
    )
    p.add_argument(
        "--recogniser",
        choices=("auto", "templates", "model"),
        default="auto",
        help="how a mix's hits are classified: the learned model trained on many kits "
        "(livedrummer acoustic train; its worst unheard kit beats the templates' worst, see "
        "docs/acoustic.md), or the audio profile's templates; auto (default): the templates "
        "when --audio-profile names a learned kit, else the model",
    )


def mix_model(args: argparse.Namespace):  # type: ignore[no-untyped-def]
    """The learned model a mix is classified by (None: the profile's templates)."""
    if args.recogniser == "templates" or (
        args.recogniser == "auto" and args.audio_profile is not None
    ):
        return None
    from livedrummer.acoustic.model import load_model

    return load_model(None)


def register(sub: Subparsers) -> None:
    p = add_command(sub, "transcribe", run)
    p.add_argument("file", type=Path, help="recording (WAV, FLAC, MP3, ... any FFmpeg reads)")
    p.add_argument("-o", "--output", type=Path, required=True, help="General MIDI drum file")
    add_audio_options(p)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from livedrummer.acoustic.detector import detect
    from livedrummer.acoustic.pieces import CLASSES, parse_channel_map
    from livedrummer.acoustic.profile import load_profile
    from livedrummer.acoustic.transcribe import hits_to_midi
    from livedrummer.errors import LivedrummerError

    from ..input.audiofile import SAMPLE_RATE, read_audio

    profile = load_profile(args.audio_profile)
    mapping = parse_channel_map(args.channels) if args.channels else None
    rec = read_audio(args.file)
    peak = float(np.max(np.abs(rec.samples)))
    if peak <= 10 ** (SILENCE_DBFS / 20):
        level = f"{20 * np.log10(peak):.0f} dBFS" if peak > 0 else "digital silence"
        raise LivedrummerError(f"{args.file}: silent (peak {level}): no hits to transcribe")
    if rec.clipped:
        share = 100.0 * rec.clipped / rec.samples.size
        print(
            f"livedrummer: warning: {args.file}: {rec.clipped:,} samples clipped "
            f"({share:.2f} %): loud hits read as full strength",
            file=sys.stderr,
        )
    model = None
    if mapping is not None:
        wanted = max(mapping) + 1
        if wanted > rec.channels:
            raise LivedrummerError(
                f"--channels: channel {wanted} named, but {args.file} has {rec.channels}"
            )
        chans = sorted(mapping)
        hits = detect(rec.samples[:, chans], SAMPLE_RATE, profile, [mapping[c] for c in chans])
    else:
        model = mix_model(args)
        hits = detect(rec.samples.mean(axis=1), SAMPLE_RATE, profile, model=model)
    try:
        hits_to_midi(hits).save(args.output)
    except OSError as exc:
        raise LivedrummerError(f"{args.output}: cannot write: {exc.strerror or exc}") from None
    counts = np.bincount(hits["cls"].astype(np.int64), minlength=len(CLASSES))
    detail = ", ".join(f"{CLASSES[c]} {n}" for c, n in enumerate(counts.tolist()) if n)
    mode = "one mic per drum" if mapping else "mix"
    how = f"profile {profile.name}"
    if mapping is None and model is not None:
        how = f"model {model.name}"
    print(
        f"{args.output}: {len(hits)} hits in {rec.duration_s:.1f} s ({mode}, {how}): "
        f"{detail or 'none'}"
    )
    return 0
