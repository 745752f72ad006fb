"""Unit meshes for the renderer, built by revolving a profile or by hand; pure numpy.

Every drawn shape is one of a few unit meshes placed by a per-instance matrix: a cylinder side
(radius 1, z 0..1; also as the coarser ``limb`` and ``rod``), a disc (radius 1 at z = 0; finer
as ``floor``), a cymbal (radius 1, bell up), a sphere (radius 1) and a cube (edge 1, centred).
Round shapes come from :func:`lathe`, which revolves an ``(r, z)`` profile about +z and takes
normals from the profile's tangent, so a new round shape is a new profile and not new code.
Meshes are indexed triangles with interleaved float32 position and normal (``VERTEX_FLOATS``
per vertex). Limits: smooth normals only along the revolution (the cube has flat faces by
construction); no texture coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

VERTEX_FLOATS = 6  # x y z nx ny nz


@dataclass(frozen=True)
class Mesh:
    """Indexed triangles: ``vertices`` float32 (V, 6), ``indices`` uint32 (T * 3,)."""

    name: str
    vertices: np.ndarray
    indices: np.ndarray


def lathe(name: str, profile: list[tuple[float, float]], segments: int = 32) -> Mesh:
    """Revolve ``(r, z)`` points (in order along the surface) about +z."""
    prof = np.asarray(profile, np.float64)
    tangent = np.gradient(prof, axis=0)
    # Normal in the (r, z) plane: the tangent turned a quarter clockwise (outwards for a
    # profile that climbs or goes inward).
    n_rz = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
    n_rz /= np.maximum(np.linalg.norm(n_rz, axis=1, keepdims=True), 1e-12)
    angle = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]  # (S+1, 1)
    shape = (segments + 1, len(prof))
    pos = np.stack([c * prof[:, 0], s * prof[:, 0], np.broadcast_to(prof[:, 1], shape)], -1)
    nrm = np.stack([c * n_rz[:, 0], s * n_rz[:, 0], np.broadcast_to(n_rz[:, 1], shape)], -1)
    vertices = np.concatenate([pos, nrm], axis=-1).reshape(-1, VERTEX_FLOATS)
    p = len(prof)
    i, j = np.meshgrid(np.arange(segments), np.arange(p - 1), indexing="ij")
    a = i * p + j
    b = (i + 1) * p + j
    quads = np.stack([a, b, a + 1, a + 1, b, b + 1], axis=-1)
    return Mesh(name, vertices.astype(np.float32), quads.reshape(-1).astype(np.uint32))


def cylinder(segments: int = 28, name: str = "cylinder") -> Mesh:
    return lathe(name, [(1.0, 0.0), (1.0, 1.0)], segments)


def disc(segments: int = 28, name: str = "disc") -> Mesh:
    # Outer edge to centre: the tangent points inward, so the normal comes out +z.
    return lathe(name, [(1.0, 0.0), (0.5, 0.0), (0.0, 0.0)], segments)


def cymbal(segments: int = 32) -> Mesh:
    """A cymbal of radius 1 with its bell up; edge at z = 0, bell top at z = 0.1."""
    return lathe(
        "cymbal",
        [
            (1.0, 0.0),
            (0.7, 0.018),
            (0.4, 0.036),
            (0.24, 0.048),
            (0.2, 0.08),
            (0.12, 0.1),
            (0.0, 0.1),
        ],
        segments,
    )


def sphere(segments: int = 16, rings: int = 10) -> Mesh:
    theta = np.linspace(0.0, np.pi, rings + 1)  # from the bottom pole to the top
    profile = [(float(np.sin(t)), float(-np.cos(t))) for t in theta]
    return lathe("sphere", profile, segments)


def cube() -> Mesh:
    corners = np.array(
        [[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)], np.float32
    )
    verts: list[np.ndarray] = []
    idx: list[int] = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            face = corners[corners[:, axis] * sign > 0]
            # Order the four corners around the face.
            u, v = [k for k in range(3) if k != axis]
            ang = np.arctan2(face[:, v], face[:, u])
            face = face[np.argsort(ang)]
            normal = np.zeros(3, np.float32)
            normal[axis] = sign
            base = len(verts)
            verts.extend(np.concatenate([f, normal]) for f in face)
            idx.extend(base + k for k in (0, 1, 2, 0, 2, 3))
    return Mesh("cube", np.array(verts, np.float32), np.array(idx, np.uint32))


def all_meshes() -> dict[str, Mesh]:
    """The meshes the renderer uploads once, by name."""
    meshes = (
        cylinder(),
        cylinder(12, "limb"),
        cylinder(6, "rod"),
        disc(),
        disc(64, "floor"),
        cymbal(),
        sphere(),
        cube(),
    )
    return {m.name: m for m in meshes}
