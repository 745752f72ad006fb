"""The performance as a glTF 2.0 binary (``.glb``): the avatar skinned to the body's joints, the
sticks, and the motion as a glTF animation that Blender and three.js play.

Why this shape. The body's 24 joints become 24 glTF nodes in the body's hierarchy, each with
its rest offset as translation; the motion is one LINEAR rotation channel per joint that has
a rotation (leaves are points) and one translation channel for the pelvis, all on one time
input in seconds, so a player needs nothing of ours. The avatar is exported *as we bind it*:
its vertices in its bind pose and ``inverseBindMatrices = inverse(bind)``, so glTF's
``world(joint) @ inverseBindMatrix`` is exactly our skinning (:mod:`~livedrummer.avatar.skinning`).
Everything is written in the kit frame under one root node whose rotation turns it into
glTF's (+Y up, the drummer facing +Z), rather than converting every array. Each stick is a
thin box on its grip joint, from its tail behind the hand to the tip.

The kit is the renderer's own (:class:`~livedrummer.render.kitmesh.KitMesh`): every instance
of a unit mesh is a node with its placement matrix; an instance that moves (a cymbal's swing,
the hi-hat's lift, the kick beater) hangs under a node animated with the rotation and
translation that :meth:`KitMesh.instances` gives it frame by frame, so the file's cymbals move
exactly as the video's.

Limits: the hit highlight and the stage floor are not written; kit colours are plain
metallic-roughness factors; textures are re-encoded as PNG (zlib); one animation, sampled at
the times given (no key reduction).
"""

from __future__ import annotations

import struct
import zlib
from typing import Any

import numpy as np

from livedrummer.avatar.model import Avatar, Material
from livedrummer.body.skeleton import JOINTS, LEAVES, N_JOINTS, PARENTS, J, Skeleton
from livedrummer.render.kitmesh import MOTION_STATIC, KitMesh

#: kit frame (+x right, +y forward, +z up) -> glTF (+Y up, front +Z: the drummer's right is -X)
KIT_TO_GLTF = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
STICK_TAIL_M = 0.11
STICK_RADIUS_M = 0.007
_FLOAT, _USHORT, _UINT = 5126, 5123, 5125
_ARRAY, _ELEMENTS = 34962, 34963


def _png(rgba: np.ndarray) -> bytes:
    h, w, _ = rgba.shape
    rows = np.concatenate([np.zeros((h, 1), np.uint8), rgba.reshape(h, w * 4)], axis=1)

    def chunk(kind: bytes, data: bytes) -> bytes:
        crc = zlib.crc32(kind + data) & 0xFFFFFFFF
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)

    head = struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", head)
        + chunk(b"IDAT", zlib.compress(rows.tobytes(), 6))
        + chunk(b"IEND", b"")
    )


def _xyzw(q_wxyz: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(q_wxyz)[..., [1, 2, 3, 0]], np.float32)


def _quat_of(m: np.ndarray) -> list[float]:
    from livedrummer.body import quat

    return [float(v) for v in _xyzw(quat.from_matrix(m))]


class _Doc:
    def __init__(self) -> None:
        import pygltflib

        self.lib = pygltflib
        self.g = pygltflib.GLTF2(asset=pygltflib.Asset(version="2.0", generator="livedrummer"))
        self.blob = bytearray()

    def view(self, data: bytes, target: int | None = None) -> int:
        self.blob.extend(b"\x00" * (-len(self.blob) % 4))
        bv = self.lib.BufferView(
            buffer=0, byteOffset=len(self.blob), byteLength=len(data), target=target
        )
        self.g.bufferViews.append(bv)
        self.blob.extend(data)
        return len(self.g.bufferViews) - 1

    def accessor(
        self,
        arr: np.ndarray,
        kind: str,
        component: int,
        target: int | None = None,
        bounds: bool = False,
    ) -> int:
        view = self.view(np.ascontiguousarray(arr).tobytes(), target)
        acc = self.lib.Accessor(
            bufferView=view, componentType=component, count=int(arr.shape[0]), type=kind
        )
        if bounds:
            flat = arr.reshape(arr.shape[0], -1)
            acc.min = [float(v) for v in flat.min(axis=0)]
            acc.max = [float(v) for v in flat.max(axis=0)]
        self.g.accessors.append(acc)
        return len(self.g.accessors) - 1

    def node(self, **kwargs: Any) -> int:
        self.g.nodes.append(self.lib.Node(**kwargs))
        return len(self.g.nodes) - 1

    def material(self, m: Material) -> int:
        lib = self.lib
        pbr = lib.PbrMetallicRoughness(
            baseColorFactor=[float(c) for c in m.base_color],
            metallicFactor=0.0,
            roughnessFactor=float(m.roughness),
        )
        if m.texture is not None:
            image = self.view(_png(np.ascontiguousarray(m.texture, np.uint8)))
            self.g.images.append(lib.Image(bufferView=image, mimeType="image/png", name=m.name))
            self.g.textures.append(lib.Texture(source=len(self.g.images) - 1))
            pbr.baseColorTexture = lib.TextureInfo(index=len(self.g.textures) - 1)
        mat = lib.Material(
            name=m.name,
            pbrMetallicRoughness=pbr,
            alphaMode=m.alpha_mode,
            doubleSided=m.double_sided,
        )
        if m.alpha_mode == "MASK":
            mat.alphaCutoff = float(m.alpha_cutoff)
        if m.shading == "toon":
            mat.extensions = {"KHR_materials_unlit": {}}
        self.g.materials.append(mat)
        return len(self.g.materials) - 1


def _box(length_from: float, length_to: float, r: float) -> tuple[np.ndarray, np.ndarray]:
    """A box along local z from ``length_from`` to ``length_to``, ``2r`` across."""
    corners = np.array(
        [[x, y, z] for z in (length_from, length_to) for x in (-r, r) for y in (-r, r)], np.float32
    )
    faces = np.array(
        [
            0,
            1,
            3,
            0,
            3,
            2,
            4,
            6,
            7,
            4,
            7,
            5,
            0,
            4,
            5,
            0,
            5,
            1,
            2,
            3,
            7,
            2,
            7,
            6,
            0,
            2,
            6,
            0,
            6,
            4,
            1,
            5,
            7,
            1,
            7,
            3,
        ],
        np.uint32,
    )
    return corners, faces


def _matrix(m: np.ndarray) -> list[float]:
    return [float(v) for v in np.asarray(m, np.float64).T.reshape(16)]


def _kit(
    d: _Doc, kit: KitMesh, channels: np.ndarray, clock: int
) -> tuple[list[int], list[Any], list[Any]]:
    """Nodes of the kit's instances, and the animation samplers/channels of those that move."""
    from livedrummer.body import quat
    from livedrummer.render.geometry import all_meshes

    lib, g = d.lib, d.g
    units = all_meshes()
    meshes: dict[tuple[str, tuple[float, float, float, float]], int] = {}
    nodes: list[int] = []
    samplers: list[Any] = []
    anim: list[Any] = []
    rest_inv = np.linalg.inv(kit.model)
    moves_at = set(np.flatnonzero(kit.motion != MOTION_STATIC).tolist())
    frames = np.stack([kit.instances(c)[:, :16] for c in channels])  # (T, N, 16)
    world = frames.reshape(len(channels), -1, 4, 4).transpose(0, 1, 3, 2).astype(np.float64)
    for i, name in enumerate(kit.mesh.tolist()):
        r, gr, b = (float(c) for c in kit.color[i])
        colour = (r, gr, b, 1.0)
        key = (name, colour)
        if key not in meshes:
            unit = units[name]
            v = np.ascontiguousarray(unit.vertices, np.float32)
            attrs = lib.Attributes(
                POSITION=d.accessor(v[:, :3], "VEC3", _FLOAT, _ARRAY, True),
                NORMAL=d.accessor(v[:, 3:6], "VEC3", _FLOAT, _ARRAY),
            )
            metal = float(kit.material[i, 0])
            mat = d.material(Material(f"kit {name}", colour, roughness=1.0 - 0.6 * metal))
            index = d.accessor(np.asarray(unit.indices, np.uint32), "SCALAR", _UINT, _ELEMENTS)
            g.meshes.append(
                lib.Mesh(
                    name=f"kit {name}",
                    primitives=[lib.Primitive(attributes=attrs, material=mat, indices=index)],
                )
            )
            meshes[key] = len(g.meshes) - 1
        placed = d.node(name=f"kit {i} {name}", mesh=meshes[key], matrix=_matrix(kit.model[i]))
        if i not in moves_at:
            nodes.append(placed)
            continue
        motion = world[:, i] @ rest_inv[i]  # (T, 4, 4): what the channels do to it
        rot = _xyzw(quat.from_matrix(motion[:, :3, :3]))
        mover = d.node(name=f"kit {i} motion", children=[placed])
        nodes.append(mover)
        shift = motion[:, :3, 3].astype(np.float32)
        for path, values, kind in (("rotation", rot, "VEC4"), ("translation", shift, "VEC3")):
            out = d.accessor(np.ascontiguousarray(values), kind, _FLOAT)
            samplers.append(lib.AnimationSampler(input=clock, output=out, interpolation="LINEAR"))
            anim.append((mover, path, len(samplers) - 1))
    return nodes, samplers, anim


def performance_glb(
    avatar: Avatar,
    skeleton: Skeleton,
    times: np.ndarray,
    local_q: np.ndarray,
    root_m: np.ndarray,
    kit: KitMesh | None = None,
    kit_channels: np.ndarray | None = None,
) -> bytes:
    """GLB bytes of ``avatar`` playing ``local_q`` (T, 24, 4; w x y z) and ``root_m`` (T, 3) at
    ``times`` (T,) seconds, on the skeleton the motion was made for; with ``kit`` and its
    scene channels ``kit_channels`` (T, P, 4), the kit too."""
    times = np.asarray(times, np.float32)
    if times.ndim != 1 or times.size == 0 or local_q.shape != (times.size, N_JOINTS, 4):
        raise ValueError(f"times {times.shape} and rotations {local_q.shape} do not match")
    d = _Doc()
    lib, g = d.lib, d.g
    root = d.node(name="livedrummer", rotation=_quat_of(KIT_TO_GLTF))
    first = len(g.nodes)
    for j, name in enumerate(JOINTS):
        t = skeleton.root_m if j == 0 else skeleton.offsets[j]
        d.node(name=name, translation=[float(v) for v in t])
    joint_node = [first + j for j in range(N_JOINTS)]
    for j in range(1, N_JOINTS):
        parent = g.nodes[joint_node[PARENTS[j]]]
        parent.children = [*(parent.children or []), joint_node[j]]
    mesh = avatar.mesh
    ibm = np.linalg.inv(mesh.bind.astype(np.float64)).transpose(0, 2, 1).astype(np.float32)
    g.skins.append(
        lib.Skin(
            joints=joint_node,
            skeleton=joint_node[0],
            inverseBindMatrices=d.accessor(ibm.reshape(N_JOINTS, 16), "MAT4", _FLOAT),
        )
    )
    mats = [d.material(m) for m in mesh.materials]
    attrs = lib.Attributes(
        POSITION=d.accessor(mesh.positions, "VEC3", _FLOAT, _ARRAY, bounds=True),
        NORMAL=d.accessor(mesh.normals, "VEC3", _FLOAT, _ARRAY),
        TEXCOORD_0=d.accessor(mesh.uv, "VEC2", _FLOAT, _ARRAY),
        JOINTS_0=d.accessor(
            np.where(mesh.weights > 0, mesh.joints, 0).astype(np.uint16), "VEC4", _USHORT, _ARRAY
        ),  # an unused influence names joint 0
        WEIGHTS_0=d.accessor(mesh.weights, "VEC4", _FLOAT, _ARRAY),
    )
    prims = []
    for p in mesh.primitives:
        if p.count:
            index = d.accessor(
                mesh.indices[p.first : p.first + p.count], "SCALAR", _UINT, _ELEMENTS
            )
            prims.append(lib.Primitive(attributes=attrs, material=mats[p.material], indices=index))
    g.meshes.append(lib.Mesh(name=avatar.name, primitives=prims))
    body = d.node(name=f"avatar {avatar.name}", mesh=len(g.meshes) - 1, skin=0)
    wood = d.material(Material("stick", (0.85, 0.70, 0.45, 1.0)))
    corners, faces = _box(STICK_TAIL_M, -skeleton.lengths.stick, STICK_RADIUS_M)
    stick_attrs = lib.Attributes(POSITION=d.accessor(corners, "VEC3", _FLOAT, _ARRAY, bounds=True))
    g.meshes.append(
        lib.Mesh(
            name="stick",
            primitives=[
                lib.Primitive(
                    attributes=stick_attrs,
                    material=wood,
                    indices=d.accessor(faces, "SCALAR", _UINT, _ELEMENTS),
                )
            ],
        )
    )
    for side in ("r", "l"):
        grip = g.nodes[joint_node[J[f"{side}_stick"]]]
        stick = d.node(name=f"{side}_stick_geo", mesh=len(g.meshes) - 1)
        grip.children = [*(grip.children or []), stick]
    g.nodes[root].children = [joint_node[0]]
    g.scenes = [lib.Scene(nodes=[root, body])]  # a skinned mesh's own node is not transformed
    g.scene = 0
    # the motion: one time input, a rotation channel per joint with one, the pelvis' position
    clock = d.accessor(times[:, None], "SCALAR", _FLOAT, bounds=True)
    samplers: list[Any] = []
    anim_channels: list[Any] = []
    if kit is not None and kit_channels is not None:
        kit_nodes, samplers, moves = _kit(d, kit, kit_channels, clock)
        g.nodes[root].children = [*g.nodes[root].children, *kit_nodes]
        for node, path, sampler in moves:
            target = lib.AnimationChannelTarget(node=node, path=path)
            anim_channels.append(lib.AnimationChannel(sampler=sampler, target=target))
    for j in range(N_JOINTS):
        if j in LEAVES:
            continue
        out = d.accessor(_xyzw(local_q[:, j]), "VEC4", _FLOAT)
        samplers.append(lib.AnimationSampler(input=clock, output=out, interpolation="LINEAR"))
        target = lib.AnimationChannelTarget(node=joint_node[j], path="rotation")
        anim_channels.append(lib.AnimationChannel(sampler=len(samplers) - 1, target=target))
    out = d.accessor(np.asarray(root_m, np.float32), "VEC3", _FLOAT)
    samplers.append(lib.AnimationSampler(input=clock, output=out, interpolation="LINEAR"))
    target = lib.AnimationChannelTarget(node=joint_node[0], path="translation")
    anim_channels.append(lib.AnimationChannel(sampler=len(samplers) - 1, target=target))
    g.animations.append(
        lib.Animation(name="performance", samplers=samplers, channels=anim_channels)
    )
    if any(m.shading == "toon" for m in mesh.materials):
        g.extensionsUsed = ["KHR_materials_unlit"]
    g.buffers = [lib.Buffer(byteLength=len(d.blob))]
    g.set_binary_blob(bytes(d.blob))
    data: bytes = b"".join(g.save_to_bytes())
    return data
