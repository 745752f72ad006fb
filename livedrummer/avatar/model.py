"""The avatar contract: a skinned mesh weighted to the body's joints, materials, proportions.

Why this shape. The body model (:mod:`livedrummer.body`) moves one fixed skeleton of 24
joints (:data:`~livedrummer.body.skeleton.JOINTS`); every avatar, built in or read from a
glTF/VRM file, is brought onto *that* skeleton once, at load time, so that the renderer, the
exporters and the live display never learn where an avatar came from:

* ``positions``/``normals``/``uv`` are the vertices in the avatar's **bind pose**, in the kit
  frame (metres, +x right, +y forward, +z up, the drummer facing +y), already scaled and
  turned by the loader;
* ``joints``/``weights`` give each vertex up to four of *our* joints (indices into
  ``JOINTS``) and weights that sum to 1; an avatar bone with no counterpart (hair, a skirt,
  a finger) is weighted to its nearest mapped ancestor, fingers pre-curled round the stick;
* ``bind`` holds, per joint, the world matrix (4x4, column vectors) the joint had when the
  mesh was bound. Drawing a pose is then linear blend skinning with
  ``world(pose)[j] @ inverse(bind[j])`` (:mod:`~livedrummer.avatar.skinning`). For an
  avatar bound in our own rest pose (all local rotations identity) ``bind[j]`` is a pure
  translation to the joint's rest position; a T-posed VRM carries the rotation that takes
  our rest bone direction onto its own;
* ``lengths`` are the avatar's own segment lengths: the rig built from them (IK, reach
  checks, BVH offsets) is the avatar's, so its sticks reach the struck zone.

Materials are glTF's metallic-roughness subset that a stage needs: a base colour factor,
an optional base-colour texture (RGBA8, row 0 at the top, as decoded), an alpha mode, a
roughness factor, and a shading flag (``lit``, or ``toon`` for VRM's MToon drawn as banded
lighting).

Limits: four weights per vertex (extra influences are dropped by the loader and the rest
renormalised); one UV set; morph targets only as the face shapes named by
:data:`livedrummer.body.face.FACES` (positions, not normals); 32-bit indices.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from livedrummer.body.skeleton import N_JOINTS, SegmentLengths
from livedrummer.errors import LivedrummerError

AlphaMode = Literal["OPAQUE", "MASK", "BLEND"]
Shading = Literal["lit", "toon"]
MAX_INFLUENCES = 4


class AvatarError(LivedrummerError):
    """An avatar file or a built avatar is not usable; the message names the file and field."""


@dataclass(frozen=True)
class Material:
    """How one primitive is coloured (see the module docstring)."""

    name: str
    base_color: tuple[float, float, float, float] = (0.8, 0.8, 0.8, 1.0)
    texture: np.ndarray | None = None  # uint8 (H, W, 4), row 0 at the top
    alpha_mode: AlphaMode = "OPAQUE"
    alpha_cutoff: float = 0.5
    double_sided: bool = False
    shading: Shading = "lit"
    #: glTF's roughness factor: 1 is matte, 0 a sharp highlight (the renderer maps it to a
    #: specular exponent); metalness is not drawn.
    roughness: float = 1.0


@dataclass(frozen=True)
class Primitive:
    """A run of ``indices`` (``first`` .. ``first + count``) drawn with one material."""

    material: int
    first: int
    count: int


@dataclass(frozen=True)
class SkinnedMesh:
    """Vertices bound to the body's joints (see the module docstring for every field)."""

    positions: np.ndarray  # float32 (V, 3), bind pose, kit frame, metres
    normals: np.ndarray  # float32 (V, 3), unit
    uv: np.ndarray  # float32 (V, 2); zeros where the source had none
    joints: np.ndarray  # uint16 (V, 4), indices into JOINTS
    weights: np.ndarray  # float32 (V, 4), each row sums to 1
    indices: np.ndarray  # uint32 (3T,), triangles
    primitives: tuple[Primitive, ...]
    materials: tuple[Material, ...]
    bind: np.ndarray  # float32 (N_JOINTS, 4, 4), joint world matrices at bind time

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def triangle_count(self) -> int:
        return int(self.indices.size // 3)

    def check(self, where: str = "avatar") -> None:
        """Raise :class:`AvatarError` naming the first field whose shape or values are wrong."""
        v = self.positions.shape[0]
        want = {
            "positions": ((v, 3), np.float32),
            "normals": ((v, 3), np.float32),
            "uv": ((v, 2), np.float32),
            "joints": ((v, MAX_INFLUENCES), np.uint16),
            "weights": ((v, MAX_INFLUENCES), np.float32),
            "bind": ((N_JOINTS, 4, 4), np.float32),
        }
        for name, (shape, dtype) in want.items():
            arr = getattr(self, name)
            if arr.shape != shape or arr.dtype != dtype:
                raise AvatarError(
                    f"{where}: {name} is {arr.dtype}{arr.shape}, want {np.dtype(dtype)}{shape}"
                )
        if self.indices.dtype != np.uint32 or self.indices.ndim != 1 or self.indices.size % 3:
            raise AvatarError(
                f"{where}: indices must be uint32 triangles (got "
                f"{self.indices.dtype}{self.indices.shape})"
            )
        if v == 0 or self.indices.size == 0:
            raise AvatarError(f"{where}: the mesh has no triangles")
        if int(self.indices.max()) >= v:
            raise AvatarError(f"{where}: index {int(self.indices.max())} past {v} vertices")
        if int(self.joints.max()) >= N_JOINTS:
            raise AvatarError(f"{where}: joint index {int(self.joints.max())} past {N_JOINTS}")
        if not np.isfinite(self.positions).all() or not np.isfinite(self.bind).all():
            raise AvatarError(f"{where}: positions or bind matrices are not finite")
        sums = self.weights.sum(axis=1)
        bad = np.flatnonzero(np.abs(sums - 1.0) > 1e-3)
        if bad.size:
            raise AvatarError(
                f"{where}: vertex {int(bad[0])} weights sum to {float(sums[bad[0]]):.4f}, want 1"
            )
        end = 0
        for i, prim in enumerate(self.primitives):
            if not 0 <= prim.material < len(self.materials):
                raise AvatarError(f"{where}: primitive {i} names material {prim.material}")
            if prim.first < 0 or prim.count % 3 or prim.first + prim.count > self.indices.size:
                raise AvatarError(f"{where}: primitive {i} runs past the index buffer")
            end = max(end, prim.first + prim.count)
        if not self.primitives:
            raise AvatarError(f"{where}: no primitives")


@dataclass(frozen=True)
class FaceShape:
    """One face shape (a blend shape, a morph target): the vertices it moves and by how much
    at full weight, in the bind pose's frame (metres). Shapes add: a drawn face is the mesh
    plus the sum of weight times shape."""

    vertices: np.ndarray  # int64 (M,), sorted, unique
    deltas: np.ndarray  # float32 (M, 3)


def face_shape(moves: list[tuple[np.ndarray, np.ndarray]]) -> FaceShape:
    """The shape of a list of (vertex indices, deltas) moves, summed where they overlap."""
    idx = np.concatenate([m[0] for m in moves]).astype(np.int64)
    d = np.concatenate([m[1] for m in moves]).astype(np.float64)
    uniq, inv = np.unique(idx, return_inverse=True)
    total = np.zeros((uniq.size, 3))
    np.add.at(total, inv, d)
    return FaceShape(uniq, total.astype(np.float32))


@dataclass(frozen=True)
class Avatar:
    """A drawable character and the proportions its motion must use."""

    name: str
    source: str  # a file path, or "built-in"
    lengths: SegmentLengths
    mesh: SkinnedMesh
    #: our joint name -> the avatar's bone (node) name it was mapped from (``avatar info``)
    bones: dict[str, str] = field(default_factory=dict)
    digest: str = ""  # hex; announced by the synth in READY so a display can compare
    #: face shapes by the names of :data:`livedrummer.body.face.FACES` (a VRM's expressions,
    #: the built-in character's own); empty for an avatar without any
    faces: dict[str, FaceShape] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.digest:
            object.__setattr__(self, "digest", mesh_digest(self.mesh, self.lengths))


def mesh_digest(mesh: SkinnedMesh, lengths: SegmentLengths) -> str:
    """A short stable hash of the geometry, binding and proportions (16 hex digits)."""
    h = hashlib.sha256()
    for arr in (mesh.positions, mesh.joints, mesh.weights, mesh.indices, mesh.bind):
        h.update(np.ascontiguousarray(arr).tobytes())
    h.update(repr(lengths).encode())
    return h.hexdigest()[:16]
