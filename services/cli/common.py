"""Small helpers shared by subcommands: option definitions, help, and the bundled demo groove.

One vocabulary: an option that means the same thing in several subcommands is defined once here
(``--kit``, ``--map``, ``--sticking``, ``--score``, ...) or at least spelled the same; a former
spelling stays accepted, hidden from ``--help``, through :func:`add_renamed`, with a warning.
Every option's help states its default: :class:`Parser` appends ``(default X)`` to any help that
does not say it already, so the stated default cannot drift from the real one; an option whose
default is ``None`` says in its own words what happens without it.

One front door for files: every command that reads a MIDI file calls :func:`read_performance`
(``--map``, ``auto`` by default; ``--channel``), which prints the file's report on stderr
(:meth:`~livedrummer.timeline.performance.Performance.report_lines`: warnings, channels left
out, the map ``auto`` chose, unknown and ignored notes, no drum notes), and folders are searched
by :func:`midi_files` for every MIDI suffix in any case.

This module is imported to build the parser, so it imports nothing heavy (no numpy).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from livedrummer.resources import data_dir

if TYPE_CHECKING:
    from livedrummer.avatar.fit import Fitting
    from livedrummer.avatar.model import Avatar
    from livedrummer.body.rig import Rig
    from livedrummer.kit.model import Kit
    from livedrummer.midi.notemap import NoteMap
    from livedrummer.render.background import Background
    from livedrummer.sticking.result import Sticking
    from livedrummer.timeline.performance import Performance

Subparsers = Any  # argparse's _SubParsersAction is private; its type is not worth importing
Command = Callable[[argparse.Namespace], int]

DEMO_GROOVE = "grooves/gmd-drummer1-funk-80.mid"
DEMO_MAP = "roland-td"


def has_screen() -> bool:
    """A graphical session to open a window on (X11 or Wayland)."""
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def demo_groove() -> Path:
    """The bundled demo groove (Groove MIDI Dataset, CC BY 4.0; see kits/grooves)."""
    return data_dir("kits") / DEMO_GROOVE


def help_with_default(action: argparse.Action) -> str:
    """An option's help with ``(default X)`` appended where it does not state its default.

    Flags (their default is off), positional arguments and options whose default is ``None``
    are left as written.
    """
    text = action.help or ""
    default = action.default
    if (
        "default" in text
        or default is None
        or default is argparse.SUPPRESS
        or action.nargs == 0
        or not action.option_strings
    ):
        return text
    shown = f"{default:g}" if isinstance(default, float) else str(default)
    return f"{text} (default {shown})".replace("%", "%%")


class _Formatter(argparse.HelpFormatter):
    def _get_help_string(self, action: argparse.Action) -> str:
        return help_with_default(action)


class Parser(argparse.ArgumentParser):
    """The CLI's argument parser: help states every default (see the module docstring)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)


class _Renamed(argparse.Action):
    """A former spelling of an option: warns, then acts as the option's current spelling."""

    def __init__(self, option_strings: Sequence[str], dest: str, *, new: argparse.Action,
                 **kwargs: Any) -> None:  # fmt: skip
        super().__init__(option_strings, dest, **kwargs)
        self.new = new

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        current = self.new.option_strings[-1]
        print(f"livedrummer: warning: {option_string} is now spelled {current}", file=sys.stderr)
        self.new(parser, namespace, values, current)


def add_renamed(parser: Any, old: str, new: argparse.Action) -> None:
    """Accept ``old``, an option's former spelling, as ``new`` (hidden from help; warns).

    ``parser``: the parser or argument group ``new`` was added to.
    """
    parser.add_argument(
        old, action=_Renamed, new=new, nargs=new.nargs, type=new.type, choices=new.choices,
        metavar=new.metavar, default=argparse.SUPPRESS, help=argparse.SUPPRESS,
    )  # fmt: skip


def add_command(
    sub: Subparsers, name: str, func: Command, help_: str | None = None
) -> argparse.ArgumentParser:
    """The parser of subcommand ``name``; its one-line help is the one ``COMMANDS`` gives.

    (``livedrummer --help`` lists the subcommands from that table without importing them;
    a ``help_`` given here must say the same.)
    """
    from . import COMMANDS

    summary = COMMANDS[name]
    if help_ is not None and help_ != summary:
        raise ValueError(f"subcommand {name}: help {help_!r} differs from COMMANDS {summary!r}")
    parser: argparse.ArgumentParser = sub.add_parser(name, help=summary, description=summary)
    parser.set_defaults(func=func)
    return parser


def add_map_option(parser: argparse.ArgumentParser, default: str = "auto") -> None:
    """``--map``; for a file, ``auto`` (the default) picks the bundled map that knows the most
    of the file's notes and says which."""
    parser.add_argument(
        "--map", default=default,
        help=f"note map name or .toml path; auto: the bundled map that knows the most of the "
        f"file's notes (default {default})",
    )  # fmt: skip


def add_channel_option(parser: Any, default: str = "auto") -> None:
    """``--channel N|all``: which MIDI channel is the drums (parsed by
    :func:`livedrummer.midi.channels.parse_channel`)."""
    parser.add_argument(
        "--channel", default=default, metavar="N|all",
        help="MIDI channel 1-16 read as drums, or all; auto: channel 10 when notes are on "
        f"several channels (default {default})",
    )  # fmt: skip


#: What a folder given as input is searched for (any case).
MIDI_SUFFIXES = (".mid", ".midi", ".kar", ".rmi")


def midi_files(specs: Sequence[str]) -> list[Path]:
    """The files named, with every MIDI file (:data:`MIDI_SUFFIXES`) under each folder named."""
    from livedrummer.errors import LivedrummerError

    out: list[Path] = []
    for spec in specs:
        path = Path(spec)
        if path.is_dir():
            found = (p for p in path.rglob("*") if p.suffix.lower() in MIDI_SUFFIXES)
            out.extend(sorted(p for p in found if p.is_file()))
        else:
            out.append(path)
    if not out:
        raise LivedrummerError(f"no MIDI files ({' '.join(MIDI_SUFFIXES)}) in {', '.join(specs)}")
    return out


def report(path: Path | str, performance: Performance, note_map: NoteMap) -> None:
    """The lines every command prints on stderr about a file it read
    (:meth:`~livedrummer.timeline.performance.Performance.report_lines`)."""
    for line in performance.report_lines(note_map.ignored):
        print(f"livedrummer: {path}: {line}", file=sys.stderr)


def read_performance(
    args: argparse.Namespace, path: Path | str, default_map: str = "auto", *, quiet: bool = False
) -> tuple[Performance, NoteMap]:
    """``path`` read as ``--map`` and ``--channel`` say, its report printed (unless
    ``quiet``); the one way every file command reads its file."""
    from livedrummer.errors import ConfigError
    from livedrummer.midi.channels import parse_channel
    from livedrummer.midi.notemap import AUTO, bundled_note_maps, load_note_map
    from livedrummer.midi.smf import read_midi_file

    try:
        channel = parse_channel(getattr(args, "channel", "auto"))
    except ValueError as exc:
        raise ConfigError(f"--channel: {exc}") from None
    spec = getattr(args, "map", None) or default_map
    if spec == AUTO:
        maps = bundled_note_maps()
        performance = read_midi_file(path, maps, channel=channel)
        note_map = next(m for m in maps if m.name == performance.map_name)
    else:
        note_map = load_note_map(spec)
        performance = read_midi_file(path, note_map, channel=channel)
    if not quiet:
        report(path, performance, note_map)
    return performance, note_map


def add_api_option(parser: argparse.ArgumentParser) -> None:
    """``--api``: which MIDI system to find ``--midi`` ports on (services.input.midiport)."""
    parser.add_argument("--api", choices=("auto", "jack", "alsa"), default="auto",
                        help="MIDI system of --midi: jack, alsa, or auto (default: the one the "
                        "port is on, ALSA first when both have it)")  # fmt: skip


def add_kit_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--kit", default="rock5", help="kit name or .toml path (default rock5)")


def add_background_option(parser: Any, transparent: bool = True) -> None:
    """``--background COLOUR|IMAGE|chroma|transparent``: what is behind the stage
    (:mod:`livedrummer.render.background`); a window cannot be ``transparent``."""
    kinds = (
        "#rrggbb, an image file, chroma or transparent"
        if transparent
        else ("#rrggbb, an image file or chroma")
    )
    parser.add_argument(
        "--background", metavar="COLOUR|IMAGE|chroma" + ("|transparent" if transparent else ""),
        help=f"behind the stage: {kinds} (default: the dark hall)",
    )  # fmt: skip


def add_look_option(parser: Any) -> None:
    """``--look NAME``: the show lights' theme (:data:`livedrummer.kit.lights.LOOKS`)."""
    from livedrummer.kit.lights import DEFAULT_LOOK, LOOKS

    parser.add_argument("--look", choices=tuple(LOOKS), default=None,
                        help="the show lights' theme, over the [lights] of the stage, preset "
                        f"and kit files (default: theirs, else {DEFAULT_LOOK})")  # fmt: skip


def lights_of(args: argparse.Namespace, kit: Any, stage: Any = None) -> Any:
    """The show lights a command starts with (:func:`livedrummer.kit.lights.resolve_lights`):
    ``--look`` over the stage file's ``[lights]``, over the ``--preset``'s, over the kit's,
    over the default look. ``stage``: a loaded stage file (``--stage``), or None."""
    from livedrummer.body.expression import preset_lights
    from livedrummer.kit.lights import resolve_lights

    preset = getattr(args, "preset", None)
    return resolve_lights(getattr(args, "look", None), getattr(kit, "lights", None),
                          preset_lights(preset) if preset else None,
                          getattr(stage, "lights", None))  # fmt: skip


def background_of(args: argparse.Namespace, window: bool = False) -> Background:
    """The checked, decoded ``--background`` of ``args`` (one line on a bad value)."""
    from livedrummer.render.background import BackgroundError

    from ..display.background import load_background

    bg = load_background(args.background)
    if window and bg.transparent:
        raise BackgroundError(
            "--background transparent: a window shows no alpha; render PNG frames or a "
            ".mov/.webm video with `livedrummer render --background transparent`"
        )
    return bg


#: ``--fit`` choices, as :data:`livedrummer.avatar.fit.FITS` names them (kept here so that
#: building the parser imports no numpy; a test holds the two equal).
FITS = ("auto", "avatar", "kit", "none")


def add_avatar_option(parser: Any) -> None:
    """``--avatar FILE|NAME`` and ``--bone-map FILE``: who plays. The rig takes the avatar's
    proportions (:func:`rig_for`), the renderer its mesh; the same in every command."""
    parser.add_argument(
        "--avatar", metavar="FILE|NAME",
        help="the drummer: a .vrm, .glb or .gltf file, or a name from `livedrummer avatars` "
        "(default: the built-in character)",
    )  # fmt: skip
    parser.add_argument(
        "--bone-map", type=Path, metavar="FILE",
        help="TOML bone map for a glTF rig whose bone names are not known (default: "
        "FILE.bones.toml beside the avatar, else the VRM map or known rig names)",
    )  # fmt: skip
    parser.add_argument(
        "--fit", choices=FITS, default="auto",
        help="an avatar whose size does not suit the kit: scale the avatar to the body the kit "
        "is built for, move the throne, pedals and stands to the avatar, or neither; auto "
        "leaves an avatar that reaches the kit alone (default: auto)",
    )  # fmt: skip


def avatar_of(args: argparse.Namespace) -> Avatar | None:
    """The avatar ``--avatar`` names, loaded and bound to the body (None: the built-in one)."""
    spec = getattr(args, "avatar", None)
    if spec is None:
        return None
    from livedrummer.avatar.loader import load_avatar

    return load_avatar(spec, getattr(args, "bone_map", None))


def avatar_argv(args: argparse.Namespace) -> list[str]:
    """``--avatar``/``--bone-map`` as given, for a child process (``up``)."""
    out: list[str] = []
    if getattr(args, "avatar", None) is not None:
        out += ["--avatar", str(args.avatar)]
    if getattr(args, "bone_map", None) is not None:
        out += ["--bone-map", str(args.bone_map)]
    if getattr(args, "fit", "auto") != "auto":
        out += ["--fit", str(args.fit)]
    return out


def fitting_of(args: argparse.Namespace, kit: Kit, avatar: Avatar | None) -> Fitting:
    """``--fit``: how the avatar plays the kit (:func:`livedrummer.avatar.fit.fit_avatar`, the
    path ``avatar info`` reports); with an avatar, one line on stderr says how it was fitted
    and why. A piece left out of reach is the one-line error."""
    from livedrummer.avatar.fit import fit_avatar

    done = fit_avatar(kit, avatar, getattr(args, "fit", "auto"))
    if avatar is not None:
        print(f"livedrummer: fit: {done.line}", file=sys.stderr)
    return done


def fitted(args: argparse.Namespace, kit: Kit, avatar: Avatar | None
           ) -> tuple[Kit, Avatar | None]:  # fmt: skip
    """The kit and avatar to play, as :func:`fitting_of` settles them."""
    done = fitting_of(args, kit, avatar)
    return done.kit, done.avatar


def rig_for(kit: Kit, avatar: Avatar | None) -> Rig:
    """The body fitted to ``kit`` with ``avatar``'s proportions (the default body's without
    one); a piece the avatar cannot reach is the rig's one-line error, naming the avatar."""
    from livedrummer.body.rig import build_rig
    from livedrummer.errors import UnreachableError

    if avatar is None:
        return build_rig(kit)
    try:
        return build_rig(kit, avatar.lengths)
    except UnreachableError as exc:
        raise UnreachableError(f"{exc}, with avatar {avatar.source}") from None


#: The limb-assignment strategies, as :data:`livedrummer.sticking.STRATEGIES` names them (kept
#: here so that building the parser imports no numpy; a test holds the two equal).
STICKING_STRATEGIES = ("optimal", "kragtwijk-basic", "kragtwijk-pair", "smed")


def add_sticking_options(p: argparse.ArgumentParser) -> None:
    """``--sticking`` and ``--score``: who plays each note, the same in every command."""
    add_renamed(p, "--strategy", p.add_argument(  # checked by the entry point: one line
        "--sticking", default=STICKING_STRATEGIES[0], metavar="STRATEGY",
        help=f"limb assignment: {', '.join(STICKING_STRATEGIES)}",
    ))  # fmt: skip
    p.add_argument(
        "--score", type=Path, metavar="FILE",
        help="edited text sticking score (sticking --format text) whose limbs are played "
        "(default: none, the strategy decides every note)",
    )  # fmt: skip


def add_motion_options(p: argparse.ArgumentParser) -> None:
    """How the body is animated (check, export, render, display): sticking, strokes, preset."""
    add_sticking_options(p)
    add_style_options(p)


def add_style_options(p: argparse.ArgumentParser) -> None:
    """``--preset`` and ``--strokes``: how the body plays, the same for files and live."""
    p.add_argument(
        "--preset", default=None, help="expression preset name or .toml path (default: neutral)"
    )
    p.add_argument(
        "--strokes",
        default="livedrummer",
        choices=("livedrummer", "paper", "smed"),
        help="stroke overlap rules (default livedrummer)",
    )


def add_osc_options(p: argparse.ArgumentParser, what: str) -> None:
    """``--osc PORT`` and ``--osc-allow ADDR,...`` (see :mod:`services.osc`)."""
    p.add_argument("--osc", type=int, metavar="PORT",
                   help=f"OSC show control on this UDP port ({what}; no authentication: "
                   "loopback only unless --osc-allow) (default: none)")  # fmt: skip
    p.add_argument(
        "--osc-allow",
        metavar="ADDR,...",
        help="also take OSC from these sender addresses (default: loopback only)",
    )
    p.add_argument("--cues", type=Path, metavar="FILE",
                   help="cue list (TOML): OSC /livedrummer/cue NAME fires a cue, and live "
                   "its bar cues fire as the beat tracker counts bars (default: none)")  # fmt: skip


def cues_of(args: argparse.Namespace) -> dict[str, Any]:
    """``--cues FILE`` loaded (one line naming the file, cue and key when it is bad)."""
    if getattr(args, "cues", None) is None:
        return {}
    from livedrummer.live.cues import load_cues

    return dict(load_cues(args.cues))


def osc_allow(args: argparse.Namespace) -> tuple[str, ...]:
    """``--osc-allow`` checked: one line naming a bad address."""
    from livedrummer.errors import ConfigError

    from ..osc import parse_allow

    if args.osc is not None and not 0 <= args.osc <= 65535:
        raise ConfigError(f"--osc: expected a UDP port 0..65535 (got {args.osc})")
    try:
        return parse_allow(args.osc_allow)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None


def lights_argv(args: argparse.Namespace) -> list[str]:
    """What a child display needs to start from the same lights (:func:`lights_of`) as this
    command: ``--look`` and the ``--preset`` (for its ``[lights]``), as given."""
    out = ["--look", args.look] if getattr(args, "look", None) else []
    preset = getattr(args, "preset", None)
    return out + (["--preset", str(preset)] if preset is not None else [])


def style_argv(args: argparse.Namespace) -> list[str]:
    """``--preset``/``--strokes`` as given, for a child process (``up``)."""
    out = ["--strokes", args.strokes]
    if args.preset is not None:
        out += ["--preset", str(args.preset)]
    return out


def sticking_of(args: argparse.Namespace, performance: Performance, kit: Kit) -> Sticking:
    """The sticking that ``--sticking`` and ``--score`` ask for, from the one entry point
    :func:`livedrummer.sticking.stick_performance` (what ``livedrummer sticking`` prints)."""
    from livedrummer.sticking.strategy import stick_performance

    return stick_performance(performance, kit, args.sticking, score=args.score)


#: Multisample counts a GL context accepts (powers of two; Mesa's llvmpipe offers up to 8).
AA_SAMPLES = (0, 1, 2, 4, 8, 16)


def check_aa(samples: int) -> None:
    """``--aa N``: one line naming the counts allowed, before any GL context is made."""
    from livedrummer.errors import ConfigError

    if samples not in AA_SAMPLES:
        allowed = ", ".join(str(n) for n in AA_SAMPLES)
        raise ConfigError(f"--aa {samples}: expected one of {allowed} (0: no multisampling)")


def parse_aa(text: str) -> tuple[int, bool]:
    """``--aa fxaa|N`` of ``render``: (multisample count, FXAA pass), one line when bad."""
    from livedrummer.errors import ConfigError

    value = str(text).strip().lower()
    if value == "fxaa":
        return 0, True
    if not value.isdigit():
        allowed = ", ".join(str(n) for n in AA_SAMPLES)
        raise ConfigError(f"--aa {text}: expected fxaa or one of {allowed}")
    check_aa(int(value))
    return int(value), False


def kit_source(args: argparse.Namespace, clock: Any, decoder: Any) -> Any:
    """The ``--midi PORT | --virtual NAME | --serial DEV`` source (a
    ``services.input.base.MidiSource``) of ``monitor``, ``map learn``, ``calibrate`` and
    ``up``'s check before it starts anything; checked unless ``--wait``: a device that is not
    there is one line naming what is."""
    from livedrummer.errors import ConfigError

    if args.serial is not None:
        from ..input.serialport import BAUD_RATES, SerialSource

        if args.baud not in BAUD_RATES:
            raise ConfigError(f"--baud: expected one of {BAUD_RATES} (got {args.baud})")
        source: Any = SerialSource(args.serial, clock, decoder, args.baud)
    else:
        from ..input.midiport import MidiPortSource

        virtual = getattr(args, "virtual", None)  # up has no --virtual
        source = MidiPortSource(virtual or args.midi, clock, decoder, api=args.api,
                                virtual=virtual is not None)  # fmt: skip
    if not getattr(args, "wait", False):
        source.check()
    return source
