"""``livedrummer up --stage stage.toml``: a live stage of several performers, supervised.

For each performer of the stage file with a live ``source``
(:mod:`livedrummer.stage.source`): one input daemon (``--performer K``, its map) and one
synth (its kit, map, avatar, ``--performer K``), on ports of their own; then ONE display
drawing the whole stage (``display --live --stage``, :mod:`services.display.stage_live`),
subscribed to every synth. Performer K's services use ``--port-base + 20*K`` + 0, 1 (input
pub, control) and + 10, 11 (synth pub, control). Everything runs under the
:mod:`services.process.supervisor` as ``up`` runs it: started in order, each after the previous one
said ready, a dead service restarted alone, all stopped on Ctrl-C, ``--seconds`` or when the
window closes; ``--headless``, ``--frames-dir``, ``--video``, ``--wait``, ``--curve-secret``
mean what they mean for ``up``.

Settings. Each performer's note map, kit and avatar, with the rig's D and L, are resolved
once (:func:`performer_settings`; a map ``auto`` becomes the one its source's notes mean) into
a settings file its input daemon and its synths are given (``--settings``, :mod:`.settings`).

Why one synth per performer (not one synth for all). Isolation: a flood of notes or a crash
in one performer's synth delays or stops no other performer's drummer; each is restarted
alone by the supervisor while the others keep playing; and the operating system spreads the
synths over the cores (on two shared cores, one synth for all would serialise every
performer's hand decisions behind the busiest one). Each pose stream then keeps its own
sequence numbers, so a gap is one performer's loss. The cost is one process (about one
Python interpreter's memory) per performer, and the display's one SUB socket each.

Ensembles. With ``[ensemble] copies = N`` each live performer is drawn N times (at the
formation's spots, :meth:`~livedrummer.stage.stagefile.Stage.players`): copy ``c`` of the
performer whose first drummer is ``k0`` has its own synth, ids and ports ``k0 + c``, on the
performer's one input daemon (which waits for its N subscribers), started with ``synth --vary
SEED --vary-ms W --vary-amplitude R`` from the stage's ``[ensemble]`` (seed, warp_ms,
amplitude): a seeded delay of every onset in ``0..D - L`` and a gain on its velocity
(:func:`livedrummer.stage.variation.vary_live`, the live twin of the offline warp). With the
default ``--delay-ms`` = ``--lookahead-ms`` there is no slack and the copies only differ in
loudness: give ``up`` a larger ``--delay-ms``.

Limits: a stage video has no drum track (the journals are per performer; ``render --stage``
makes one from files); each performer's ``preset`` is played live by its synth; the sources
are checked for syntax before starting, but a missing MIDI port is found by its input daemon
(one line, or ``--wait``).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

from ..process.program import program_argv

if TYPE_CHECKING:
    from livedrummer.live.settings import Delay, ShowSettings
    from livedrummer.stage.stagefile import Performer
    from livedrummer.stage.variation import Variation

    from ..process.supervisor import ServiceSpec

PORTS_PER_PERFORMER = 20


def stage_specs(
    args: argparse.Namespace, stage_file: Path, delay: Delay, folder: Path
) -> list[ServiceSpec]:
    """The services of a live stage, in start order (see the module docstring); each
    performer's settings resolved once (:func:`performer_settings`) into a file in ``folder``
    that its input daemon and its synths are given."""
    from livedrummer.stage.stagefile import load_stage

    from ..process.supervisor import ServiceSpec
    from .staging import check_room
    from .up_launch import curve_argv, frame_size, recorded, windowed

    stage = load_stage(stage_file)
    check_room(stage)
    live = stage.live()
    curve = curve_argv(args)
    me = program_argv()
    specs: list[ServiceSpec] = []
    subs: list[str] = []
    settings: list[str] = []  # each drummer's file, for the display too
    for k, performer, _spot in live:
        ep, near = _endpoints(args, k)
        name = performer.id if performer.copy == 0 else f"{performer.id}.{performer.copy}"
        given = folder / f"settings-{k - performer.copy}.json"  # a copy plays its performer's
        if performer.copy > 0:  # an ensemble copy: its own synth on its performer's input
            near["in_pub"] = _endpoints(args, k - performer.copy)[1]["in_pub"]
        else:
            performer_settings(performer, stage_file, delay).save(given)
            specs.append(
                _input(args, stage_file, k, performer, ep, curve["input"], stage.copies, given)
            )
        specs.append(
            ServiceSpec(
                f"synth-{name}",
                [
                    *me,
                    "synth",
                    "--sub",
                    near["in_pub"],
                    "--pub",
                    ep["syn_pub"],
                    "--control",
                    ep["syn_ctl"],
                    "--settings",
                    str(given),
                    "--performer",
                    str(k),
                    *_vary(stage.variation(k)),
                    *(["--preset", performer.preset] if performer.preset else []),
                    *curve["synth"],
                ],
            )
        )
        subs.append(near["syn_pub"])
        settings.append(str(given))
    display = [*me, "display", "--live", "--stage", str(stage_file.resolve()),
               "--sub", ",".join(subs), "--settings", ",".join(settings),
               "--camera", args.camera, "--fps", str(args.fps),
               "--size", frame_size(args), *curve["display"]]  # fmt: skip
    if windowed(args):
        display += ["--monitor", str(args.monitor)]
        display += ["--fullscreen"] if args.fullscreen else []
    else:
        display += ["--headless", "--frames-dir", str(args.frames_dir)]
        display += [] if args.png and args.video is None else ["--no-png"]
        display += ["--video", str(args.video)] if args.video is not None else []
        display += ["--seconds", str(args.seconds)] if recorded(args) else []
    display += ["--look", args.look] if args.look else []  # over the stage's and kit's [lights]
    specs.append(ServiceSpec("display", display, ends_rig=windowed(args) or recorded(args)))
    return specs


def _endpoints(args: argparse.Namespace, k: int) -> tuple[dict[str, str], dict[str, str]]:
    """Drummer ``k``'s endpoints: as bound, and as a local service connects to them."""
    base = args.port_base + PORTS_PER_PERFORMER * k
    ep = {
        name: f"tcp://{args.bind}:{base + d}"
        for name, d in (("in_pub", 0), ("in_ctl", 1), ("syn_pub", 10), ("syn_ctl", 11))
    }
    near = {name: e.replace("tcp://0.0.0.0:", "tcp://127.0.0.1:") for name, e in ep.items()}
    return ep, near


def _vary(variation: Variation | None) -> list[str]:
    """``synth --vary`` options for an ensemble copy (the synth caps the shift at D - L)."""
    if variation is None:
        return []
    return [
        "--vary",
        str(variation.seed),
        "--vary-ms",
        f"{variation.warp_s * 1000:g}",
        "--vary-amplitude",
        f"{variation.amplitude:g}",
    ]


def performer_settings(performer: Performer, stage_file: Path, delay: Delay) -> ShowSettings:
    """Performer's settings, resolved once for its input daemon and synths: its kit, avatar
    and map, a map ``auto`` made the one its source's notes mean (for a file, the bundled
    map that knows the most of them, as ``input --file`` chooses it; roland-td for a kit),
    the rig's D and L; a stage sounds nothing live."""
    from livedrummer.live.settings import AUTO, AvatarChoice, ShowSettings, spec_path
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.stage.source import parse_source

    from .files import DEMO_MAP, read_performance

    note_map = performer.map
    if note_map == AUTO:
        source = parse_source(performer.source or "", stage_file.parent)
        note_map = DEMO_MAP
        if source.kind == "file":
            quiet = argparse.Namespace(map=AUTO, channel=performer.channel)
            note_map = read_performance(quiet, source.value, quiet=True)[1].name
    load_note_map(note_map)  # a bad map is one line before anything starts
    return ShowSettings(
        note_map=spec_path(note_map) or note_map,
        kit=spec_path(performer.kit) or performer.kit,
        avatar=AvatarChoice(spec_path(performer.avatar)),
        delay=delay,
    )


def _input(
    args: argparse.Namespace,
    stage_file: Path,
    k: int,
    performer: Performer,
    ep: dict[str, str],
    curve: list[str],
    copies: int,
    settings: Path,
) -> ServiceSpec:
    """Performer ``k``'s input daemon, waiting for its ``copies`` synths to subscribe."""
    from livedrummer.stage.source import parse_source

    from ..process.supervisor import ServiceSpec

    source = parse_source(performer.source or "", stage_file.parent)
    src = source.input_argv()
    src += ["--api", args.api] if source.opens_midi else []
    src += ["--wait"] if args.wait and source.kind in ("midi", "serial") else []
    journal = ["--no-journal"] if args.no_journal else []
    return ServiceSpec(
        f"input-{performer.id}",
        [
            *program_argv(),
            "input",
            *src,
            "--settings",
            str(settings),
            "--performer",
            str(k),
            "--pub",
            ep["in_pub"],
            "--control",
            ep["in_ctl"],
            "--wait-subscribers",
            str(copies),
            *journal,
            *curve,
        ],
    )


def run_stage(args: argparse.Namespace) -> int:
    """``up --stage``: check everything, then supervise the stage's services."""
    from livedrummer.errors import ConfigError

    from .up_launch import check_before_start, resolve

    if args.seconds is not None and not args.seconds > 0:
        raise ConfigError(f"--seconds: expected > 0 (got {args.seconds})")
    wait = args.wait
    args.wait = True  # the sources are the stage file's (checked below), the options here
    rig = resolve(args)  # D and L for every performer; kits, maps, avatars are the file's
    check_before_start(args, rig)
    args.wait = wait
    with tempfile.TemporaryDirectory(prefix="livedrummer-stage-") as tmp:
        return _run(args, stage_specs(args, args.stage, rig.delay, Path(tmp)))


def _run(args: argparse.Namespace, specs: list[ServiceSpec]) -> int:
    from livedrummer.errors import ConfigError

    from ..process.supervisor import Supervisor
    from .up_launch import supervise

    last = max(
        int(s.argv[s.argv.index("--performer") + 1]) for s in specs if "--performer" in s.argv
    )
    if args.port_base + PORTS_PER_PERFORMER * last + 11 > 65535:
        raise ConfigError(f"--port-base {args.port_base}: performer {last}'s ports pass 65535")
    if args.video is not None:
        args.video.parent.mkdir(parents=True, exist_ok=True)
    performers = sum(1 for s in specs if s.name.startswith("synth-"))
    print(f"up: a stage of {performers} live performers from {args.stage}", flush=True)
    return supervise(args, Supervisor(specs))
