"""The built-in drummer: a skinned human mesh generated in code from the body's proportions.

Why this shape. The character must follow any :class:`~livedrummer.body.skeleton.SegmentLengths`
(the rig the IK uses), ship no downloaded assets, and build fast enough to need no cache, so it
is made of a few dozen **swept cross-sections** placed along the rest-pose skeleton: each body
part is a ring tube (superellipse rings of varying half-width, half-depth and centre, closed by
rounded caps) laid along its bone chain, and small ellipsoids for the face. Parts overlap where
they meet (an arm's rounded top inside the shoulder, the thigh's inside the hips, the shirt over
the trousers), so a bent joint shows skin or cloth, never a hole.

* Torso: one tube from the hips to the neck whose rings widen to hips, narrow to the waist and
  widen again to chest and shoulders; trousers below the belt, a T-shirt above it.
* Arms and legs: one tube each from shoulder to wrist and hip to ankle, so the elbow and knee
  bend one continuous surface; T-shirt sleeves and trouser legs are the cloth tubes over them.
* Head: a tube of rings shaped to a skull with a narrower jaw, eyes (whites, irises, pupils),
  brows, nose, lips and ears placed on its front surface, and a hair shell from a hairline to
  the crown. It is modelled looking up a little with the eyes looking down
  (:data:`FACE_TILT_RAD`), so a drummer watching his drums still shows the audience a face.
* Hands: a palm and four fingers curled round the stick at the grip fulcrum (the ``*_stick``
  joint), a thumb along the stick; shoes with a light sole.

Weights follow each part's parameter along its chain: a vertex's weight passes from one joint
to the next with a smoothstep over a window around the joint (wide at the elbow and knee,
narrow where the part is rigid), at most three joints at once, so elbows and knees bend
smoothly. The fingers are weighted partly to the stick joint, so they stay wrapped round the
stick as it pivots in the hand. The bind pose is the body's rest pose (all local rotations
identity): every ``bind`` matrix is a pure translation.

The face has shapes of its own for the blinks, looks and reactions of
:mod:`livedrummer.body.face` (:func:`_faces`: eyes, brows and mouth moved, no eyelids).

Limits: no textures (flat colours), linear blend skinning (a joint
bent past ~130 degrees thins a little on its inner side); the face is a stage-distance
face, not a portrait.
"""

from __future__ import annotations

import numpy as np

from livedrummer.avatar.model import Avatar, FaceShape, Material, Primitive, SkinnedMesh, face_shape
from livedrummer.body.skeleton import N_JOINTS, PARENTS, J, SegmentLengths, build_skeleton

#: The head is modelled looking up by this much (radians), its eyes looking down by as much:
#: the body pitches the head 25-40 degrees down towards the drums, and a face turned that far
#: away shows the audience mostly hair; eyes that look down carry the gaze instead.
FACE_TILT_RAD = np.radians(14.0)

#: Material indices of the built-in character.
SKIN, SHIRT, TROUSERS, SHOES, SOLE, HAIR, EYE_WHITE, IRIS, PUPIL, LIPS = range(10)
MATERIALS: tuple[Material, ...] = (
    Material("skin", (0.86, 0.62, 0.50, 1.0), roughness=0.7),
    Material("shirt", (0.62, 0.10, 0.09, 1.0), roughness=0.95),
    Material("trousers", (0.13, 0.15, 0.22, 1.0), roughness=0.95),
    Material("shoes", (0.07, 0.07, 0.08, 1.0), roughness=0.5),
    Material("sole", (0.88, 0.87, 0.84, 1.0), roughness=0.9),
    Material("hair", (0.17, 0.10, 0.06, 1.0), roughness=0.6, double_sided=True),
    Material("eye_white", (0.96, 0.95, 0.92, 1.0), roughness=0.3),
    Material("iris", (0.22, 0.36, 0.52, 1.0), roughness=0.3),
    Material("pupil", (0.02, 0.02, 0.02, 1.0), roughness=0.3),
    Material("lips", (0.68, 0.36, 0.34, 1.0), roughness=0.6),
)

#: Primitives are drawn outer layers first (hair over the scalp, the shirt over the trousers'
#: waist, sleeves over the arms), so the layers under them fail the depth test unshaded.
DRAW_ORDER = (HAIR, EYE_WHITE, IRIS, PUPIL, LIPS, SHIRT, SHOES, SOLE, TROUSERS, SKIN)


def _smooth(edge0: float, edge1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - edge0) / max(edge1 - edge0, 1e-9), 0.0, 1.0)
    return np.asarray(t * t * (3.0 - 2.0 * t))


def chain_weights(
    s: np.ndarray, joints: list[int], bounds: list[tuple[float, float]]
) -> np.ndarray:
    """Dense weights (len(s), N_JOINTS): joint k hands over to k+1 around ``bounds[k]`` =
    (parameter at the joint, half-width of the blend)."""
    s = np.asarray(s, np.float64)
    w = np.zeros((s.size, N_JOINTS))
    carry = np.ones(s.size)
    for k, joint in enumerate(joints):
        if k < len(bounds):
            at, half = bounds[k]
            nxt = _smooth(at - half, at + half, s)
            w[:, joint] += carry * (1.0 - nxt)
            carry = carry * nxt
        else:
            w[:, joint] += carry
    return w


class _Parts:
    """Triangle soups per material, with dense joint weights, merged at the end."""

    def __init__(self) -> None:
        self.parts: list[tuple[int, np.ndarray, np.ndarray, np.ndarray]] = []
        self.tags: dict[int, str] = {}  # part index -> a face part's name (see faces())
        self.where: dict[str, np.ndarray] = {}  # set by mesh(): tag -> vertex indices

    def tag(self, name: str) -> None:
        """Name the part added last (the face's shapes move tagged parts)."""
        self.tags[len(self.parts) - 1] = name

    def add(self, material: int, pos: np.ndarray, tri: np.ndarray, weights: np.ndarray) -> None:
        self.parts.append((material, pos, tri, weights))

    def tube(
        self,
        material: int,
        rings: np.ndarray,
        weights: np.ndarray,
        *,
        keep: np.ndarray | None = None,
    ) -> None:
        """Rings (R, K, 3) joined into a closed tube; ``weights`` (R, N_JOINTS) per ring or
        (R, K, N_JOINTS) per vertex; ``keep`` (R, K) bool drops every quad with a vertex not
        kept."""
        r, k = rings.shape[:2]
        i = np.arange(r - 1)[:, None]
        j = np.arange(k)[None, :]
        a = i * k + j
        b = i * k + (j + 1) % k
        c = (i + 1) * k + j
        d = (i + 1) * k + (j + 1) % k
        quads = np.stack([a, b, d, c], axis=-1).reshape(-1, 4)
        if keep is not None:
            flat = keep.reshape(-1)
            quads = quads[flat[quads].all(axis=1)]
        tri = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        w = weights.reshape(-1, N_JOINTS) if weights.ndim == 3 else np.repeat(weights, k, 0)
        self.add(material, rings.reshape(-1, 3), tri, w)

    def mesh(self) -> SkinnedMesh:
        positions, normals, weights, tris, prims = [], [], [], [], []
        base = 0
        first = 0
        order = sorted(range(len(self.parts)), key=lambda n: DRAW_ORDER.index(self.parts[n][0]))
        by_material: dict[int, int] = {}
        for n in order:
            material, pos, tri, w = self.parts[n]
            if n in self.tags:
                got = self.where.get(self.tags[n], np.zeros(0, np.int64))
                self.where[self.tags[n]] = np.concatenate([got, base + np.arange(pos.shape[0])])
            positions.append(pos)
            normals.append(_normals(pos, tri))
            weights.append(w)
            tris.append(tri + base)
            base += pos.shape[0]
            by_material[material] = by_material.get(material, 0) + tri.size
        for material in sorted(by_material, key=DRAW_ORDER.index):
            prims.append(Primitive(material, first, by_material[material]))
            first += by_material[material]
        dense = np.concatenate(weights)
        top = np.argsort(-dense, axis=1)[:, :4]
        wt = np.take_along_axis(dense, top, axis=1)
        wt /= wt.sum(axis=1, keepdims=True)
        p = np.concatenate(positions).astype(np.float32)
        return SkinnedMesh(
            positions=p,
            normals=np.concatenate(normals).astype(np.float32),
            uv=np.zeros((p.shape[0], 2), np.float32),
            joints=np.where(wt > 0, top, 0).astype(np.uint16),
            weights=wt.astype(np.float32),
            indices=np.concatenate(tris).astype(np.uint32).reshape(-1),
            primitives=tuple(prims),
            materials=MATERIALS,
            bind=np.zeros((N_JOINTS, 4, 4), np.float32),  # set by build_character
        )


def _normals(pos: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals, turned to point away from the part's centre."""
    a, b, c = pos[tri[:, 0]], pos[tri[:, 1]], pos[tri[:, 2]]
    face = np.cross(b - a, c - a)
    n = np.zeros_like(pos)
    for k in range(3):
        np.add.at(n, tri[:, k], face)
    if float(np.einsum("ij,ij->", n, pos - pos.mean(axis=0))) < 0:
        n = -n
        tri[:, [1, 2]] = tri[:, [2, 1]]
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.asarray(n / np.maximum(length, 1e-12))


def _ring(
    centre: np.ndarray, ex: np.ndarray, ey: np.ndarray, a: float, b: float, power: float, k: int
) -> np.ndarray:
    """K points of a superellipse (|x/a|^p + |y/b|^p = 1) round ``centre`` in the ex/ey plane;
    angle 0 is +ex, angle 90 degrees +ey."""
    t = np.linspace(0.0, 2.0 * np.pi, k, endpoint=False)
    c, s = np.cos(t), np.sin(t)
    e = 2.0 / power
    x = np.sign(c) * np.abs(c) ** e * a
    y = np.sign(s) * np.abs(s) ** e * b
    return np.asarray(centre + x[:, None] * ex + y[:, None] * ey)


def _sweep(
    profile: list[tuple[float, float, float, float, float]],
    origin: np.ndarray,
    axis: np.ndarray,
    ex: np.ndarray,
    ey: np.ndarray,
    *,
    power: float = 2.0,
    k: int = 20,
    caps: tuple[int, int] = (4, 4),
    depth: tuple[float, float] = (1.0, 1.0),
) -> tuple[np.ndarray, np.ndarray]:
    """A tube from a profile of (s along axis, half-width a, half-depth b, offset along ex,
    offset along ey) rows; rounded caps of ``caps`` rings at either end (0: open), each
    ``depth`` times the end ring's smaller radius deep. Returns rings (R, K, 3) and each
    ring's parameter s (R,)."""
    rows = [(float(r[0]), float(r[1]), float(r[2]), float(r[3]), float(r[4])) for r in profile]
    out: list[tuple[float, float, float, float, float]] = []
    first, last = rows[0], rows[-1]
    if caps[0]:
        d0 = depth[0] * min(first[1], first[2])
        for phi in np.linspace(np.pi / 2, 0.0, caps[0], endpoint=False):
            f = np.cos(phi) if phi < np.pi / 2 - 1e-9 else 0.0
            out.append(
                (first[0] - d0 * np.sin(phi), first[1] * f, first[2] * f, first[3], first[4])
            )
    out.extend(rows)
    if caps[1]:
        d1 = depth[1] * min(last[1], last[2])
        for phi in np.linspace(0.0, np.pi / 2, caps[1] + 1)[1:]:
            f = np.cos(phi) if phi < np.pi / 2 - 1e-9 else 0.0
            out.append((last[0] + d1 * np.sin(phi), last[1] * f, last[2] * f, last[3], last[4]))
    arr = np.array(out)
    rings = np.stack(
        [
            _ring(origin + s * axis + ox * ex + oy * ey, ex, ey, a, b, power, k)
            for s, a, b, ox, oy in arr
        ]
    )
    return rings, arr[:, 0]


def _ellipsoid(
    parts: _Parts,
    material: int,
    centre: np.ndarray,
    radii: tuple[float, float, float],
    joint: int | np.ndarray,
    *,
    rot: np.ndarray | None = None,
    k: int = 10,
    rings: int = 6,
) -> None:
    """A closed ellipsoid (axes x, y, z scaled by ``radii``, turned by ``rot``) on one joint
    (an index) or on a dense weight row."""
    phi = np.linspace(-np.pi / 2, np.pi / 2, rings + 2)
    phi[0], phi[-1] = -np.pi / 2 * 0.999, np.pi / 2 * 0.999
    t = np.linspace(0.0, 2.0 * np.pi, k, endpoint=False)
    x = np.cos(phi)[:, None] * np.cos(t)[None, :] * radii[0]
    y = np.cos(phi)[:, None] * np.sin(t)[None, :] * radii[1]
    z = np.repeat(np.sin(phi)[:, None] * radii[2], k, axis=1)
    pts = np.stack([x, y, z], axis=-1)
    if rot is not None:
        pts = pts @ rot.T
    pts = pts + centre
    w = np.zeros((pts.shape[0], N_JOINTS))
    if isinstance(joint, int):
        w[:, joint] = 1.0
    else:
        w[:] = joint
    parts.tube(material, pts, w)


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def rest_positions(lengths: SegmentLengths) -> np.ndarray:
    """World joint positions (24, 3) of the rest pose the character is bound in."""
    sk = build_skeleton(lengths)
    p = np.zeros((N_JOINTS, 3))
    p[0] = sk.root_m
    for j in range(1, N_JOINTS):
        p[j] = p[PARENTS[j]] + sk.offsets[j]
    return p


X = np.array([1.0, 0.0, 0.0])
Y = np.array([0.0, 1.0, 0.0])
Z = np.array([0.0, 0.0, 1.0])


def _one(joint: int, n: int) -> np.ndarray:
    w = np.zeros((n, N_JOINTS))
    w[:, joint] = 1.0
    return w


def build_character(lengths: SegmentLengths | None = None) -> Avatar:
    """The built-in drummer for ``lengths`` (default proportions when None)."""
    s = lengths or SegmentLengths()
    s.check()
    p = rest_positions(s)
    parts = _Parts()
    _torso(parts, s, p)
    first = len(parts.parts)
    _head(parts, s, p)
    _tilt(parts, first, p[J["head"]], FACE_TILT_RAD)
    for side, sign in (("r", 1.0), ("l", -1.0)):
        _arm(parts, s, p, side, sign)
        _hand(parts, s, p, side, sign)
        _leg(parts, s, p, side, sign)
        _shoe(parts, s, p, side, sign)
    mesh = parts.mesh()
    bind = np.tile(np.eye(4, dtype=np.float32), (N_JOINTS, 1, 1))
    bind[:, :3, 3] = p
    mesh = SkinnedMesh(
        mesh.positions,
        mesh.normals,
        mesh.uv,
        mesh.joints,
        mesh.weights,
        mesh.indices,
        mesh.primitives,
        mesh.materials,
        bind,
    )
    mesh.check("built-in character")
    return Avatar("drummer", "built-in", s, mesh, faces=_faces(mesh.positions, parts.where))


def _faces(pos: np.ndarray, where: dict[str, np.ndarray]) -> dict[str, FaceShape]:
    """The character's own shapes for :data:`livedrummer.body.face.FACES` (moves of its eyes,
    brows and mouth in the bind pose, metres): a blink flattens each eye into a line and sinks
    it into the face, a look moves iris and pupil across the eye, happy widens the mouth and
    lifts its corners and the brows, surprised opens the mouth and raises the brows higher."""
    p = pos.astype(np.float64)
    shapes: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}

    def move(name: str, idx: np.ndarray, delta: np.ndarray) -> None:
        shapes.setdefault(name, []).append((idx, delta))

    for eye in ("eye_r", "eye_l"):
        white = where[f"{eye}_white"]
        parts_ = np.concatenate([white, where[f"{eye}_iris"], where[f"{eye}_pupil"]])
        centre = p[white].mean(axis=0)
        d = np.zeros((parts_.size, 3))
        d[:, 2] = (centre[2] - p[parts_, 2]) * 0.88
        d[:, 1] = -0.004
        move("blink", parts_, d)
        front = np.concatenate([where[f"{eye}_iris"], where[f"{eye}_pupil"]])
        for name, axis, amount in (
            ("look_left", 0, -0.0055),
            ("look_right", 0, 0.0055),
            ("look_up", 2, 0.0035),
            ("look_down", 2, -0.0035),
        ):
            d = np.zeros((front.size, 3))
            d[:, axis] = amount
            move(name, front, d)
        wide = np.zeros((white.size, 3))
        wide[:, 2] = (p[white, 2] - centre[2]) * 0.25
        move("surprised", white, wide)
    mouth = where["mouth"]
    mc = p[mouth].mean(axis=0)
    rel = p[mouth] - mc
    half = max(float(np.abs(rel[:, 0]).max()), 1e-6)
    smile = np.zeros_like(rel)
    smile[:, 0] = rel[:, 0] * 0.3
    smile[:, 2] = 0.005 * (rel[:, 0] / half) ** 2
    move("happy", mouth, smile)
    open_ = np.zeros_like(rel)
    open_[:, 2] = rel[:, 2] * 1.6 - 0.002
    open_[:, 0] = -rel[:, 0] * 0.2
    move("surprised", mouth, open_)
    for brow in ("brow_r", "brow_l"):
        for name, up in (("happy", 0.002), ("surprised", 0.006)):
            b = where[brow]
            d = np.zeros((b.size, 3))
            d[:, 2] = up
            move(name, b, d)
    return {name: face_shape(parts_) for name, parts_ in shapes.items()}


def _torso(parts: _Parts, s: SegmentLengths, p: np.ndarray) -> None:
    pelvis = p[J["pelvis"]]
    low, chest, neck = p[J["lower_back"]], p[J["chest"]], p[J["neck"]]
    sh = s.shoulder_half_width
    top = chest[2] + s.chest_to_shoulder - pelvis[2]  # shoulder line above the pelvis
    k_lb = low[2] - pelvis[2]
    k_ch = chest[2] - pelvis[2]
    k_nk = neck[2] - pelvis[2]
    hw = s.hip_half_width

    def weights(z: np.ndarray) -> np.ndarray:
        return chain_weights(
            z,
            [J["pelvis"], J["lower_back"], J["chest"], J["neck"]],
            [(0.5 * k_lb + 0.02, 0.06), (0.5 * (k_lb + k_ch), 0.08), (k_nk + 0.01, 0.02)],
        )

    # rows: height above the pelvis, half-width, half-depth, x offset, y offset
    trousers = [
        (-0.10, hw + 0.045, 0.095, 0.0, 0.005),
        (-0.05, hw + 0.065, 0.11, 0.0, 0.01),
        (0.02, hw + 0.06, 0.105, 0.0, 0.01),
        (0.09, hw + 0.045, 0.10, 0.0, 0.012),
        (0.12, hw + 0.035, 0.095, 0.0, 0.012),
    ]
    rings, z = _sweep(trousers, pelvis, Z, X, Y, power=2.4, k=28, caps=(4, 0), depth=(0.35, 1.0))
    parts.tube(TROUSERS, rings, weights(z))
    f = top / 0.545
    shirt = [
        (0.075, hw + 0.052, 0.108, 0.0, 0.012),
        (0.085, hw + 0.05, 0.106, 0.0, 0.012),
        (0.18 * f, hw + 0.035, 0.098, 0.0, 0.018),
        (0.30 * f, sh - 0.04, 0.105, 0.0, 0.022),
        (0.40 * f, sh - 0.025, 0.112, 0.0, 0.02),
        (0.47 * f, sh - 0.005, 0.106, 0.0, 0.012),
        (top - 0.045, sh + 0.03, 0.096, 0.0, 0.006),
        (top - 0.01, sh + 0.032, 0.09, 0.0, 0.004),
        (top + 0.022, sh + 0.01, 0.08, 0.0, 0.0),
        (top + 0.042, sh - 0.045, 0.07, 0.0, 0.0),
        (top + 0.058, 0.09, 0.064, 0.0, 0.002),
        (top + 0.068, 0.068, 0.062, 0.0, 0.006),
    ]
    rings, z = _sweep(shirt, pelvis, Z, X, Y, power=2.6, k=30, caps=(0, 0))
    parts.tube(SHIRT, rings, _shoulder_blend(rings, weights(z), p, s))
    # the neck, from inside the collar to inside the skull
    head = p[J["head"]]
    nz0 = top - 0.04
    neck_rows = [
        (
            nz0 + t * (head[2] - pelvis[2] + 0.03 - nz0),
            0.058 - 0.008 * t,
            0.058 - 0.008 * t,
            0.0,
            0.005 + 0.01 * t,
        )
        for t in np.linspace(0, 1, 6)
    ]
    rings, z = _sweep(neck_rows, pelvis, Z, X, Y, k=16, caps=(0, 2))
    parts.tube(
        SKIN,
        rings,
        chain_weights(
            z, [J["chest"], J["neck"], J["head"]], [(k_nk, 0.025), (head[2] - pelvis[2], 0.03)]
        ),
    )


def _shoulder_blend(
    rings: np.ndarray, ring_w: np.ndarray, p: np.ndarray, s: SegmentLengths
) -> np.ndarray:
    """Per-vertex weights (R, K, N_JOINTS) of the upper torso: the outer shoulder follows
    the upper arm (up to half), so the deltoid bends with it instead of showing a seam."""
    w = np.repeat(ring_w[:, None, :], rings.shape[1], axis=1)
    for side, sign in (("r", 1.0), ("l", -1.0)):
        sh = J[f"{side}_shoulder"]
        x = rings[..., 0] * sign - (p[J["chest"], 0] * sign)
        z = rings[..., 2] - p[sh, 2]
        f = (
            0.85
            * _smooth(s.shoulder_half_width - 0.10, s.shoulder_half_width - 0.01, x)
            * _smooth(-0.19, -0.07, z)
            * (1.0 - 0.6 * _smooth(0.0, 0.04, z))
        )
        w *= (1.0 - f)[..., None]
        w[..., sh] += f
    return w


def _head_ring(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Half-width, half-depth and forward offset of the head at u in -1 (chin) .. 1 (crown)."""
    u = np.asarray(u, np.float64)
    round_ = np.sqrt(np.clip(1.0 - u * u, 0.0, 1.0))
    jaw = 1.0 - 0.28 * np.clip(-u - 0.1, 0.0, 1.0) ** 1.2
    a = 0.078 * round_ * jaw
    b = 0.099 * round_ * (1.0 - 0.12 * np.clip(-u - 0.2, 0.0, 1.0))
    y = 0.012 + 0.012 * np.clip(-u, 0.0, 1.0) - 0.008 * np.clip(u, 0, 1)
    return a, b, y


def _tilt(parts: _Parts, first: int, pivot: np.ndarray, angle: float) -> None:
    """Turn the parts from index ``first`` on about the x axis through ``pivot``."""
    rot = _rot_x(angle)
    for n in range(first, len(parts.parts)):
        material, pos, tri, w = parts.parts[n]
        parts.parts[n] = (material, (pos - pivot) @ rot.T + pivot, tri, w)


def _head(parts: _Parts, s: SegmentLengths, p: np.ndarray) -> None:
    h = J["head"]
    base, top = p[h], p[J["head_top"]]
    height = (top[2] - base[2]) + 0.095  # chin to crown
    zc = top[2] + 0.012 - height / 2
    half = height / 2
    u = np.concatenate([[-1.0], np.linspace(-0.97, 0.97, 24), [1.0]])
    a, b, y = _head_ring(u)
    rows = [(zc + half * ui, ai, bi, 0.0, yi) for ui, ai, bi, yi in zip(u, a, b, y, strict=True)]
    origin = np.array([base[0], base[1], 0.0])
    rings, _ = _sweep(rows, origin, Z, X, Y, power=2.15, k=26, caps=(0, 0))
    parts.tube(SKIN, rings, _one(h, rings.shape[0]))

    def front(uu: float, x: float) -> np.ndarray:
        aa, bb, yy = (float(v) for v in _head_ring(np.array(uu)))
        t = min(abs(x) / aa, 0.999)
        depth = bb * (1.0 - t**2.15) ** (1 / 2.15)
        return np.array([base[0] + x, base[1] + yy + depth, zc + half * uu])

    eye_u = 0.02
    for sign in (1.0, -1.0):
        x = 0.032 * sign
        c = front(eye_u, x) - np.array([0, 0.0085, 0])
        eye = "eye_r" if sign > 0 else "eye_l"
        _ellipsoid(parts, EYE_WHITE, c, (0.0138, 0.011, 0.0098), h)
        parts.tag(f"{eye}_white")
        # the eyes look down by the face's tilt (see FACE_TILT_RAD)
        gaze = _rot_x(-FACE_TILT_RAD - 0.05)
        _ellipsoid(
            parts, IRIS, c + gaze @ np.array([0, 0.0083, 0]), (0.0069, 0.0038, 0.0069), h, rot=gaze
        )
        parts.tag(f"{eye}_iris")
        _ellipsoid(
            parts, PUPIL, c + gaze @ np.array([0, 0.0108, 0]), (0.0031, 0.0018, 0.0031), h, rot=gaze
        )
        parts.tag(f"{eye}_pupil")
        brow = front(eye_u + 0.19, x * 1.05) - np.array([0, 0.002, 0])
        _ellipsoid(
            parts,
            HAIR,
            brow,
            (0.0185, 0.0055, 0.0048),
            h,
            rot=_rot_z(0.0) @ np.array([[1, 0, 0], [0, 1, 0], [-0.12 * sign, 0, 1]]),
        )
        parts.tag("brow_r" if sign > 0 else "brow_l")
        ear = np.array(
            [
                base[0] + sign * (float(_head_ring(np.array(eye_u - 0.1))[0]) + 0.002),
                base[1] + 0.004,
                zc + half * (eye_u - 0.1),
            ]
        )
        _ellipsoid(parts, SKIN, ear, (0.009, 0.017, 0.029), h, rot=_rot_z(-0.25 * sign))
    nose = front(eye_u - 0.22, 0.0) - np.array([0, 0.006, 0])
    _ellipsoid(parts, SKIN, nose, (0.0085, 0.013, 0.024), h, rot=_rot_x(-0.5))
    tip = front(eye_u - 0.36, 0.0) + np.array([0, 0.005, 0.0])
    _ellipsoid(parts, SKIN, tip, (0.0095, 0.0075, 0.0075), h)
    mouth = front(eye_u - 0.53, 0.0) - np.array([0, 0.0035, 0])
    _ellipsoid(parts, LIPS, mouth, (0.024, 0.0072, 0.0068), h)
    parts.tag("mouth")
    # hair: the skull pushed outward from its centre, from a hairline (low at the back, a
    # fringe in front) to the crown; each column of the grid starts at its own hairline
    theta = np.linspace(0.0, 2.0 * np.pi, 32, endpoint=False)
    sin_t, cos_t = np.sin(theta), np.cos(theta)
    line = np.where(
        sin_t > 0, 0.30 + 0.20 * sin_t**2 - 0.03 * np.cos(7 * theta) * sin_t, 0.30 + 0.85 * sin_t
    )
    t = np.linspace(0.0, 1.0, 14)[:, None]
    uu = line[None, :] + (1.0 - line[None, :]) * (1.0 - (1.0 - t) ** 1.5)
    a, b, y = _head_ring(uu)
    e = 2.0 / 2.15
    px = np.sign(cos_t) * np.abs(cos_t) ** e * a
    py = y + np.sign(sin_t) * np.abs(sin_t) ** e * b
    pz = half * uu
    centre = np.array([0.0, 0.01, 0.0])
    rel = np.stack([px, py, pz], axis=-1) - centre
    dist = np.linalg.norm(rel, axis=-1, keepdims=True)
    grow = 0.003 + 0.013 * np.clip((uu[..., None] - 0.2) / 0.6, 0.0, 1.0)
    pts = centre + rel * (1.0 + grow / np.maximum(dist, 1e-9))
    pts = pts + np.array([base[0], base[1], zc])
    parts.tube(HAIR, pts, _one(h, pts.shape[0]))


def _arm(parts: _Parts, s: SegmentLengths, p: np.ndarray, side: str, sign: float) -> None:
    sh, el, wr = J[f"{side}_shoulder"], J[f"{side}_elbow"], J[f"{side}_wrist"]
    origin = p[sh]
    ua, fa = s.upper_arm, s.forearm
    # s measured downward from the shoulder joint: rows (s, across, front-back, x, y)
    rows = [
        (-0.005, 0.045, 0.048, 0.0, 0.0),
        (0.06 * ua / 0.3, 0.046, 0.049, 0.0, 0.0),
        (0.14 * ua / 0.3, 0.044, 0.047, 0.0, 0.0),
        (0.24 * ua / 0.3, 0.039, 0.042, 0.0, 0.0),
        (ua, 0.037, 0.038, 0.0, 0.0),
        (ua + 0.06 * fa / 0.27, 0.041, 0.040, 0.0, 0.0),
        (ua + 0.15 * fa / 0.27, 0.036, 0.032, 0.0, 0.0),
        (ua + fa - 0.02, 0.029, 0.021, 0.0, 0.0),
        (ua + fa + 0.005, 0.028, 0.020, 0.0, 0.0),
    ]
    bounds = [(0.025, 0.06), (ua, 0.05), (ua + fa, 0.025)]
    joints = [J["chest"], sh, el, wr]
    # the bare arm starts inside the sleeve, so no skin shows at the shoulder
    rings, t = _sweep(rows[2:], origin, -Z, X * sign, Y, k=16, caps=(3, 2), depth=(0.5, 1.0))
    parts.tube(SKIN, rings, chain_weights(t, joints, bounds))
    sleeve = [(r[0], r[1] + 0.007, r[2] + 0.008, r[3], r[4]) for r in rows[:3]]
    end = sleeve[-1]
    sleeve.append((end[0] + 0.01, end[1] + 0.002, end[2] + 0.002, 0.0, 0.0))
    sleeve.append((end[0] + 0.012, end[1] - 0.012, end[2] - 0.012, 0.0, 0.0))
    rings, t = _sweep(sleeve, origin, -Z, X * sign, Y, k=16, caps=(3, 0), depth=(0.3, 1.0))
    parts.tube(SHIRT, rings, chain_weights(t, joints, bounds))


def _hand(parts: _Parts, s: SegmentLengths, p: np.ndarray, side: str, sign: float) -> None:
    """A fist round the stick. In the rest pose the stick runs along -z through the fulcrum
    (the ``*_stick`` joint), in line with the hand; the back of the hand faces +y (up while
    playing), four fingers wrap the stick below it, index at the fulcrum, pinky towards the
    wrist, and the thumb lies along the stick on the inner side, its tip at the fulcrum."""
    wr, st = J[f"{side}_wrist"], J[f"{side}_stick"]
    wrist, grip = p[wr], p[st]
    inner = -X * sign
    hand = wrist[2] - grip[2]
    palm = np.array([grip[0], grip[1] + 0.011, grip[2] + 0.52 * hand])
    _ellipsoid(
        parts, SKIN, palm - inner * 0.002, (0.027, 0.018, 0.5 * hand + 0.006), wr, k=14, rings=8
    )
    for f in range(4):
        z = grip[2] + 0.006 + (hand - 0.026) * f / 3.0
        w = np.zeros(N_JOINTS)
        w[st] = 0.9 - 0.2 * f
        w[wr] = 1.0 - w[st]
        major, minor = 0.0158, 0.0089 - 0.0005 * f
        # from the back of the hand (+y) round the outer side, under the stick (-y) and up
        # the inner side: 1.5 turns of a half circle
        ang = (
            np.linspace(0.5 * np.pi, -0.85 * np.pi, 8)
            if sign > 0
            else np.linspace(0.5 * np.pi, 1.85 * np.pi, 8)
        )
        path = np.column_stack(
            [grip[0] + major * np.cos(ang), grip[1] + major * np.sin(ang), np.full(ang.size, z)]
        )
        path[0, 1] += 0.006
        _tube_path(parts, SKIN, path, minor, w)
    thumb = np.array(
        [
            palm + inner * 0.02 + Y * 0.004 + Z * 0.012,
            grip + inner * 0.019 + Y * 0.004 + Z * 0.022,
            grip + inner * 0.012 - Y * 0.002 - Z * 0.002,
        ]
    )
    w = np.zeros(N_JOINTS)
    w[wr], w[st] = 0.3, 0.7
    _tube_path(parts, SKIN, thumb, 0.0098, w)


def _tube_path(
    parts: _Parts, material: int, path: np.ndarray, radius: float, weights: np.ndarray, k: int = 7
) -> None:
    """A round tube of ``radius`` along a polyline, with rounded ends, on one weight row."""
    d = np.gradient(path, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    helper = np.where(np.abs(d[:, 2:3]) < 0.9, Z, X)
    ex = np.cross(d, helper)
    ex /= np.linalg.norm(ex, axis=1, keepdims=True)
    ey = np.cross(d, ex)
    rings = [
        np.asarray(path[0] - d[0] * radius * 0.999)[None].repeat(k, 0),
        _ring(path[0] - d[0] * radius * 0.7, ex[0], ey[0], radius * 0.7, radius * 0.7, 2.0, k),
    ]
    for i in range(path.shape[0]):
        rings.append(_ring(path[i], ex[i], ey[i], radius, radius, 2.0, k))
    rings.append(
        _ring(path[-1] + d[-1] * radius * 0.7, ex[-1], ey[-1], radius * 0.7, radius * 0.7, 2.0, k)
    )
    rings.append(np.asarray(path[-1] + d[-1] * radius * 0.999)[None].repeat(k, 0))
    arr = np.stack(rings)
    parts.tube(material, arr, np.tile(weights, (arr.shape[0], 1)))


def _leg(parts: _Parts, s: SegmentLengths, p: np.ndarray, side: str, sign: float) -> None:
    hip, knee, ankle = J[f"{side}_hip"], J[f"{side}_knee"], J[f"{side}_ankle"]
    th, sn = s.thigh, s.shin
    rows = [
        (-0.02, 0.086, 0.092, 0.0, -0.005),
        (0.10 * th / 0.45, 0.082, 0.085, 0.0, 0.0),
        (0.25 * th / 0.45, 0.07, 0.072, 0.0, 0.0),
        (th - 0.04, 0.058, 0.060, 0.0, 0.0),
        (th + 0.02, 0.056, 0.058, 0.0, 0.0),
        (th + 0.10 * sn / 0.44, 0.057, 0.062, 0.0, -0.008),
        (th + 0.26 * sn / 0.44, 0.049, 0.052, 0.0, 0.0),
        (th + sn - 0.03, 0.052, 0.054, 0.0, 0.0),
        (th + sn + 0.01, 0.052, 0.054, 0.0, 0.0),
    ]
    bounds = [(-0.06, 0.03), (th, 0.06), (th + sn, 0.03)]
    rings, t = _sweep(rows, p[hip], -Z, X * sign, Y, k=18, caps=(5, 3))
    parts.tube(TROUSERS, rings, chain_weights(t, [J["pelvis"], hip, knee, ankle], bounds))


def _shoe(parts: _Parts, s: SegmentLengths, p: np.ndarray, side: str, sign: float) -> None:
    ankle = p[J[f"{side}_ankle"]]
    a = J[f"{side}_ankle"]
    foot = s.foot
    sole_z = ankle[2] - 0.075
    f = foot / 0.15
    # along +y from the heel: (y, half-width, half-height, x offset, height of the centre)
    rows = [
        (-0.06, 0.038, 0.050, 0.0, 0.052),
        (-0.02, 0.044, 0.062, 0.0, 0.063),
        (0.04 * f, 0.047, 0.048, 0.0, 0.050),
        (0.10 * f, 0.050, 0.034, 0.0, 0.036),
        (0.16 * f, 0.048, 0.027, 0.0, 0.029),
        (0.19 * f, 0.040, 0.024, 0.0, 0.026),
    ]
    origin = np.array([ankle[0], ankle[1], sole_z])
    rings, _ = _sweep(rows, origin, Y, X * sign, Z, power=3.0, k=18, caps=(3, 3))
    parts.tube(SHOES, rings, _one(a, rings.shape[0]))
    sole = [(r[0], r[1] + 0.004, 0.009, 0.0, 0.008) for r in rows]
    rings, _ = _sweep(sole, origin, Y, X * sign, Z, power=4.0, k=18, caps=(2, 2))
    parts.tube(SOLE, rings, _one(a, rings.shape[0]))
