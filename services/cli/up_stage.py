"""``livedrummer up --stage stage.toml``: a live stage of several performers, supervised.

For each performer of the stage file with a live ``source``
(:mod:`livedrummer.stage.source`): one input daemon (``--performer K``, its map) and one
synth (its kit, map, avatar, ``--performer K``), on ports of their own; then ONE display
drawing the whole stage (``display --live --stage``, :mod:`services.display.stage_live`),
subscribed to every synth. Performer K's services use ``--port-base + 20*K`` + 0, 1 (input
pub, control) and + 10, 11 (synth pub, control). Everything runs under the
:mod:`services.supervisor` as ``up`` runs it: started in order, each after the previous one
said ready, a dead service restarted alone, all stopped on Ctrl-C, ``--seconds`` or when the
window closes; ``--headless``, ``--frames-dir``, ``--video``, ``--wait``, ``--curve-secret``
mean what they mean for ``up``.

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
from pathlib import Path
from typing import TYPE_CHECKING

from ..program import program_argv

if TYPE_CHECKING:
    from livedrummer.stage.stagefile import Performer
    from livedrummer.stage.variation import Variation

    from ..supervisor import ServiceSpec

PORTS_PER_PERFORMER = 20


def stage_specs(args: argparse.Namespace, stage_file: Path) -> list[ServiceSpec]:
    """The services of a live stage, in start order (see the module docstring)."""
    from livedrummer.stage.stagefile import load_stage

    from ..supervisor import ServiceSpec
    from .common import DEMO_MAP
    from .staging import check_room
    from .up import curve_argv, frame_size, recorded, windowed

    stage = load_stage(stage_file)
    check_room(stage)
    live = stage.live()
    curve = curve_argv(args)
    me = program_argv()
    specs: list[ServiceSpec] = []
    subs: list[str] = []
    for k, performer, _spot in live:
        ep, near = _endpoints(args, k)
        name = performer.id if performer.copy == 0 else f"{performer.id}.{performer.copy}"
        if performer.copy > 0:  # an ensemble copy: its own synth on its performer's input
            near["in_pub"] = _endpoints(args, k - performer.copy)[1]["in_pub"]
        else:
            specs.append(_input(args, stage_file, k, performer, ep, curve["input"], stage.copies))
        synth_map = DEMO_MAP if performer.map == "auto" else performer.map
        specs.append(ServiceSpec(f"synth-{name}", [
            *me, "synth", "--sub", near["in_pub"], "--pub", ep["syn_pub"],
            "--control", ep["syn_ctl"], "--kit", performer.kit, "--map", synth_map,
            "--lookahead-ms", str(args.lookahead_ms), "--delay-ms", str(args.delay_ms),
            "--performer", str(k), *_avatar(performer), *_vary(stage.variation(k)),
            *(["--preset", performer.preset] if performer.preset else []),
            *curve["synth"]]))  # fmt: skip
        subs.append(near["syn_pub"])
    display = [*me, "display", "--live", "--stage", str(stage_file.resolve()),
               "--sub", ",".join(subs), "--camera", args.camera, "--fps", str(args.fps),
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
    ep = {name: f"tcp://{args.bind}:{base + d}" for name, d in
          (("in_pub", 0), ("in_ctl", 1), ("syn_pub", 10), ("syn_ctl", 11))}  # fmt: skip
    near = {name: e.replace("tcp://0.0.0.0:", "tcp://127.0.0.1:") for name, e in ep.items()}
    return ep, near


def _vary(variation: Variation | None) -> list[str]:
    """``synth --vary`` options for an ensemble copy (the synth caps the shift at D - L)."""
    if variation is None:
        return []
    return ["--vary", str(variation.seed), "--vary-ms", f"{variation.warp_s * 1000:g}",
            "--vary-amplitude", f"{variation.amplitude:g}"]  # fmt: skip


def _input(args: argparse.Namespace, stage_file: Path, k: int, performer: Performer,
           ep: dict[str, str], curve: list[str], copies: int) -> ServiceSpec:  # fmt: skip
    """Performer ``k``'s input daemon, waiting for its ``copies`` synths to subscribe."""
    from livedrummer.stage.source import parse_source

    from ..supervisor import ServiceSpec

    source = parse_source(performer.source or "", stage_file.parent)
    src = source.input_argv()
    src += ["--api", args.api] if source.opens_midi else []
    src += ["--wait"] if args.wait and source.kind in ("midi", "serial") else []
    journal = ["--no-journal"] if args.no_journal else []
    return ServiceSpec(f"input-{performer.id}", [
        *program_argv(), "input", *src, "--map", performer.map, "--performer", str(k),
        "--pub", ep["in_pub"], "--control", ep["in_ctl"], "--wait-subscribers", str(copies),
        *journal, *curve])  # fmt: skip


def _avatar(performer: Performer) -> list[str]:
    return [] if performer.avatar is None else ["--avatar", performer.avatar]


def run_stage(args: argparse.Namespace) -> int:
    """``up --stage``: check everything, then supervise the stage's services."""
    from livedrummer.errors import ConfigError

    from ..supervisor import Supervisor
    from .up import _supervise, check_before_start

    if args.seconds is not None and not args.seconds > 0:
        raise ConfigError(f"--seconds: expected > 0 (got {args.seconds})")
    wait = args.wait
    args.wait = True  # the sources are the stage file's (checked below), the options here
    check_before_start(args)
    args.wait = wait
    specs = stage_specs(args, args.stage)
    last = max(int(s.argv[s.argv.index("--performer") + 1]) for s in specs
               if "--performer" in s.argv)  # fmt: skip
    if args.port_base + PORTS_PER_PERFORMER * last + 11 > 65535:
        raise ConfigError(f"--port-base {args.port_base}: performer {last}'s ports pass 65535")
    if args.video is not None:
        args.video.parent.mkdir(parents=True, exist_ok=True)
    performers = sum(1 for s in specs if s.name.startswith("synth-"))
    print(f"up: a stage of {performers} live performers from {args.stage}", flush=True)
    return _supervise(args, Supervisor(specs))
