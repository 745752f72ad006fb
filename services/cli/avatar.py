"""``livedrummer avatar info FILE|NAME``: what an avatar file holds and how it maps onto the body.

Prints the humanoid bones found (and from which map: VRM 1.0, VRM 0.x, Mixamo, Blender/Rigify,
Unreal or a bone map file), which of our joints each was mapped from, required bones that are
missing, the facing, up axis, unit and height found, the proportions the rig will use, the
mesh's triangles and the materials with their textures, and how it is fitted to ``--kit``
with ``--fit`` (:func:`livedrummer.avatar.fit.fit_avatar`, the very call ``render``, ``check``,
``export``, ``synth`` and ``display`` make, so "usable" here is what they do); ``--json``
prints the same as one object. An avatar that cannot be used (a bone missing, or a piece the
fit leaves out of reach) is still described, then its one-line reason ends the output and the
exit status is 2.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from .parsing import Subparsers, add_command
from .performer import FITS


def register(sub: Subparsers) -> None:
    p = add_command(sub, "avatar", lambda _args: 2)
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    info = actions.add_parser(
        "info",
        help="bones, proportions, triangles and textures",
        description="bones, proportions, triangles and textures",
    )
    info.add_argument("file", metavar="FILE|NAME", help="a .vrm, .glb or .gltf file, or a name")
    info.add_argument(
        "--bone-map",
        type=Path,
        metavar="FILE",
        help="TOML bone map (default: FILE.bones.toml beside the file, if any)",
    )
    info.add_argument("--json", action="store_true", help="print one JSON object")
    info.add_argument(
        "--kit", default="rock5", help="the kit it is fitted to, as render --kit (default: rock5)"
    )
    info.add_argument(
        "--fit",
        choices=FITS,
        default="auto",
        help="how it is fitted, as render --fit (default: auto)",
    )
    info.set_defaults(func=run_info)


def run_info(args: argparse.Namespace) -> int:
    from livedrummer.avatar.loader import inspect_avatar, resolve_avatar
    from livedrummer.avatar.model import AvatarError
    from livedrummer.kit.loader import load_kit

    path = resolve_avatar(args.file)
    if path is None:
        raise AvatarError(f"avatar {args.file!r} is the built-in character: no file to describe")
    info = inspect_avatar(path, args.bone_map, load_kit(args.kit), args.fit)
    report = info.as_json()
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        print("\n".join(text_lines(report)))
    if info.error:
        raise AvatarError(info.error)
    return 0


def text_lines(r: dict[str, Any]) -> list[str]:
    """The human-readable ``avatar info`` of :meth:`AvatarInfo.as_json`'s object."""
    found = r["humanoid_bones"]
    lines = [
        f"{r['file']}: {r['convention'] or 'no humanoid map'}, {r['nodes']} nodes, "
        f"{'usable' if r['usable'] else 'NOT usable'}"
    ]
    lines.append(f"  humanoid bones   {len(found)} found: {', '.join(found) or '-'}")
    lines.append(f"  required missing {', '.join(r['required_missing']) or 'none'}")
    if "proportions_m" not in r:
        return lines
    lines.append(
        f"  frame            faces {r['faces']}, up {r['up']}, unit "
        f"{r['unit_scale']:g} m, height {r['height_m']:.3f} m, "
        f"digest {r['digest']}"
    )
    mapped = ", ".join(f"{ours}<-{node}" for ours, node in r["mapped"].items())
    lines.append(f"  mapped           {mapped}")
    props = r["proportions_m"]
    lines.append("  proportions m    " + " ".join(f"{k} {v:.3f}" for k, v in props.items()))
    lines.append(
        f"  mesh             {r['triangles']} triangles, {r['vertices']} vertices, "
        f"{r['primitives']} primitives, {r['curled_finger_bones']} finger bones "
        "curled"
    )
    mats = []
    for m in r["materials"]:
        tex = f"texture {m['texture'][0]}x{m['texture'][1]}" if m["texture"] else "colour"
        mats.append(f"{m['name']} ({tex}, {m['alpha']}, {m['shading']})")
    lines.append(f"  materials        {r['textures']} textures: {'; '.join(mats)}")
    if "fit" in r:
        lines.append(
            f"  fit              --fit {r['fit']['asked']} on kit {r['fit']['kit']}: "
            f"{r['fit']['said']}"
        )
    return lines
