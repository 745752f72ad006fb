"""``livedrummer audio learn|profile``: an audio profile for the percussion recogniser.

``learn`` listens to the player's own kit through an audio input, one drum at a time (each
hit about eight times; after the snare its side stick, after the ride its bell, as
``--other-strokes`` names them), and writes its templates and level calibration
(:mod:`livedrummer.acoustic.profile`) for ``transcribe``/``input --audio --audio-profile``.
``profile`` makes the same from a General MIDI SoundFont's drum kit, with no microphone: it is
how the bundled ``general-midi`` profile is made (``kits/audio/general-midi.toml``).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from .parsing import Subparsers, add_command

if TYPE_CHECKING:
    from livedrummer.acoustic.profile import DetectorSettings

DEFAULT_DRUMS = "kick,snare,hihat,hihat_open,tom_high,tom_mid,tom_low,crash,ride"
#: ``--other-strokes``: the names of :data:`livedrummer.acoustic.learn.OTHER_STROKES` (not
#: imported here: ``--help`` loads no numpy).
DEFAULT_OTHER_STROKES = "side-stick,ride-bell"


def register(sub: Subparsers) -> None:
    p = add_command(sub, "audio", _usage)
    actions = p.add_subparsers(dest="action", metavar="ACTION")
    learn = actions.add_parser("learn", help="learn a kit's sound from its hits")
    learn.add_argument("--audio", metavar="DEVICE", required=True, help="audio input device")
    learn.add_argument("-o", "--output", type=Path, required=True, help="profile .toml to write")
    learn.add_argument(
        "--drums", default=DEFAULT_DRUMS, help=f"drums to learn, in order (default {DEFAULT_DRUMS})"
    )
    learn.add_argument("--hits", type=int, default=8, help="hits per drum (default 8)")
    learn.add_argument(
        "--other-strokes",
        metavar="LIST",
        default=DEFAULT_OTHER_STROKES,
        help="strokes to learn right after their drum's plain ones, when it "
        "is learnt: side-stick (snare), ride-bell (ride), or none (default "
        f"{DEFAULT_OTHER_STROKES})",
    )
    learn.add_argument(
        "--channels",
        metavar="MAP",
        default=None,
        help="one mic per drum, as for input --audio (default: a mix)",
    )
    learn.add_argument(
        "--timeout",
        type=float,
        default=60.0,
        metavar="S",
        help="seconds to wait for a drum's hits; an other stroke not heard "
        "in time is skipped (default 60)",
    )
    _lookahead_option(learn)
    learn.set_defaults(func=run_learn)
    prof = actions.add_parser("profile", help="make a profile from a SoundFont's drum kit")
    prof.add_argument("--soundfont", type=Path, required=True, help="General MIDI .sf2")
    prof.add_argument("-o", "--output", type=Path, required=True, help="profile .toml to write")
    _lookahead_option(prof)
    prof.set_defaults(func=run_profile)


def _lookahead_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--lookahead",
        type=int,
        default=2,
        metavar="N",
        help="frames of 2.67 ms the detector waits after an onset before deciding "
        "it, 1..8: 1 decides 2.7 ms sooner and tells a low tom from a kick less "
        "well (default 2)",
    )


def _settings(args: argparse.Namespace) -> DetectorSettings:
    from livedrummer.acoustic.profile import DetectorSettings
    from livedrummer.errors import LivedrummerError

    if not 1 <= args.lookahead <= 8:
        raise LivedrummerError(f"--lookahead: 1..8 frames (got {args.lookahead})")
    return DetectorSettings(lookahead=args.lookahead)


def _usage(args: argparse.Namespace) -> int:
    print("usage: livedrummer audio {learn,profile} ...")
    return 2


def _write(path: Path, text: str) -> None:
    from livedrummer.errors import LivedrummerError

    try:
        path.write_text(text)
    except OSError as exc:
        raise LivedrummerError(f"{path}: cannot write: {exc.strerror or exc}") from None


def run_learn(args: argparse.Namespace) -> int:
    from livedrummer.acoustic.learn import parse_other_strokes
    from livedrummer.acoustic.pieces import parse_channel_map, parse_class
    from livedrummer.errors import LivedrummerError

    from ..input.audiolearn import learn_kit

    drums = [parse_class(d, "--drums") for d in args.drums.split(",") if d.strip()]
    strokes = parse_other_strokes(args.other_strokes, "--other-strokes")
    mapping = parse_channel_map(args.channels) if args.channels else None
    if mapping is not None:
        missing = [d for d in drums if d not in mapping.values()]
        if missing:
            from livedrummer.acoustic.pieces import CLASSES

            names = ", ".join(CLASSES[d] for d in missing)
            raise LivedrummerError(f"--drums: {names} on no channel of --channels")
    if args.hits < 3:
        raise LivedrummerError(f"--hits: at least 3 (got {args.hits})")
    settings = _settings(args)
    profile = learn_kit(
        args.audio,
        drums,
        args.output.stem,
        args.hits,
        mapping,
        args.timeout,
        say=lambda line: print(line, flush=True),
        settings=settings,
        other_strokes=strokes,
    )
    _write(args.output, profile.to_toml())
    print(f"{args.output}: {len(drums)} drums learnt; use --audio-profile {args.output}")
    return 0


def run_profile(args: argparse.Namespace) -> int:
    from livedrummer.acoustic.learn import soundfont_profile

    from ..input.audiofile import SAMPLE_RATE

    profile = soundfont_profile(args.soundfont, SAMPLE_RATE, args.output.stem, _settings(args))
    _write(args.output, profile.to_toml())
    print(f"{args.output}: {len(set(profile.template_class.tolist()))} drums from {args.soundfont}")
    return 0
