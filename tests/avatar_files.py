"""Avatar files made for the tests (no downloads): box-limbed humanoids written with pygltflib.

Each is built in glTF's frame (+Y up) from one table of humanoid bone positions for a 1.75 m
person standing in T-pose and facing +Z (the character's left at +X), then scaled to the height
asked for, its arms lowered for an A-pose, and turned 180 degrees about +Y to face -Z (as VRM
0.x files do). The mesh is a box per bone (head to child head), weighted fully to that bone,
plus a head box with a nose on the face's side, so a test can tell which way the avatar
faces; a hair bone under the head that no humanoid map names; a hand with a middle finger and
a thumb (curled by the loader). ``rigid=True`` attaches each box to its bone node as a plain
mesh (no skin). The head is a second skinned mesh with two primitives (skin and hair
materials); one material has a 4x4 PNG base-colour texture.
"""

from __future__ import annotations

import json
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pygltflib

#: bone -> (parent, head position of the 1.75 m T-pose facing +Z; x = the character's left)
BONES: dict[str, tuple[str | None, tuple[float, float, float]]] = {
    "hips": (None, (0.0, 0.95, 0.0)),
    "spine": ("hips", (0.0, 1.06, 0.0)),
    "chest": ("spine", (0.0, 1.20, 0.0)),
    "neck": ("chest", (0.0, 1.45, -0.01)),
    "head": ("neck", (0.0, 1.56, 0.0)),
    "hair": ("head", (0.0, 1.70, -0.05)),
}
for _side, _sx in (("left", 1.0), ("right", -1.0)):
    BONES.update(
        {
            f"{_side}Shoulder": ("chest", (_sx * 0.04, 1.40, 0.0)),
            f"{_side}UpperArm": (f"{_side}Shoulder", (_sx * 0.18, 1.40, 0.0)),
            f"{_side}LowerArm": (f"{_side}UpperArm", (_sx * 0.47, 1.40, 0.0)),
            f"{_side}Hand": (f"{_side}LowerArm", (_sx * 0.73, 1.40, 0.0)),
            f"{_side}MiddleProximal": (f"{_side}Hand", (_sx * 0.82, 1.40, 0.0)),
            f"{_side}MiddleIntermediate": (f"{_side}MiddleProximal", (_sx * 0.865, 1.40, 0.0)),
            f"{_side}MiddleDistal": (f"{_side}MiddleIntermediate", (_sx * 0.89, 1.40, 0.0)),
            f"{_side}ThumbMetacarpal": (f"{_side}Hand", (_sx * 0.75, 1.39, 0.03)),
            f"{_side}ThumbProximal": (f"{_side}ThumbMetacarpal", (_sx * 0.78, 1.39, 0.06)),
            f"{_side}ThumbDistal": (f"{_side}ThumbProximal", (_sx * 0.80, 1.39, 0.08)),
            f"{_side}UpperLeg": ("hips", (_sx * 0.09, 0.90, 0.0)),
            f"{_side}LowerLeg": (f"{_side}UpperLeg", (_sx * 0.09, 0.50, 0.01)),
            f"{_side}Foot": (f"{_side}LowerLeg", (_sx * 0.09, 0.08, 0.0)),
            f"{_side}Toes": (f"{_side}Foot", (_sx * 0.09, 0.02, 0.14)),
        }
    )

#: leaf ends of the boxes (a bone with no child in BONES)
ENDS = {"head": (0.0, 1.75, 0.0), "hair": (0.0, 1.70, -0.12)}
for _side, _sx in (("left", 1.0), ("right", -1.0)):
    ENDS[f"{_side}MiddleDistal"] = (_sx * 0.91, 1.40, 0.0)
    ENDS[f"{_side}ThumbDistal"] = (_sx * 0.81, 1.39, 0.095)
    ENDS[f"{_side}Toes"] = (_sx * 0.09, 0.02, 0.20)
THICK = {"hips": 0.16, "spine": 0.15, "chest": 0.17, "neck": 0.05, "head": 0.10, "hair": 0.05}
HEIGHT_M = 1.75

#: Mixamo, Blender/Rigify and Unreal names of the humanoid bones used here.
_MIXAMO_LIMB = {"Shoulder": "Shoulder", "UpperArm": "Arm", "LowerArm": "ForeArm",
                "Hand": "Hand", "UpperLeg": "UpLeg", "LowerLeg": "Leg", "Foot": "Foot",
                "Toes": "ToeBase", "MiddleProximal": "HandMiddle1",
                "MiddleIntermediate": "HandMiddle2", "MiddleDistal": "HandMiddle3",
                "ThumbMetacarpal": "HandThumb1", "ThumbProximal": "HandThumb2",
                "ThumbDistal": "HandThumb3"}  # fmt: skip
_BLENDER_LIMB = {"Shoulder": "shoulder", "UpperArm": "upper_arm", "LowerArm": "forearm",
                 "Hand": "hand", "UpperLeg": "thigh", "LowerLeg": "shin", "Foot": "foot",
                 "Toes": "toe", "MiddleProximal": "f_middle.01", "MiddleIntermediate":
                 "f_middle.02", "MiddleDistal": "f_middle.03", "ThumbMetacarpal": "thumb.01",
                 "ThumbProximal": "thumb.02", "ThumbDistal": "thumb.03"}  # fmt: skip
_UNREAL_LIMB = {"Shoulder": "clavicle", "UpperArm": "upperarm", "LowerArm": "lowerarm",
                "Hand": "hand", "UpperLeg": "thigh", "LowerLeg": "calf", "Foot": "foot",
                "Toes": "ball", "MiddleProximal": "middle_01", "MiddleIntermediate":
                "middle_02", "MiddleDistal": "middle_03", "ThumbMetacarpal": "thumb_01",
                "ThumbProximal": "thumb_02", "ThumbDistal": "thumb_03"}  # fmt: skip
_TORSO_NAMES = {
    "mixamo": {"hips": "Hips", "spine": "Spine", "chest": "Spine1", "neck": "Neck", "head": "Head"},
    "blender": {
        "hips": "spine",
        "spine": "spine.001",
        "chest": "spine.002",
        "neck": "spine.004",
        "head": "spine.006",
    },
    "unreal": {
        "hips": "pelvis",
        "spine": "spine_01",
        "chest": "spine_02",
        "neck": "neck_01",
        "head": "head",
    },
}


def node_name(bone: str, naming: str) -> str:
    """The node name ``bone`` has in a file of ``naming`` (vrm/mixamo/blender/unreal)."""
    if bone == "hair":
        return "Hair_01"
    if naming == "vrm":
        return f"J_{bone}"
    if bone in _TORSO_NAMES[naming]:
        name = _TORSO_NAMES[naming][bone]
    else:
        side = "left" if bone.startswith("left") else "right"
        limb = bone[len(side) :]
        if naming == "mixamo":
            name = f"{side.capitalize()}{_MIXAMO_LIMB[limb]}"
        elif naming == "blender":
            name = f"{_BLENDER_LIMB[limb]}.{side[0].upper()}"
        else:
            name = f"{_UNREAL_LIMB[limb]}_{side[0]}"
    if naming == "mixamo":
        return f"mixamorig:{name}"
    if naming == "blender":
        return f"DEF-{name}"
    return name


def png_rgba(pixels: np.ndarray) -> bytes:
    """A PNG file of RGBA8 ``pixels`` (H, W, 4)."""
    h, w, _ = pixels.shape
    raw = b"".join(b"\x00" + pixels[r].astype(np.uint8).tobytes() for r in range(h))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data))
            + kind
            + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
        )

    ihdr = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(b"IDAT", zlib.compress(raw))
        + chunk(b"IEND", b"")
    )


TEXTURE = np.zeros((4, 4, 4), np.uint8)
TEXTURE[..., 0] = 200
TEXTURE[..., 3] = 255
TEXTURE[0, 0] = (10, 20, 30, 255)  # row 0 at the top, as decoded


@dataclass
class Spec:
    """What to write."""

    height_m: float = HEIGHT_M
    pose: str = "T"  # T or A
    facing: str = "+z"  # +z or -z
    naming: str = "vrm"  # vrm, mixamo, blender, unreal
    vrm: str | None = None  # None, "0" or "1": which VRM extension to write
    rigid: bool = False
    unit: float = 1.0  # 100.0 writes centimetres
    drop: tuple[str, ...] = ()  # humanoid bones left out of the VRM map
    faces: bool = False  # morph targets on the head and the VRM's expressions binding them
    extra: dict[str, Any] = field(default_factory=dict)


def positions(spec: Spec) -> dict[str, np.ndarray]:
    """World head positions of every bone (and ``END:bone`` leaf ends) as written."""
    k = spec.height_m / HEIGHT_M
    out = {b: np.array(p) * k for b, (_, p) in BONES.items()}
    out.update({f"END:{b}": np.array(p) * k for b, p in ENDS.items()})
    if spec.pose == "A":
        for side, sx in (("left", 1.0), ("right", -1.0)):
            pivot = out[f"{side}UpperArm"].copy()
            a = np.radians(-40.0) * sx  # rotate about +Z: the arm down
            rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
            for name in list(out):
                bare = name.removeprefix("END:")
                if bare.startswith(side) and _under(bare, f"{side}UpperArm"):
                    out[name] = pivot + rot @ (out[name] - pivot)
    if spec.facing == "-z":
        for name in out:
            out[name] = out[name] * np.array([-1.0, 1.0, -1.0])
    return {n: p * spec.unit for n, p in out.items()}


def _under(bone: str, ancestor: str) -> bool:
    while bone is not None:
        if bone == ancestor:
            return True
        bone = BONES[bone][0]  # type: ignore[assignment]
    return False


def _child(bone: str) -> str | None:
    """The bone a box of ``bone`` runs to (its main child)."""
    main = {"hips": "spine", "spine": "chest", "chest": "neck", "neck": "head"}
    if bone in main:
        return main[bone]
    side = "left" if bone.startswith("left") else "right"
    limb = bone[len(side) :]
    nxt = {
        "Shoulder": "UpperArm",
        "UpperArm": "LowerArm",
        "LowerArm": "Hand",
        "Hand": "MiddleProximal",
        "MiddleProximal": "MiddleIntermediate",
        "MiddleIntermediate": "MiddleDistal",
        "ThumbMetacarpal": "ThumbProximal",
        "ThumbProximal": "ThumbDistal",
        "UpperLeg": "LowerLeg",
        "LowerLeg": "Foot",
        "Foot": "Toes",
    }.get(limb)
    return f"{side}{nxt}" if nxt else None


def _box(a: np.ndarray, b: np.ndarray, thick: float) -> tuple[np.ndarray, np.ndarray]:
    """8 corners and 12 triangles of a box from ``a`` to ``b``, ``thick`` across."""
    d = b - a
    n = np.linalg.norm(d)
    d = d / n if n > 1e-9 else np.array([0.0, 1.0, 0.0])
    ref = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(d, ref)
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    h = thick / 2
    corners = [end + su * h * u + sv * h * v for end in (a, b) for su in (-1, 1) for sv in (-1, 1)]
    faces = [
        (0, 1, 3),
        (0, 3, 2),
        (4, 6, 7),
        (4, 7, 5),
        (0, 4, 5),
        (0, 5, 1),
        (2, 3, 7),
        (2, 7, 6),
        (0, 2, 6),
        (0, 6, 4),
        (1, 5, 7),
        (1, 7, 3),
    ]
    return np.array(corners), np.array(faces)


def _segments(
    spec: Spec, pos: dict[str, np.ndarray]
) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
    """(bone, from, to, thickness) of every box of the body (not the head mesh)."""
    k = spec.height_m / HEIGHT_M * spec.unit
    out = []
    for bone in BONES:
        if bone in ("head", "hair"):
            continue
        child = _child(bone)
        end = pos[child] if child is not None else pos.get(f"END:{bone}")
        if end is None:
            continue
        thick = THICK.get(
            bone,
            0.03
            if "Middle" in bone or "Thumb" in bone
            else 0.04
            if "Shoulder" in bone
            else 0.07
            if "Arm" in bone or "Hand" in bone
            else 0.04
            if "Foot" in bone or "Toes" in bone
            else 0.10,
        )
        out.append((bone, pos[bone], end, thick * k))
    return out


class _Writer:
    def __init__(self) -> None:
        self.blob = bytearray()
        self.g = pygltflib.GLTF2(asset=pygltflib.Asset(version="2.0", generator="tests"))

    def view(self, data: bytes, target: int | None = None) -> int:
        while len(self.blob) % 4:
            self.blob.append(0)
        self.g.bufferViews.append(
            pygltflib.BufferView(
                buffer=0, byteOffset=len(self.blob), byteLength=len(data), target=target
            )
        )
        self.blob.extend(data)
        return len(self.g.bufferViews) - 1

    def accessor(
        self,
        arr: np.ndarray,
        kind: str,
        component: int,
        target: int | None = None,
        minmax: bool = False,
    ) -> int:
        view = self.view(arr.tobytes(), target)
        acc = pygltflib.Accessor(
            bufferView=view, componentType=component, count=int(arr.shape[0]), type=kind
        )
        if minmax:
            acc.min = arr.min(axis=0).tolist()
            acc.max = arr.max(axis=0).tolist()
        self.g.accessors.append(acc)
        return len(self.g.accessors) - 1


def build(spec: Spec) -> bytes:
    """The GLB bytes of ``spec``."""
    pos = positions(spec)
    w = _Writer()
    g = w.g
    names = list(BONES)
    index = {b: i for i, b in enumerate(names)}
    for bone in names:
        parent = BONES[bone][0]
        local = pos[bone] - (pos[parent] if parent else 0.0)
        g.nodes.append(
            pygltflib.Node(name=node_name(bone, spec.naming), translation=[float(x) for x in local])
        )
    for bone in names:
        kids = [index[b] for b, (p, _) in BONES.items() if p == bone]
        if kids:
            g.nodes[index[bone]].children = kids
    texture_png = png_rgba(TEXTURE)
    img_view = w.view(texture_png)
    g.images.append(pygltflib.Image(bufferView=img_view, mimeType="image/png", name="cloth"))
    g.samplers.append(pygltflib.Sampler())
    g.textures.append(pygltflib.Texture(source=0, sampler=0))
    g.materials = [
        pygltflib.Material(
            name="cloth",
            pbrMetallicRoughness=pygltflib.PbrMetallicRoughness(
                baseColorFactor=[0.2, 0.3, 0.8, 1.0],
                baseColorTexture=pygltflib.TextureInfo(index=0),
            ),
        ),
        pygltflib.Material(
            name="skin",
            pbrMetallicRoughness=pygltflib.PbrMetallicRoughness(
                baseColorFactor=[0.9, 0.7, 0.6, 1.0]
            ),
        ),
        pygltflib.Material(
            name="hair",
            alphaMode="MASK",
            alphaCutoff=0.4,
            doubleSided=True,
            pbrMetallicRoughness=pygltflib.PbrMetallicRoughness(
                baseColorFactor=[0.1, 0.05, 0.0, 1.0]
            ),
        ),
    ]
    k = spec.height_m / HEIGHT_M * spec.unit
    forward = np.array([0.0, 0.0, 1.0 if spec.facing == "+z" else -1.0])
    head, top = pos["head"], pos["END:head"]
    nose_a = head + np.array([0, 0.05, 0]) * k + forward * 0.05 * k
    head_parts = [
        ("head", head, top, 0.18 * k, 1),
        ("head", nose_a, nose_a + forward * 0.05 * k, 0.03 * k, 1),
        ("hair", pos["hair"], pos["END:hair"], 0.05 * k, 2),
    ]
    body = [(b, a, e, t, 0) for b, a, e, t in _segments(spec, pos)]
    roots = [index["hips"]]
    if spec.rigid:
        for bone, a, e, t, mat in body + head_parts:
            corners, faces = _box(a, e, t)
            corners = corners - pos[bone]  # the node's frame (translations only)
            mesh = _mesh(w, [(corners, faces, np.full(8, 0), mat)], skinned=False)
            node = pygltflib.Node(name=f"{bone}_geo", mesh=mesh)
            g.nodes.append(node)
            parent = g.nodes[index[bone]]
            parent.children = [*(parent.children or []), len(g.nodes) - 1]
    else:
        skin_joints = list(range(len(names)))
        ibm = np.stack([np.linalg.inv(_translation(pos[b])).T for b in names]).astype(np.float32)
        ibm_acc = w.accessor(ibm.reshape(len(names), 16), "MAT4", 5126)
        g.skins.append(
            pygltflib.Skin(joints=skin_joints, inverseBindMatrices=ibm_acc, skeleton=index["hips"])
        )
        head_joints = [index["neck"], index["head"], index["hair"]]
        hibm = np.stack([np.linalg.inv(_translation(pos[names[j]])).T for j in head_joints])
        hibm_acc = w.accessor(hibm.astype(np.float32).reshape(3, 16), "MAT4", 5126)
        g.skins.append(pygltflib.Skin(joints=head_joints, inverseBindMatrices=hibm_acc))
        parts = [(*_box(a, e, t), np.full(8, index[bone]), mat) for bone, a, e, t, mat in body]
        g.nodes.append(pygltflib.Node(name="Body", mesh=_mesh(w, parts, skinned=True), skin=0))
        roots.append(len(g.nodes) - 1)
        local = {index["head"]: 1, index["hair"]: 2}
        hparts = [
            (*_box(a, e, t), np.full(8, local[index[bone]]), mat)
            for bone, a, e, t, mat in head_parts
        ]
        k_face = spec.height_m / HEIGHT_M * spec.unit
        targets = tuple(tuple(k_face * c for c in t) for t in FACE_TARGETS) if spec.faces else ()
        face_mesh = _mesh(w, hparts, skinned=True, targets=targets)  # type: ignore[arg-type]
        g.nodes.append(pygltflib.Node(name="Face", mesh=face_mesh, skin=1))
        roots.append(len(g.nodes) - 1)
        face_node = len(g.nodes) - 1
    g.scenes = [pygltflib.Scene(nodes=roots)]
    g.scene = 0
    ext: dict[str, Any] = {}
    human = [b for b in BONES if b != "hair" and b not in spec.drop]
    if spec.vrm == "0":

        def vrm0(bone: str) -> str:
            for side in ("left", "right"):
                for new, old in (
                    ("ThumbMetacarpal", "ThumbProximal"),
                    ("ThumbProximal", "ThumbIntermediate"),
                ):
                    if bone == f"{side}{new}":
                        return f"{side}{old}"
            return bone

        ext["VRM"] = {
            "specVersion": "0.0",
            "humanoid": {
                "humanBones": [
                    {"bone": vrm0(b), "node": index[b], "useDefaultValues": True} for b in human
                ]
            },
            "materialProperties": [{"name": "skin", "shader": "VRM/MToon"}],
        }
        if spec.faces:
            ext["VRM"]["blendShapeMaster"] = {
                "blendShapeGroups": [
                    {
                        "name": "Blink",
                        "presetName": "blink",
                        "binds": [{"mesh": face_mesh, "index": 0, "weight": 100}],
                    },
                    {
                        "name": "Joy",
                        "presetName": "joy",
                        "binds": [{"mesh": face_mesh, "index": 1, "weight": 50}],
                    },
                    {
                        "name": "O",
                        "presetName": "o",
                        "binds": [{"mesh": face_mesh, "index": 2, "weight": 100}],
                    },
                ]
            }
        g.extensionsUsed = ["VRM"]
    elif spec.vrm == "1":
        ext["VRMC_vrm"] = {
            "specVersion": "1.0",
            "humanoid": {"humanBones": {b: {"node": index[b]} for b in human}},
        }
        if spec.faces:
            ext["VRMC_vrm"]["expressions"] = {
                "preset": {
                    "blink": {"morphTargetBinds": [{"node": face_node, "index": 0, "weight": 1.0}]},
                    "happy": {"morphTargetBinds": [{"node": face_node, "index": 1, "weight": 0.5}]},
                    "surprised": {
                        "morphTargetBinds": [{"node": face_node, "index": 2, "weight": 1.0}]
                    },
                }
            }
        g.materials[1].extensions = {"VRMC_materials_mtoon": {"specVersion": "1.0"}}
        g.extensionsUsed = ["VRMC_vrm", "VRMC_materials_mtoon"]
    ext.update(spec.extra)
    if ext:
        g.extensions = ext
    g.buffers = [pygltflib.Buffer(byteLength=len(w.blob))]
    g.set_binary_blob(bytes(w.blob))
    out: bytes = b"".join(g.save_to_bytes())
    return out


def _translation(p: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = p
    return m


#: With ``Spec.faces``: the head's morph targets, one uniform move (glTF frame, metres at
#: 1.75 m) each: 0 shuts the eyes (down), 1 is a smile (towards the character's left), 2 opens
#: the mouth (forward, towards the face's side in a +z-facing file).
FACE_TARGETS = ((0.0, -0.01, 0.0), (0.02, 0.0, 0.0), (0.0, 0.0, 0.03))


def _mesh(
    w: _Writer,
    parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, int]],
    skinned: bool,
    targets: tuple[tuple[float, float, float], ...] = (),
) -> int:
    """One mesh, one primitive per material, from (corners, faces, joint per corner, material);
    ``targets``: morph targets moving every vertex of every primitive by one vector each."""
    prims = []
    by_mat: dict[int, list[tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}
    for corners, faces, joints, mat in parts:
        by_mat.setdefault(mat, []).append((corners, faces, joints))
    for mat, items in sorted(by_mat.items()):
        p = np.concatenate([c for c, _, _ in items]).astype(np.float32)
        offs = np.cumsum([0] + [len(c) for c, _, _ in items[:-1]])
        f = np.concatenate(
            [faces + o for (_, faces, _), o in zip(items, offs, strict=True)]
        ).astype(np.uint32)
        uv = np.tile(np.float32([[0, 0], [1, 0], [0, 1], [1, 1]]), (p.shape[0] // 4, 1))
        attrs = pygltflib.Attributes(
            POSITION=w.accessor(p, "VEC3", 5126, 34962, minmax=True),
            TEXCOORD_0=w.accessor(uv, "VEC2", 5126, 34962),
        )
        if skinned:
            j = np.zeros((p.shape[0], 4), np.uint16)
            j[:, 0] = np.concatenate([jj for _, _, jj in items])
            wt = np.zeros((p.shape[0], 4), np.float32)
            wt[:, 0] = 1.0
            attrs.JOINTS_0 = w.accessor(j, "VEC4", 5123, 34962)
            attrs.WEIGHTS_0 = w.accessor(wt, "VEC4", 5126, 34962)
        morphs = [
            pygltflib.Attributes(
                POSITION=w.accessor(
                    np.tile(np.float32(t), (p.shape[0], 1)), "VEC3", 5126, 34962, minmax=True
                )
            )
            for t in targets
        ]
        prims.append(
            pygltflib.Primitive(
                attributes=attrs,
                material=mat,
                indices=w.accessor(f.reshape(-1, 1), "SCALAR", 5125, 34963),
                targets=morphs or None,
            )
        )
    w.g.meshes.append(pygltflib.Mesh(primitives=prims))
    return len(w.g.meshes) - 1


#: The avatars of the tests, by file name.
AVATARS: dict[str, Spec] = {
    "short.glb": Spec(height_m=1.55, naming="blender"),
    "tall.glb": Spec(height_m=1.95, naming="unreal"),
    "vrm0.vrm": Spec(height_m=1.70, pose="A", facing="-z", vrm="0"),
    "vrm1.vrm": Spec(height_m=1.80, pose="A", facing="+z", vrm="1"),
    "rigid.glb": Spec(height_m=1.75, naming="blender", rigid=True),
    "mixamo.glb": Spec(height_m=1.72, naming="mixamo", unit=100.0),
}


def write(folder: Path, name: str, spec: Spec | None = None) -> Path:
    path = folder / name
    path.write_bytes(build(spec or AVATARS[name]))
    return path


def write_all(folder: Path) -> dict[str, Path]:
    return {name: write(folder, name) for name in AVATARS}


def glb_json(data: bytes) -> dict[str, Any]:
    """The JSON chunk of GLB bytes (for tests that break a file)."""
    length = struct.unpack_from("<I", data, 12)[0]
    out: dict[str, Any] = json.loads(data[20 : 20 + length])
    return out


def glb_with_json(data: bytes, doc: dict[str, Any]) -> bytes:
    """GLB bytes with the JSON chunk replaced (the binary chunk kept)."""
    length = struct.unpack_from("<I", data, 12)[0]
    rest = data[20 + length :]
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<I", len(text)) + b"JSON" + text + rest
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body
