"""Which node of an avatar file is which humanoid bone: VRM maps, known rig names, a user's map.

Why this shape. Everything after this module speaks one vocabulary, the VRM 1.0 humanoid bone
names (``hips``, ``leftUpperArm``, ``rightMiddleProximal``, ...), because it is the one
standard humanoid naming there is and VRM 0.x differs from it only in the thumb. A file's map
is found in this order, and the first that applies is used (never mixed):

1. a user's bone map file (TOML, ``[bones]`` table of ``humanoidBone = "node name"``), given
   explicitly or found beside the avatar as ``NAME.bones.toml``; read strictly through
   :mod:`livedrummer.config` (an unknown bone is named with the file, table and key and a
   "did you mean"; a node name the file lacks is named too);
2. VRM 1.0's ``VRMC_vrm.humanoid.humanBones`` (``{bone: {node: i}}``);
3. VRM 0.x's ``VRM.humanoid.humanBones`` (``[{bone, node}]``; its thumb's proximal,
   intermediate and distal are VRM 1.0's metacarpal, proximal and distal);
4. node names of common rigs: Mixamo (``mixamorig:LeftForeArm``, any ``mixamorigN:`` or
   ``_`` prefix), Blender's metarig and Rigify's deform bones (``DEF-forearm.L``), and the
   Unreal mannequin (``lowerarm_l``); the convention that names every required bone wins.

:data:`REQUIRED` bones must all be present (VRM's own required set); a file that has some but
not all is refused naming the missing ones. Limits: name matching is exact per convention
(after the prefix), case-insensitive; rigs with other names need a bone map file.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from livedrummer.avatar.model import AvatarError
from livedrummer.config import Table, read_toml
from livedrummer.errors import ConfigError

if TYPE_CHECKING:
    from livedrummer.avatar.gltf import GltfScene


class BoneMapError(AvatarError, ConfigError):
    """A bone map file is wrong; the message names the file, table and key."""


SIDES = ("left", "right")
_LIMBS = ("Shoulder", "UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toes")
FINGERS = ("Thumb", "Index", "Middle", "Ring", "Little")
_THUMB = ("Metacarpal", "Proximal", "Distal")
_FINGER = ("Proximal", "Intermediate", "Distal")


def _finger_bones(side: str) -> list[str]:
    return [f"{side}{f}{p}" for f in FINGERS for p in (_THUMB if f == "Thumb" else _FINGER)]


#: Every humanoid bone we read, VRM 1.0 names.
HUMAN_BONES: tuple[str, ...] = (
    "hips", "spine", "chest", "upperChest", "neck", "head",
    *(f"{s}{limb}" for s in SIDES for limb in _LIMBS),
    *(b for s in SIDES for b in _finger_bones(s)),
)  # fmt: skip

#: The bones an avatar must have (VRM 1.0's required set).
REQUIRED: tuple[str, ...] = (
    "hips",
    "spine",
    "head",
    *(
        f"{s}{limb}"
        for s in SIDES
        for limb in ("UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot")
    ),
)


@dataclass(frozen=True)
class Humanoid:
    """Humanoid bone name -> node index, and where the map came from."""

    bones: dict[str, int]
    convention: str  # "VRM 1.0", "VRM 0.x", "Mixamo", "Blender/Rigify", "Unreal", "bone map F"

    def missing(self) -> list[str]:
        return [b for b in REQUIRED if b not in self.bones]


def _vrm0_name(bone: str) -> str:
    for side in SIDES:
        for old, new in (
            ("ThumbProximal", "ThumbMetacarpal"),
            ("ThumbIntermediate", "ThumbProximal"),
        ):
            if bone == f"{side}{old}":
                return f"{side}{new}"
    return bone


def from_vrm(ext: dict[str, Any], n_nodes: int, source: str) -> Humanoid | None:
    def node(value: Any, bone: str, where: str) -> int:
        if not isinstance(value, int) or not 0 <= value < n_nodes:
            raise AvatarError(
                f"{source}: {where} bone {bone!r} names node {value!r}, "
                f"not one of the file's {n_nodes} nodes"
            )
        return value

    vrm1 = ext.get("VRMC_vrm")
    if isinstance(vrm1, dict):
        human = (vrm1.get("humanoid") or {}).get("humanBones")
        if not isinstance(human, dict):
            raise AvatarError(f"{source}: VRMC_vrm has no humanoid.humanBones table")
        bones = {
            b: node((v or {}).get("node"), b, "VRMC_vrm humanoid")
            for b, v in human.items()
            if b in HUMAN_BONES
        }
        return Humanoid(bones, "VRM 1.0")
    vrm0 = ext.get("VRM")
    if isinstance(vrm0, dict):
        human = (vrm0.get("humanoid") or {}).get("humanBones")
        if not isinstance(human, list):
            raise AvatarError(f"{source}: VRM extension has no humanoid.humanBones list")
        bones = {}
        for item in human:
            if isinstance(item, dict) and isinstance(item.get("bone"), str):
                name = _vrm0_name(item["bone"])
                if name in HUMAN_BONES and item.get("node") != -1:  # -1: some exporters' "none"
                    bones[name] = node(item.get("node"), item["bone"], "VRM humanoid")
        return Humanoid(bones, "VRM 0.x")
    return None


def _rig_names() -> dict[str, dict[str, tuple[str, ...]]]:
    """Per convention: humanoid bone -> the node names (lower case, prefix removed) it may have."""
    mixamo: dict[str, tuple[str, ...]] = {
        "hips": ("hips",),
        "spine": ("spine",),
        "chest": ("spine1",),
        "upperChest": ("spine2",),
        "neck": ("neck",),
        "head": ("head",),
    }
    blender: dict[str, tuple[str, ...]] = {
        "hips": ("hips", "pelvis", "spine"), "spine": ("spine.001",), "chest": ("spine.002",),
        "upperChest": ("spine.003",), "neck": ("spine.004", "neck"),
        "head": ("spine.006", "spine.005", "head"),
    }  # fmt: skip
    unreal: dict[str, tuple[str, ...]] = {
        "hips": ("pelvis",),
        "spine": ("spine_01",),
        "chest": ("spine_02",),
        "upperChest": ("spine_03",),
        "neck": ("neck_01",),
        "head": ("head",),
    }
    mixamo_limb = dict(
        zip(
            _LIMBS,
            ("Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase"),
            strict=True,
        )
    )
    blender_limb = dict(
        zip(
            _LIMBS,
            ("shoulder", "upper_arm", "forearm", "hand", "thigh", "shin", "foot", "toe"),
            strict=True,
        )
    )
    unreal_limb = dict(
        zip(
            _LIMBS,
            ("clavicle", "upperarm", "lowerarm", "hand", "thigh", "calf", "foot", "ball"),
            strict=True,
        )
    )
    mixamo_finger = dict(zip(FINGERS, ("Thumb", "Index", "Middle", "Ring", "Pinky"), strict=True))
    blender_finger = dict(
        zip(FINGERS, ("thumb", "f_index", "f_middle", "f_ring", "f_pinky"), strict=True)
    )
    unreal_finger = dict(zip(FINGERS, ("thumb", "index", "middle", "ring", "pinky"), strict=True))
    for side in SIDES:
        cap, s = side.capitalize(), side[0]
        for limb in _LIMBS:
            mixamo[f"{side}{limb}"] = (f"{cap}{mixamo_limb[limb]}".lower(),)
            blender[f"{side}{limb}"] = (f"{blender_limb[limb]}.{s}",)
            unreal[f"{side}{limb}"] = (f"{unreal_limb[limb]}_{s}",)
        for f in FINGERS:
            parts = _THUMB if f == "Thumb" else _FINGER
            for k, part in enumerate(parts, start=1):
                mixamo[f"{side}{f}{part}"] = (f"{cap}Hand{mixamo_finger[f]}{k}".lower(),)
                blender[f"{side}{f}{part}"] = (f"{blender_finger[f]}.0{k}.{s}",)
                unreal[f"{side}{f}{part}"] = (f"{unreal_finger[f]}_0{k}_{s}",)
    return {"Mixamo": mixamo, "Blender/Rigify": blender, "Unreal": unreal}


_RIGS = _rig_names()
_PREFIX = {
    "Mixamo": re.compile(r"^mixamorig\d*[:_]?"),
    "Blender/Rigify": re.compile(r"^(armature[|:])?(def-)?"),
    "Unreal": re.compile(r"^(root[|:])?"),
}


def from_names(scene: GltfScene) -> Humanoid | None:
    best: Humanoid | None = None
    for convention, table in _RIGS.items():
        prefix = _PREFIX[convention]
        names: dict[str, int] = {}
        for i, node in enumerate(scene.nodes):
            raw = node.name.lower()
            key = prefix.sub("", raw)
            if convention == "Mixamo" and key == raw:
                continue  # Mixamo names always carry the prefix
            deform = raw != key and "def-" in raw  # Rigify: the deform bone wins over ORG/plain
            if key not in names or deform:
                names[key] = i
        bones: dict[str, int] = {}
        for bone, candidates in table.items():
            for c in candidates:
                if c in names:
                    bones[bone] = names[c]
                    break
        found = Humanoid(bones, convention)
        if best is None or len(found.missing()) < len(best.missing()):
            best = found
    if best is None or len(best.bones) < 3:
        return None
    return best


def load_bone_map(path: Path, scene: GltfScene) -> Humanoid:
    """A user's bone map file, each name checked against ``scene``'s nodes."""
    raw = read_toml(path, BoneMapError)
    top = Table(raw, str(path), "", BoneMapError)
    bones_t = top.table("bones")
    top.done()
    bones: dict[str, int] = {}
    for bone in HUMAN_BONES:
        name = bones_t.text(bone, None)
        if name is None:
            continue
        index = scene.node_named(name)
        if index is None:
            raise bones_t.fail(bone, f"no node of that name in {scene.source}", name)
        bones[bone] = index
    bones_t.done()
    return Humanoid(bones, f"bone map {path}")


def sidecar(avatar_path: Path) -> Path:
    """Where a bone map for ``avatar_path`` is looked for when none is given."""
    return avatar_path.with_name(f"{avatar_path.stem}.bones.toml")


def find_humanoid(scene: GltfScene, bone_map: Path | None = None) -> Humanoid:
    """The file's humanoid map (see the module docstring for the order); every required
    bone present, else :class:`AvatarError` naming the missing ones."""
    human: Humanoid | None = None
    if bone_map is not None:
        human = load_bone_map(bone_map, scene)
    if human is None:
        human = from_vrm(scene.extensions, len(scene.nodes), scene.source)
    if human is None:
        human = from_names(scene)
    if human is None:
        raise AvatarError(
            f"{scene.source}: no humanoid: not a VRM file and no node names of a "
            "known rig (Mixamo, Blender/Rigify, Unreal); give a bone map "
            "(NAME.bones.toml)"
        )
    missing = human.missing()
    if missing:
        raise AvatarError(
            f"{scene.source}: required bone(s) missing ({human.convention}): {', '.join(missing)}"
        )
    return human
