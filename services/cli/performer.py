"""Who plays and how, the same in every command: kit, avatar and fit, sticking, style.

The options (``--kit``, ``--avatar``, ``--fit``, ``--sticking``, ``--score``, ``--preset``,
``--strokes``), what they resolve to (the avatar, the rig, the sticking) and their argv for a
child process. The choice lists are kept here as plain tuples so that building the parser
imports no numpy; tests hold them equal to the library's.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .parsing import add_renamed

if TYPE_CHECKING:
    from livedrummer.avatar.fit import Fitting
    from livedrummer.avatar.model import Avatar
    from livedrummer.body.rig import Rig
    from livedrummer.kit.model import Kit
    from livedrummer.sticking.result import Sticking
    from livedrummer.timeline.performance import Performance


def add_kit_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--kit", default="rock5", help="kit name or .toml path (default rock5)")


#: ``--fit`` choices, as :data:`livedrummer.avatar.fit.FITS` names them (kept here so that
#: building the parser imports no numpy; a test holds the two equal).
FITS = ("auto", "avatar", "kit", "none")


def add_avatar_option(parser: Any) -> None:
    """``--avatar FILE|NAME`` and ``--bone-map FILE``: who plays. The rig takes the avatar's
    proportions (:func:`rig_for`), the renderer its mesh; the same in every command."""
    parser.add_argument(
        "--avatar",
        metavar="FILE|NAME",
        help="the drummer: a .vrm, .glb or .gltf file, or a name from `livedrummer avatars` "
        "(default: the built-in character)",
    )
    parser.add_argument(
        "--bone-map",
        type=Path,
        metavar="FILE",
        help="TOML bone map for a glTF rig whose bone names are not known (default: "
        "FILE.bones.toml beside the avatar, else the VRM map or known rig names)",
    )
    parser.add_argument(
        "--fit",
        choices=FITS,
        default="auto",
        help="an avatar whose size does not suit the kit: scale the avatar to the body the kit "
        "is built for, move the throne, pedals and stands to the avatar, or neither; auto "
        "leaves an avatar that reaches the kit alone (default: auto)",
    )


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


def fitted(args: argparse.Namespace, kit: Kit, avatar: Avatar | None) -> tuple[Kit, Avatar | None]:
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
    add_renamed(
        p,
        "--strategy",
        p.add_argument(  # checked by the entry point: one line
            "--sticking",
            default=STICKING_STRATEGIES[0],
            metavar="STRATEGY",
            help=f"limb assignment: {', '.join(STICKING_STRATEGIES)}",
        ),
    )
    p.add_argument(
        "--score",
        type=Path,
        metavar="FILE",
        help="edited text sticking score (sticking --format text) whose limbs are played "
        "(default: none, the strategy decides every note)",
    )


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
