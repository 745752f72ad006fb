"""Reading glTF 2.0 (``.glb``/``.gltf``) and VRM files into arrays: nodes, one mesh, materials.

Why this shape. A glTF file is a scene graph with skins, several meshes and primitives, and
materials pointing at images; an avatar for us is *one* mesh in its bind pose with, per vertex,
a few avatar bones (node indices) and weights. This module does the glTF half of that and
nothing else: it resolves every node's world matrix, reads every triangle primitive of every
mesh node in the default scene, and puts the vertices where the file *displays* them (skinned
vertices through ``world(joint) @ inverseBindMatrix``, as a glTF viewer would; rigid meshes
through their node's world matrix, weighted fully to that node). It stays in glTF's own frame
(+Y up, any facing, any scale): turning the avatar into the kit frame needs its humanoid bones,
which :mod:`~livedrummer.avatar.retarget` does once, with :mod:`~livedrummer.avatar.bonemap`.

The JSON and the GLB container are parsed by pygltflib (a maintained, pure-Python, typed
dataclass model of the glTF 2.0 schema, which keeps unknown extensions such as ``VRM`` and
``VRMC_vrm`` as plain dicts); accessors, buffers and images are read here with numpy, so every
out-of-range offset, missing buffer or undecodable image is an :class:`AvatarError` naming the
file and the object, never an IndexError. Images (PNG, JPEG) are decoded with PyAV, already a
dependency for video, so no imaging library is added.

Limits: triangles, triangle strips and fans only (points and lines are skipped); one UV set
(``TEXCOORD_0``); sparse accessors are applied; morph targets are read as position deltas
(as displayed, for the face: :mod:`~livedrummer.avatar.faces`), their normals ignored;
animations, cameras and lights are ignored; KTX2/Basis textures are not decoded (the
material keeps its colour factor); Draco- or meshopt-compressed files are refused by name.
"""

from __future__ import annotations

import base64
import io
import logging
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from livedrummer.avatar.model import AlphaMode, AvatarError, Material, Primitive, Shading

log = logging.getLogger(__name__)

_COMPONENTS: dict[int, type[np.generic]] = {
    5120: np.int8,
    5121: np.uint8,
    5122: np.int16,
    5123: np.uint16,
    5125: np.uint32,
    5126: np.float32,
}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_GLB_MAGIC = b"glTF"
MTOON = ("VRMC_materials_mtoon",)
#: Required extensions whose buffers cannot be read as plain accessors.
COMPRESSED = frozenset(
    {"KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression"}
)


@dataclass(frozen=True)
class Node:
    """One node of the default scene: its name, parent index (-1 at a root) and world matrix."""

    name: str
    parent: int
    world: np.ndarray  # float64 (4, 4), column vectors, glTF frame


@dataclass(frozen=True)
class GltfScene:
    """What an avatar needs from a glTF file, in glTF's frame (see the module docstring)."""

    source: str
    nodes: tuple[Node, ...]
    positions: np.ndarray  # float64 (V, 3), as displayed
    normals: np.ndarray  # float64 (V, 3)
    uv: np.ndarray  # float32 (V, 2)
    bones: np.ndarray  # int64 (V, K): node indices
    weights: np.ndarray  # float64 (V, K), rows sum to 1
    indices: np.ndarray  # uint32 (3T,)
    primitives: tuple[Primitive, ...]
    materials: tuple[Material, ...]
    extensions: dict[str, Any] = field(default_factory=dict)  # the file's top-level ones
    textures: int = 0  # images decoded
    #: (node, morph target) -> (vertex indices, position deltas (M, 3) as displayed): the
    #: targets a VRM's expressions bind (see :mod:`~livedrummer.avatar.faces`)
    morphs: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    mesh_nodes: dict[int, tuple[int, ...]] = field(default_factory=dict)  # mesh -> its nodes

    def node_named(self, name: str) -> int | None:
        for i, node in enumerate(self.nodes):
            if node.name == name:
                return i
        return None

    def children(self) -> list[list[int]]:
        out: list[list[int]] = [[] for _ in self.nodes]
        for i, node in enumerate(self.nodes):
            if node.parent >= 0:
                out[node.parent].append(i)
        return out


def read_gltf_file(path: str | Path) -> GltfScene:
    """Open and parse ``path`` (``.glb``, ``.gltf`` or ``.vrm``); external buffers and images
    are looked up beside it."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise AvatarError(f"{p}: cannot read: {exc.strerror or exc}") from exc
    return parse_gltf(data, str(p), base_dir=p.parent)


def parse_gltf(data: bytes, source: str, base_dir: Path | None = None) -> GltfScene:
    """Parse a glTF file's bytes (GLB container or JSON text); ``source`` names it in errors."""
    return _Reader(data, source, base_dir).scene()


def _load(data: bytes, source: str) -> Any:
    import pygltflib

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            if data[:4] == _GLB_MAGIC:
                gltf = pygltflib.GLTF2.load_from_bytes(data)
            else:
                try:
                    text = data.decode("utf-8")
                except UnicodeDecodeError:
                    raise AvatarError(
                        f"{source}: not a glTF file (neither GLB nor JSON text)"
                    ) from None
                if not text.lstrip().startswith("{"):
                    raise AvatarError(f"{source}: not a glTF file (neither GLB nor JSON text)")
                gltf = pygltflib.GLTF2.from_json(text, infer_missing=True)
        except AvatarError:
            raise
        except Exception as exc:  # the library raises anything from struct.error to KeyError
            raise AvatarError(
                f"{source}: not a readable glTF file: {type(exc).__name__}: {exc}"
            ) from exc
    if gltf is None:
        raise AvatarError(f"{source}: GLB container without a JSON chunk")
    version = str(getattr(gltf.asset, "version", "") or "")
    if not version.startswith("2."):
        raise AvatarError(f"{source}: glTF version {version or '?'} (only 2.x is read)")
    unread = sorted(set(gltf.extensionsRequired or []) & COMPRESSED)
    if unread:
        raise AvatarError(
            f"{source}: compressed with {', '.join(unread)}, which is not read "
            "(export it uncompressed)"
        )
    return gltf


def _trs(node: Any) -> np.ndarray:
    m = np.eye(4)
    if node.matrix is not None and len(node.matrix) == 16:
        return np.asarray(node.matrix, np.float64).reshape(4, 4).T
    t = node.translation or (0.0, 0.0, 0.0)
    r = node.rotation or (0.0, 0.0, 0.0, 1.0)
    s = node.scale or (1.0, 1.0, 1.0)
    x, y, z, w = (float(v) for v in r)
    n = np.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    rot = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    m[:3, :3] = rot * np.asarray(s, np.float64)[None, :]
    m[:3, 3] = t
    return m


def _or_local(world: np.ndarray | None, node: Any) -> np.ndarray:
    """A node outside the default scene keeps its own transform."""
    return _trs(node) if world is None else world


class _Reader:
    """One parse: the pygltflib document, its buffers and decoded images, cached by index."""

    def __init__(self, data: bytes, source: str, base_dir: Path | None) -> None:
        self.source = source
        self.base_dir = base_dir
        self.gltf = _load(data, source)
        self._buffers: dict[int, bytes] = {}
        self._images: dict[int, np.ndarray | None] = {}

    def fail(self, what: str) -> AvatarError:
        return AvatarError(f"{self.source}: {what}")

    def _item(self, kind: str, index: Any) -> Any:
        items = getattr(self.gltf, kind) or []
        if not isinstance(index, int) or not 0 <= index < len(items):
            raise self.fail(f"{kind[:-1]} {index} does not exist ({len(items)} in the file)")
        return items[index]

    def _uri_bytes(self, uri: str, what: str) -> bytes:
        if uri.startswith("data:"):
            head, _, payload = uri.partition(",")
            if not head.endswith(";base64"):
                raise self.fail(f"{what}: data URI is not base64")
            try:
                return base64.b64decode(payload, validate=True)
            except ValueError as exc:
                raise self.fail(f"{what}: bad base64 data URI ({exc})") from exc
        if self.base_dir is None:
            raise self.fail(f"{what}: external file {uri!r} and no folder to look in")
        from urllib.parse import unquote

        path = self.base_dir / unquote(uri)
        try:
            return path.read_bytes()
        except OSError as exc:
            raise self.fail(f"{what}: cannot read {path}: {exc.strerror or exc}") from exc

    def buffer(self, index: int) -> bytes:
        if index in self._buffers:
            return self._buffers[index]
        buf = self._item("buffers", index)
        what = f"buffer {index}"
        if buf.uri is None:
            blob = self.gltf.binary_blob() if index == 0 else None
            if blob is None:
                raise self.fail(f"{what} has no data (no uri and no GLB binary chunk)")
            data = bytes(blob)
        else:
            data = self._uri_bytes(buf.uri, what)
        if buf.byteLength is not None and len(data) < buf.byteLength:
            raise self.fail(f"{what} is {len(data)} bytes, the file says {buf.byteLength}")
        self._buffers[index] = data
        return data

    def view_bytes(self, index: int, what: str) -> tuple[bytes, int, int, int | None]:
        """(buffer, start, length, stride) of buffer view ``index``, checked against its buffer."""
        bv = self._item("bufferViews", index)
        data = self.buffer(bv.buffer)
        start = int(bv.byteOffset or 0)
        length = int(bv.byteLength or 0)
        if start < 0 or length < 0 or start + length > len(data):
            raise self.fail(
                f"{what}: buffer view {index} ({start}+{length} bytes) runs past "
                f"buffer {bv.buffer} ({len(data)} bytes)"
            )
        return data, start, length, bv.byteStride

    def accessor(self, index: Any, what: str) -> np.ndarray:
        """Accessor ``index`` as an array (count, width) (MAT4: (count, 4, 4)), float for
        normalized integers, every offset checked."""
        acc = self._item("accessors", index)
        label = f"accessor {index} ({what})"
        dtype = _COMPONENTS.get(acc.componentType)
        width = _WIDTH.get(acc.type)
        if dtype is None or width is None:
            raise self.fail(
                f"{label}: component type {acc.componentType} / type {acc.type!r} is not glTF 2.0"
            )
        count = int(acc.count or 0)
        item = np.dtype(dtype).itemsize
        if acc.bufferView is None:
            out = np.zeros((count, width), dtype)
        else:
            data, start, length, stride = self.view_bytes(acc.bufferView, label)
            size = item * width
            step = int(stride or size)
            offset = int(acc.byteOffset or 0)
            end = offset + step * max(count - 1, 0) + size if count else offset
            if offset < 0 or step < size or end > length:
                raise self.fail(
                    f"{label}: {count} items of {size} bytes (stride {step}) from "
                    f"offset {offset} run past its buffer view of {length} "
                    "bytes"
                )
            out = np.ndarray(
                (count, width), dtype, buffer=data, offset=start + offset, strides=(step, item)
            ).copy()
        if acc.sparse is not None and acc.sparse.count:
            out = self._sparse(acc, out, label)
        result: np.ndarray = out
        if acc.normalized and dtype is not np.float32:
            top = float(np.iinfo(np.dtype(dtype)).max)
            result = np.maximum(out.astype(np.float64) / top, -1.0)
        if acc.type == "MAT4":
            result = result.reshape(count, 4, 4).transpose(0, 2, 1)
        return result

    def _sparse(self, acc: Any, out: np.ndarray, label: str) -> np.ndarray:
        sp = acc.sparse
        n = int(sp.count)
        idt = _COMPONENTS.get(sp.indices.componentType)
        if idt is None:
            raise self.fail(f"{label}: sparse index type {sp.indices.componentType}")
        data, start, length, _ = self.view_bytes(sp.indices.bufferView, label)
        off = int(sp.indices.byteOffset or 0)
        if off + n * np.dtype(idt).itemsize > length:
            raise self.fail(f"{label}: sparse indices run past their buffer view")
        idx = np.frombuffer(data, idt, n, start + off).astype(np.int64)
        data, start, length, _ = self.view_bytes(sp.values.bufferView, label)
        off = int(sp.values.byteOffset or 0)
        width = out.shape[1]
        if off + n * width * out.dtype.itemsize > length:
            raise self.fail(f"{label}: sparse values run past their buffer view")
        vals = np.frombuffer(data, out.dtype, n * width, start + off).reshape(n, width)
        if idx.size and (idx.min() < 0 or idx.max() >= out.shape[0]):
            raise self.fail(f"{label}: sparse index {int(idx.max())} past {out.shape[0]} items")
        out = out.copy()
        out[idx] = vals
        return out

    def image(self, index: int) -> np.ndarray | None:
        """Image ``index`` decoded to RGBA8 (H, W, 4), row 0 at the top; None for a format
        not decoded here (logged)."""
        if index in self._images:
            return self._images[index]
        img = self._item("images", index)
        what = f"image {index} ({img.name or img.uri or 'embedded'})"
        if img.bufferView is not None:
            data, start, length, _ = self.view_bytes(img.bufferView, what)
            raw = data[start : start + length]
        elif img.uri:
            raw = self._uri_bytes(img.uri, what)
        else:
            raise self.fail(f"{what}: neither a buffer view nor a uri")
        self._images[index] = decode_image(raw, f"{self.source}: {what}")
        return self._images[index]

    def materials(self) -> tuple[list[Material], int]:
        vrm0 = {}
        ext = self.gltf.extensions or {}
        for props in (ext.get("VRM") or {}).get("materialProperties") or []:
            if isinstance(props, dict) and isinstance(props.get("name"), str):
                vrm0[props["name"]] = str(props.get("shader") or "")
        out: list[Material] = []
        decoded = 0
        for i, m in enumerate(self.gltf.materials or []):
            pbr = m.pbrMetallicRoughness
            factor = tuple(
                float(v)
                for v in (
                    pbr.baseColorFactor if pbr and pbr.baseColorFactor else (1.0, 1.0, 1.0, 1.0)
                )
            )
            if len(factor) != 4:
                raise self.fail(f"material {i}: baseColorFactor has {len(factor)} numbers")
            texture = None
            if pbr is not None and pbr.baseColorTexture is not None:
                tex = self._item("textures", pbr.baseColorTexture.index)
                if tex.source is not None:
                    texture = self.image(tex.source)
                    decoded += texture is not None
            mode = str(m.alphaMode or "OPAQUE")
            if mode not in ("OPAQUE", "MASK", "BLEND"):
                raise self.fail(f"material {i}: alphaMode {mode!r}")
            alpha: AlphaMode = (
                "MASK" if mode == "MASK" else "BLEND" if mode == "BLEND" else "OPAQUE"
            )
            mext = m.extensions or {}
            toon = any(k in mext for k in MTOON) or vrm0.get(m.name or "", "") == "VRM/MToon"
            shading: Shading = "toon" if toon else "lit"
            out.append(
                Material(
                    name=m.name or f"material{i}",
                    base_color=(factor[0], factor[1], factor[2], factor[3]),
                    texture=texture,
                    alpha_mode=alpha,
                    alpha_cutoff=float(0.5 if m.alphaCutoff is None else m.alphaCutoff),
                    double_sided=bool(m.doubleSided),
                    shading=shading,
                )
            )
        return out, decoded

    def nodes(self) -> tuple[list[Node], list[int]]:
        """Every node with its world matrix; the indices of the default scene's nodes."""
        gltf_nodes = self.gltf.nodes or []
        n = len(gltf_nodes)
        parent = [-1] * n
        for i, node in enumerate(gltf_nodes):
            for c in node.children or []:
                if not isinstance(c, int) or not 0 <= c < n:
                    raise self.fail(f"node {i} names child {c}, not a node")
                if parent[c] >= 0 or c == i:
                    raise self.fail(f"node {c} has two parents (the node graph is not a tree)")
                parent[c] = i
        scenes = self.gltf.scenes or []
        if scenes:
            which = self.gltf.scene if isinstance(self.gltf.scene, int) else 0
            roots = list(self._item("scenes", which).nodes or [])
        else:
            roots = [i for i in range(n) if parent[i] < 0]
        world: list[np.ndarray | None] = [None] * n
        order: list[int] = []
        stack = [r for r in reversed(roots)]
        for r in roots:
            if not isinstance(r, int) or not 0 <= r < n:
                raise self.fail(f"the scene names node {r}, not a node")
        while stack:
            i = stack.pop()
            if world[i] is not None:
                raise self.fail(f"node {i} is reached twice (a cycle in the node graph)")
            local = _trs(gltf_nodes[i])
            p = parent[i]
            pw = world[p] if p >= 0 else None
            world[i] = local if pw is None else pw @ local
            order.append(i)
            stack.extend(reversed(gltf_nodes[i].children or []))
        out = [
            Node(gltf_nodes[i].name or f"node{i}", parent[i], _or_local(world[i], gltf_nodes[i]))
            for i in range(n)
        ]
        return out, order

    def scene(self) -> GltfScene:
        nodes, order = self.nodes()
        materials, decoded = self.materials()
        default_material = len(materials)
        parts: list[dict[str, Any]] = []
        prims: list[Primitive] = []
        first = 0
        base = 0
        width = 4
        used_default = False
        morphs: dict[tuple[int, int], list[tuple[np.ndarray, np.ndarray]]] = {}
        mesh_nodes: dict[int, list[int]] = {}
        for ni in order:
            gnode = self.gltf.nodes[ni]
            if gnode.mesh is None:
                continue
            mesh = self._item("meshes", gnode.mesh)
            mesh_nodes.setdefault(int(gnode.mesh), []).append(ni)
            for pi, prim in enumerate(mesh.primitives or []):
                what = f"mesh {gnode.mesh} ({mesh.name or ''}) primitive {pi}"
                part = self._primitive(prim, ni, gnode, nodes, what)
                if part is None:
                    continue
                width = max(width, part["bones"].shape[1])
                tri = part["indices"].astype(np.int64) + base
                part["indices"] = tri
                mat = prim.material
                if mat is None:
                    mat = default_material
                    used_default = True
                elif not 0 <= mat < len(materials):
                    raise self.fail(f"{what} names material {mat}, not a material")
                prims.append(Primitive(int(mat), first, int(tri.size)))
                first += int(tri.size)
                for k, delta in part.pop("morphs", {}).items():
                    moved = np.flatnonzero(np.abs(delta).max(axis=1) > 0.0)
                    morphs.setdefault((ni, k), []).append((base + moved, delta[moved]))
                base += part["positions"].shape[0]
                parts.append(part)
        if not parts:
            raise self.fail("no triangle meshes in the default scene")
        if used_default:
            materials.append(Material("default"))

        def cat(key: str) -> np.ndarray:
            return np.concatenate([p[key] for p in parts])

        def pad(key: str, fill: float) -> np.ndarray:
            return np.concatenate(
                [
                    np.pad(p[key], ((0, 0), (0, width - p[key].shape[1])), constant_values=fill)
                    for p in parts
                ]
            )

        ext = self.gltf.extensions if isinstance(self.gltf.extensions, dict) else {}
        return GltfScene(
            source=self.source,
            nodes=tuple(nodes),
            positions=cat("positions"),
            normals=cat("normals"),
            uv=cat("uv").astype(np.float32),
            bones=pad("bones", 0),
            weights=pad("weights", 0.0),
            indices=cat("indices").astype(np.uint32),
            primitives=tuple(prims),
            materials=tuple(materials),
            extensions=dict(ext),
            textures=decoded,
            morphs={
                key: (np.concatenate([m[0] for m in got]), np.concatenate([m[1] for m in got]))
                for key, got in morphs.items()
            },
            mesh_nodes={m: tuple(n) for m, n in mesh_nodes.items()},
        )

    def _primitive(
        self, prim: Any, ni: int, gnode: Any, nodes: list[Node], what: str
    ) -> dict[str, Any] | None:
        mode = 4 if prim.mode is None else int(prim.mode)
        if mode not in (4, 5, 6):
            log.info("%s: %s: mode %d (points or lines) skipped", self.source, what, mode)
            return None
        attrs = prim.attributes
        if attrs is None or attrs.POSITION is None:
            raise self.fail(f"{what}: no POSITION attribute")
        pos = self.accessor(attrs.POSITION, f"{what} POSITION").astype(np.float64)
        v = pos.shape[0]
        if pos.shape[1] != 3:
            raise self.fail(f"{what}: POSITION is not VEC3")

        def per_vertex(index: Any, name: str, cols: int) -> np.ndarray | None:
            if index is None:
                return None
            arr = self.accessor(index, f"{what} {name}")
            if arr.shape != (v, cols):
                raise self.fail(
                    f"{what}: {name} has {arr.shape[0]} items of {arr.shape[1]}, want {v} of {cols}"
                )
            return arr

        nrm = per_vertex(attrs.NORMAL, "NORMAL", 3)
        uv = per_vertex(attrs.TEXCOORD_0, "TEXCOORD_0", 2)
        if prim.indices is not None:
            idx = self.accessor(prim.indices, f"{what} indices").reshape(-1).astype(np.int64)
        else:
            idx = np.arange(v, dtype=np.int64)
        if idx.size and (idx.min() < 0 or idx.max() >= v):
            raise self.fail(f"{what}: index {int(idx.max())} past its {v} vertices")
        idx = _triangles(idx, mode)
        if nrm is None:
            nrm = _vertex_normals(pos, idx)
        nrm = nrm.astype(np.float64)
        joint_sets = []
        k = 0
        while getattr(attrs, f"JOINTS_{k}", None) is not None:
            joints = per_vertex(getattr(attrs, f"JOINTS_{k}"), f"JOINTS_{k}", 4)
            wname = f"WEIGHTS_{k}"
            weights = per_vertex(getattr(attrs, wname, None), wname, 4)
            if joints is None or weights is None:
                raise self.fail(f"{what}: JOINTS_{k} without {wname}")
            joint_sets.append((joints.astype(np.int64), weights.astype(np.float64)))
            k += 1
        if gnode.skin is not None and joint_sets:
            skin = self._item("skins", gnode.skin)
            skin_joints = list(skin.joints or [])
            for j in skin_joints:
                if not isinstance(j, int) or not 0 <= j < len(nodes):
                    raise self.fail(f"skin {gnode.skin} names joint {j}, not a node")
            if skin.inverseBindMatrices is not None:
                ibm = self.accessor(skin.inverseBindMatrices, f"skin {gnode.skin} inverse binds")
                if ibm.shape != (len(skin_joints), 4, 4):
                    raise self.fail(
                        f"skin {gnode.skin}: {ibm.shape[0]} inverse bind matrices "
                        f"for {len(skin_joints)} joints"
                    )
            else:
                ibm = np.tile(np.eye(4), (len(skin_joints), 1, 1))
            jm = np.stack([nodes[j].world for j in skin_joints]) @ ibm
            local = np.concatenate([s[0] for s in joint_sets], axis=1)
            weights = np.concatenate([s[1] for s in joint_sets], axis=1)
            if local.size and local.max() >= len(skin_joints):
                raise self.fail(
                    f"{what}: JOINTS_ index {int(local.max())} past the "
                    f"{len(skin_joints)} joints of skin {gnode.skin}"
                )
            weights = np.where(np.isfinite(weights) & (weights > 0), weights, 0.0)
            total = weights.sum(axis=1, keepdims=True)
            empty = total[:, 0] <= 1e-9
            weights[empty, 0] = 1.0
            total[empty] = 1.0
            weights /= total
            m = np.einsum("vk,vkij->vij", weights, jm[local])
            world_pos = np.einsum("vij,vj->vi", m[:, :3, :3], pos) + m[:, :3, 3]
            world_nrm = np.einsum("vij,vj->vi", m[:, :3, :3], nrm)
            bones = np.asarray(skin_joints, np.int64)[local]
            bones[empty, 0] = ni
            linear = m[:, :3, :3]
        else:
            w = nodes[ni].world
            linear = np.broadcast_to(w[:3, :3], (v, 3, 3))
            world_pos = pos @ w[:3, :3].T + w[:3, 3]
            world_nrm = nrm @ np.linalg.inv(w[:3, :3])  # inverse transpose, row vectors
            bones = np.full((v, 4), ni, np.int64)
            weights = np.zeros((v, 4))
            weights[:, 0] = 1.0
        norm = np.linalg.norm(world_nrm, axis=1, keepdims=True)
        world_nrm = np.where(norm > 1e-12, world_nrm / np.maximum(norm, 1e-12), [0.0, 1.0, 0.0])
        if not np.isfinite(world_pos).all():
            raise self.fail(f"{what}: vertex positions are not finite")
        morphs = {}
        for k, target in enumerate(prim.targets or []):
            index = (
                target.get("POSITION")
                if isinstance(target, dict)
                else getattr(target, "POSITION", None)
            )
            delta = per_vertex(index, f"morph target {k} POSITION", 3)
            if delta is not None:
                morphs[k] = np.einsum("vij,vj->vi", linear, delta.astype(np.float64))
        return {
            "morphs": morphs,
            "positions": world_pos,
            "normals": world_nrm,
            "uv": np.zeros((v, 2)) if uv is None else uv.astype(np.float64),
            "bones": bones,
            "weights": weights,
            "indices": idx,
        }


def _triangles(idx: np.ndarray, mode: int) -> np.ndarray:
    """Index list of separate triangles from a list, strip (5) or fan (6)."""
    if mode == 4:
        return idx[: idx.size - idx.size % 3]
    if idx.size < 3:
        return np.zeros(0, np.int64)
    k = np.arange(idx.size - 2)
    if mode == 5:
        a, b = np.where(k % 2 == 0, k, k + 1), np.where(k % 2 == 0, k + 1, k)
        tri = np.stack([idx[a], idx[b], idx[k + 2]], axis=1)
    else:
        tri = np.stack([np.full(k.size, idx[0]), idx[k + 1], idx[k + 2]], axis=1)
    return tri.reshape(-1)


def _vertex_normals(pos: np.ndarray, idx: np.ndarray) -> np.ndarray:
    tri = idx.reshape(-1, 3)
    face = np.cross(pos[tri[:, 1]] - pos[tri[:, 0]], pos[tri[:, 2]] - pos[tri[:, 0]])
    out = np.zeros_like(pos)
    for c in range(3):
        np.add.at(out, tri[:, c], face)
    return out


def decode_image(raw: bytes, what: str) -> np.ndarray | None:
    """PNG or JPEG bytes to RGBA8 (H, W, 4), row 0 at the top, through PyAV (FFmpeg)."""
    if raw[:8] == b"\x89PNG\r\n\x1a\n":
        fmt = "png_pipe"
    elif raw[:3] == b"\xff\xd8\xff":
        fmt = "jpeg_pipe"
    elif raw[:4] == b"RIFF" and raw[8:12] == b"WEBP":
        fmt = "webp_pipe"
    else:
        log.warning("%s: not PNG, JPEG or WebP: drawn with its colour factor only", what)
        return None
    import av

    try:
        with av.open(io.BytesIO(raw), "r", format=fmt) as container:
            for frame in container.decode(video=0):
                out: np.ndarray = frame.to_ndarray(format="rgba")
                return np.ascontiguousarray(out, np.uint8)
    except (av.FFmpegError, ValueError, OSError) as exc:
        raise AvatarError(f"{what}: cannot decode the image: {exc}") from exc
    raise AvatarError(f"{what}: the image holds no picture")
