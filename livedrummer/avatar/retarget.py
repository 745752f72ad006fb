"""An avatar's humanoid skeleton onto ours: frame, scale, proportions, bind matrices, weights.

Why this shape. The body moves one skeleton of 24 joints (:mod:`livedrummer.body.skeleton`),
built from :class:`SegmentLengths`; an avatar brings its own bones. Rather than animate the
avatar's bones, the avatar is bound once to *our* skeleton, sized to it:

1. **Frame.** The humanoid bones say where up (hips to head), left (right to left shoulders and
   hips) and so forward are; each is snapped to the nearest axis of the file, which covers glTF's
   +Y up, VRM 0.x facing -Z and VRM 1.0 (and plain glTF) facing +Z without trusting a flag, and
   keeps the avatar's own lean. Vertices and bones go into the kit frame (+x right, +y forward,
   +z up), feet on z = 0, centred under the hips.
2. **Scale.** glTF is in metres, but exporters leave centimetres or millimetres behind: a
   height of 30-350 units is read as centimetres, 350-3500 as millimetres; anything else
   outside 0.3-3.5 m is an error naming the height.
3. **Proportions.** Our joints are placed where the avatar's are, within our skeleton's shape
   (torso joints stacked over the pelvis, shoulders and hips level): elbows, wrists, knees and
   ankles land exactly on the avatar's, the grip fulcrum on the middle finger's knuckle (or
   30 % of a forearm past the wrist without fingers), the ball of the foot on the toe bone.
   The distances between them, left and right averaged, are the :class:`SegmentLengths` the
   IK uses, so *this* avatar's stick tips land on the drums. The stick stays 0.30 m (a prop).
4. **Bind.** ``bind[j]`` is our joint's world matrix in the avatar's bind pose: its position
   above, and the rotation that takes our rest bone direction (-z; the foot's +y) onto the
   avatar's bone, twisted so that our rest side (+x, the elbow's and knee's hinge) becomes
   ``direction x forward``: for a T-posed arm that is straight up, i.e. our rest pose lowers a
   T-pose's arms by swinging them down about the forward axis (palms to the thighs), and a
   bent elbow bends the mesh forward. Torso joints keep the avatar's own torso (identity).
5. **Weights.** Every avatar bone is replaced by its nearest mapped ancestor (hair and eyes by
   the head, a skirt by the hips, fingers and toes by the hand and foot, unparented meshes by
   the pelvis), duplicates summed, the four largest kept and renormalised.

Faces: a VRM's expressions (:mod:`~livedrummer.avatar.faces`) come along as face shapes,
turned and scaled like the vertices.

Fingers are curled around the grip before binding (the avatar's own skin, posed on its own
finger bones: proximal 75, middle 90, distal 60 degrees, the thumb less, towards the palm,
the palm found from the thumb's side), since they then ride on our wrist joint. Limits: a
symmetric body (left and right lengths averaged); no twist bones of our own (a forearm's
twist is the wrist's); the seat-to-hip height is the default's scaled by leg length.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from livedrummer.avatar.bonemap import FINGERS, SIDES, Humanoid
from livedrummer.avatar.faces import vrm_faces
from livedrummer.avatar.gltf import GltfScene
from livedrummer.avatar.model import MAX_INFLUENCES, Avatar, AvatarError, SkinnedMesh, face_shape
from livedrummer.avatar.skinning import joint_matrices
from livedrummer.body import quat
from livedrummer.body.skeleton import (
    BONE_REST_DIR,
    BONE_REST_SIDE,
    FOOT_REST_DIR,
    FOOT_REST_SIDE,
    N_JOINTS,
    J,
    SegmentLengths,
)

STICK_M = SegmentLengths().stick
FORWARD = np.array([0.0, 1.0, 0.0])
UP = np.array([0.0, 0.0, 1.0])
#: Finger curl (degrees) per bone of a finger chain, and of the thumb's.
CURL_DEG = (75.0, 90.0, 60.0)
THUMB_CURL_DEG = (20.0, 35.0, 30.0)
_DEFAULT = SegmentLengths()

#: Humanoid bone -> our joint (per side: VRM "right" is the drummer's right, +x).
_TORSO = {"hips": "pelvis", "spine": "lower_back", "chest": "chest", "neck": "neck", "head": "head"}
_LIMB = {
    "UpperArm": "shoulder",
    "LowerArm": "elbow",
    "Hand": "wrist",
    "UpperLeg": "hip",
    "LowerLeg": "knee",
    "Foot": "ankle",
}


@dataclass(frozen=True)
class Fitted:
    """What retargeting measured, for ``avatar info``."""

    height_m: float
    unit_scale: float  # file units -> metres
    facing: str  # which file axis the avatar faced, e.g. "-z"
    up: str
    curled_fingers: int


def _snap(basis: np.ndarray) -> np.ndarray:
    """Rows snapped to the nearest signed axes when they form a rotation; else orthonormalised."""
    snapped = np.zeros_like(basis)
    for i, row in enumerate(basis):
        k = int(np.argmax(np.abs(row)))
        snapped[i, k] = np.sign(row[k])
    if np.allclose(snapped @ snapped.T, np.eye(3)) and np.linalg.det(snapped) > 0:
        return snapped
    return basis


def _axis_name(v: np.ndarray) -> str:
    k = int(np.argmax(np.abs(v)))
    return ("-" if v[k] < 0 else "+") + "xyz"[k]


def _unit(v: np.ndarray) -> np.ndarray:
    out: np.ndarray = v / max(float(np.linalg.norm(v)), 1e-12)
    return out


def _frame(scene: GltfScene, human: Humanoid) -> tuple[np.ndarray, float, str, str]:
    """Rotation (3, 3) file -> kit frame, the unit scale, and the facing/up axes for info."""
    at = {b: scene.nodes[i].world[:3, 3] for b, i in human.bones.items()}
    up = at["head"] - at["hips"]
    left = (at["leftUpperArm"] + at["leftUpperLeg"]) - (at["rightUpperArm"] + at["rightUpperLeg"])
    if np.linalg.norm(up) < 1e-9 or np.linalg.norm(left) < 1e-9:
        raise AvatarError(f"{scene.source}: head on the hips or left on right: no body to measure")
    up = _unit(up)
    forward = _unit(np.cross(left, up))
    right = np.cross(forward, up)
    rot = _snap(np.stack([right, forward, up]))
    z = (scene.positions @ rot.T)[:, 2]
    bones = np.array([p @ rot[2] for p in at.values()])
    # the mesh's extent, or the bones' (head to foot is ~85 % of a height) if it is only a prop
    height = max(float(z.max() - z.min()), float(bones.max() - bones.min()) / 0.85)
    for lo, hi, unit in ((0.3, 3.5, 1.0), (30.0, 350.0, 0.01), (350.0, 3500.0, 0.001)):
        if lo <= height <= hi:
            return rot, unit, _axis_name(rot[1]), _axis_name(rot[2])
    raise AvatarError(
        f"{scene.source}: the avatar is {height:.4g} units tall: not a person in "
        "metres, centimetres or millimetres"
    )


def _curl(human: Humanoid, parents: np.ndarray, heads: np.ndarray) -> np.ndarray:
    """Per node, the 4x4 that curls the fingers towards the palm (identity elsewhere)."""
    n = heads.shape[0]
    local = np.tile(np.eye(4), (n, 1, 1))
    b = human.bones
    for side in SIDES:
        hand = b.get(f"{side}Hand")
        if hand is None:
            continue
        knuckle = b.get(f"{side}MiddleProximal")
        thumb = b.get(f"{side}ThumbProximal", b.get(f"{side}ThumbMetacarpal"))
        h_dir = _unit(heads[knuckle] - heads[hand]) if knuckle is not None else None
        if h_dir is None:
            continue
        if thumb is not None:
            t = heads[thumb] - heads[hand]
            t = t - (t @ h_dir) * h_dir
            palm = _unit(np.cross(h_dir, t)) * (-1.0 if side == "right" else 1.0)
        else:
            palm = _unit(-UP - (-UP @ h_dir) * h_dir)
        for finger in FINGERS:
            parts = (
                ("Metacarpal", "Proximal", "Distal")
                if finger == "Thumb"
                else ("Proximal", "Intermediate", "Distal")
            )
            angles = THUMB_CURL_DEG if finger == "Thumb" else CURL_DEG
            chain = [b.get(f"{side}{finger}{p}") for p in parts]
            for k, node in enumerate(chain):
                if node is None:
                    continue
                nxt = next((c for c in chain[k + 1 :] if c is not None), None)
                prev = parents[node]
                direction = (
                    heads[nxt] - heads[node] if nxt is not None else heads[node] - heads[prev]
                )
                if np.linalg.norm(direction) < 1e-9:
                    continue
                axis = _unit(np.cross(_unit(direction), palm))
                if finger == "Thumb":
                    axis = _unit(np.cross(_unit(direction), palm) + 0.5 * h_dir)
                r = quat.to_matrix(quat.from_axis_angle(axis, np.radians(angles[k])))
                m = np.eye(4)
                m[:3, :3] = r
                m[:3, 3] = heads[node] - r @ heads[node]
                local[node] = m
    # compose down the tree (a node's curl is about its head, then its parent's carries it)
    world = local.copy()
    order = sorted(range(n), key=lambda i: _depth(parents, i))
    for i in order:
        if parents[i] >= 0:
            world[i] = world[parents[i]] @ local[i]
    return world


def _depth(parents: np.ndarray, i: int) -> int:
    d = 0
    while parents[i] >= 0 and d <= parents.size:
        i = int(parents[i])
        d += 1
    return d


def _head_top(pos: np.ndarray, head_z: float, shoulder_z: float) -> float:
    """The top of the head: the mesh's highest point, or, where the mesh does not reach above
    the head bone (a prop, not a body), the default's skull scaled by the neck's length."""
    top = float(pos[:, 2].max())
    if top > head_z + 0.02:
        return top
    return head_z + _DEFAULT.head_top * (head_z - shoulder_z) / (
        _DEFAULT.neck + _DEFAULT.head - _DEFAULT.chest_to_shoulder
    )


def retarget(scene: GltfScene, human: Humanoid, name: str) -> tuple[Avatar, Fitted]:
    """The avatar bound to our skeleton (see the module docstring)."""
    src = scene.source
    rot, unit, facing, up_axis = _frame(scene, human)
    parents = np.array([node.parent for node in scene.nodes], np.int64)
    heads_file = np.array([node.world[:3, 3] for node in scene.nodes]).reshape(-1, 3)
    pos = (scene.positions @ rot.T) * unit
    nrm = scene.normals @ rot.T
    heads = (heads_file @ rot.T) * unit
    hips0 = heads[human.bones["hips"]]
    origin = np.array([hips0[0], hips0[1], pos[:, 2].min()])
    pos -= origin
    heads -= origin
    # fingers curled on the avatar's own skin
    curl = _curl(human, parents, heads)
    curled = int(sum(not np.allclose(c, np.eye(4)) for c in curl))
    if curled:
        m = np.einsum("vk,vkij->vij", scene.weights, curl[scene.bones])
        pos = np.einsum("vij,vj->vi", m[:, :3, :3], pos) + m[:, :3, 3]
        nrm = np.einsum("vij,vj->vi", m[:, :3, :3], nrm)
        nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
    lengths, bind, node_joint = _fit(scene, human, heads, pos, parents)
    joints, weights = _remap(scene.bones, scene.weights, node_joint)
    mesh = SkinnedMesh(
        positions=pos.astype(np.float32),
        normals=nrm.astype(np.float32),
        uv=scene.uv,
        joints=joints,
        weights=weights,
        indices=scene.indices,
        primitives=scene.primitives,
        materials=scene.materials,
        bind=bind,
    )
    mesh.check(src)
    bones = {our: scene.nodes[human.bones[b]].name for b, our in _mapping(human).items()}
    height = float(pos[:, 2].max() - pos[:, 2].min())
    # the VRM's expressions, turned and scaled as the vertices (the fingers' curl is no face's)
    faces = {k: face_shape([(idx, (d @ rot.T) * unit)]) for k, (idx, d) in vrm_faces(scene).items()}
    avatar = Avatar(name, src, lengths, mesh, bones, faces=faces)
    return avatar, Fitted(height, unit, facing, up_axis, curled)


def _mapping(human: Humanoid) -> dict[str, str]:
    """Humanoid bone -> our joint, for the bones this avatar has."""
    out = {b: j for b, j in _TORSO.items() if b in human.bones}
    if "chest" not in human.bones and "upperChest" in human.bones:
        out["upperChest"] = "chest"
    for side in SIDES:
        for limb, joint in _LIMB.items():
            if f"{side}{limb}" in human.bones:
                out[f"{side}{limb}"] = f"{side[0]}_{joint}"
    return out


def _fit(
    scene: GltfScene, human: Humanoid, heads: np.ndarray, pos: np.ndarray, parents: np.ndarray
) -> tuple[SegmentLengths, np.ndarray, np.ndarray]:
    src = scene.source
    b = human.bones

    def at(bone: str) -> np.ndarray:
        out: np.ndarray = heads[b[bone]]
        return out

    shoulder_z = (at("leftUpperArm")[2] + at("rightUpperArm")[2]) / 2
    hz, sz, head_z = at("hips")[2], at("spine")[2], at("head")[2]
    chest_bone = "chest" if "chest" in b else "upperChest" if "upperChest" in b else None
    chest_z = at(chest_bone)[2] if chest_bone else sz + 0.52 * (shoulder_z - sz)
    if chest_z >= shoulder_z:
        chest_z = sz + 0.52 * (shoulder_z - sz)
    neck_z = at("neck")[2] if "neck" in b else shoulder_z + 0.25 * (head_z - shoulder_z)
    top_z = _head_top(pos, head_z, shoulder_z)
    torso = {
        "lower_back": sz - hz, "upper_back": chest_z - sz,
        "chest_to_shoulder": shoulder_z - chest_z,
        "neck": neck_z - chest_z, "head": head_z - neck_z, "head_top": top_z - head_z,
    }  # fmt: skip
    for seg, value in torso.items():
        if not value > 0.005:
            raise AvatarError(
                f"{src}: the bones do not stack up the torso: segment {seg} is "
                f"{value * 1000:.0f} mm (spine above hips, neck above chest, "
                "head above neck?)"
            )
    half_w = abs(at("rightUpperArm")[0] - at("leftUpperArm")[0]) / 2
    hip_w = abs(at("rightUpperLeg")[0] - at("leftUpperLeg")[0]) / 2
    hip_f = max(0.005, (at("rightUpperLeg")[1] + at("leftUpperLeg")[1]) / 2 - at("hips")[1])
    p = np.zeros((N_JOINTS, 3))
    rq = np.tile([1.0, 0.0, 0.0, 0.0], (N_JOINTS, 1))
    p[J["pelvis"]] = at("hips")
    p[J["lower_back"]] = p[J["pelvis"]] + (0, 0, torso["lower_back"])
    p[J["chest"]] = p[J["lower_back"]] + (0, 0, torso["upper_back"])
    p[J["neck"]] = p[J["chest"]] + (0, 0, torso["neck"])
    p[J["head"]] = p[J["neck"]] + (0, 0, torso["head"])
    p[J["head_top"]] = p[J["head"]] + (0, 0, torso["head_top"])
    arm: dict[str, list[float]] = {"upper_arm": [], "forearm": [], "hand": []}
    leg: dict[str, list[float]] = {"thigh": [], "shin": [], "foot": []}
    dirs: dict[str, np.ndarray] = {}
    for side, sign in (("right", 1.0), ("left", -1.0)):
        s = side[0]
        shoulder = p[J["chest"]] + (sign * half_w, 0.0, torso["chest_to_shoulder"])
        elbow, wrist = at(f"{side}LowerArm"), at(f"{side}Hand")
        knuckle = b.get(f"{side}MiddleProximal")
        if knuckle is not None and np.linalg.norm(heads[knuckle] - wrist) > 0.01:
            grip = heads[knuckle]
        else:
            grip = wrist + 0.3 * (wrist - elbow)
        arm["upper_arm"].append(float(np.linalg.norm(elbow - shoulder)))
        arm["forearm"].append(float(np.linalg.norm(wrist - elbow)))
        arm["hand"].append(float(np.linalg.norm(grip - wrist)))
        dirs[f"{s}_shoulder"] = _unit(elbow - shoulder)
        dirs[f"{s}_elbow"] = _unit(wrist - elbow)
        dirs[f"{s}_wrist"] = _unit(grip - wrist)
        hip = p[J["pelvis"]] + (sign * hip_w, hip_f, 0.0)
        knee, ankle = at(f"{side}LowerLeg"), at(f"{side}Foot")
        toes = b.get(f"{side}Toes")
        if toes is not None and np.linalg.norm(heads[toes] - ankle) > 0.02:
            ball = heads[toes]
        else:
            ball = _ball_of_foot(scene, b[f"{side}Foot"], parents, pos, ankle)
        leg["thigh"].append(float(np.linalg.norm(knee - hip)))
        leg["shin"].append(float(np.linalg.norm(ankle - knee)))
        leg["foot"].append(float(np.linalg.norm(ball - ankle)))
        dirs[f"{s}_hip"] = _unit(knee - hip)
        dirs[f"{s}_knee"] = _unit(ankle - knee)
        dirs[f"{s}_ankle"] = _unit(ball - ankle)
    mean = {k: float(np.mean(v)) for k, v in {**arm, **leg}.items()}
    legs_ratio = (mean["thigh"] + mean["shin"]) / (_DEFAULT.thigh + _DEFAULT.shin)
    try:
        lengths = SegmentLengths(
            pelvis_height=_DEFAULT.pelvis_height * legs_ratio,
            lower_back=torso["lower_back"],
            upper_back=torso["upper_back"],
            chest_to_shoulder=torso["chest_to_shoulder"],
            shoulder_half_width=half_w,
            neck=torso["neck"],
            head=torso["head"],
            head_top=torso["head_top"],
            upper_arm=mean["upper_arm"],
            forearm=mean["forearm"],
            hand=mean["hand"],
            stick=STICK_M,
            hip_half_width=hip_w,
            hip_forward=hip_f,
            thigh=mean["thigh"],
            shin=mean["shin"],
            foot=mean["foot"],
        )
        lengths = SegmentLengths(**{f: float(getattr(lengths, f)) for f in lengths.__slots__})
        lengths.check()
    except ValueError as exc:
        raise AvatarError(f"{src}: proportions out of range: {exc}") from exc
    # our joints in the bind pose: FK along the avatar's bone directions with our lengths
    for side, sign in (("r", 1.0), ("l", -1.0)):
        p[J[f"{side}_shoulder"]] = p[J["chest"]] + (sign * half_w, 0.0, torso["chest_to_shoulder"])
        chain = (
            (f"{side}_shoulder", f"{side}_elbow", lengths.upper_arm),
            (f"{side}_elbow", f"{side}_wrist", lengths.forearm),
            (f"{side}_wrist", f"{side}_stick", lengths.hand),
            (f"{side}_stick", f"{side}_tip", lengths.stick),
        )
        for joint, child, length in chain:
            d = dirs.get(joint, dirs[f"{side}_wrist"])
            rq[J[joint]] = _aim(BONE_REST_DIR, BONE_REST_SIDE, d)
            p[J[child]] = p[J[joint]] + length * d
        rq[J[f"{side}_tip"]] = rq[J[f"{side}_stick"]]
        p[J[f"{side}_hip"]] = p[J["pelvis"]] + (sign * hip_w, hip_f, 0.0)
        for joint, child, length in (
            (f"{side}_hip", f"{side}_knee", lengths.thigh),
            (f"{side}_knee", f"{side}_ankle", lengths.shin),
        ):
            rq[J[joint]] = _aim(BONE_REST_DIR, BONE_REST_SIDE, dirs[joint])
            p[J[child]] = p[J[joint]] + length * dirs[joint]
        foot = dirs[f"{side}_ankle"]
        rq[J[f"{side}_ankle"]] = quat.align(
            FOOT_REST_DIR, FOOT_REST_SIDE, foot, _unit(np.cross(foot, UP))
        )
        rq[J[f"{side}_toe"]] = rq[J[f"{side}_ankle"]]
        p[J[f"{side}_toe"]] = p[J[f"{side}_ankle"]] + lengths.foot * foot
    bind = joint_matrices(rq, p).astype(np.float32)
    # every node's joint: its nearest mapped ancestor (or itself), else the pelvis
    mapped = {b[bone]: J[joint] for bone, joint in _mapping(human).items()}
    node_joint = np.full(parents.size, J["pelvis"], np.int64)
    for i in range(parents.size):
        k, steps = i, 0
        while k >= 0 and k not in mapped and steps <= parents.size:
            k, steps = int(parents[k]), steps + 1
        if k >= 0 and k in mapped:
            node_joint[i] = mapped[k]
    return lengths, bind, node_joint


def _aim(rest_dir: np.ndarray, rest_side: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Our rest bone onto ``direction``, its side onto ``direction x forward`` (see above)."""
    side = np.cross(direction, FORWARD)
    if np.linalg.norm(side) < 1e-6:  # a bone pointing straight forward or back
        side = np.cross(direction, UP)
    q: np.ndarray = quat.align(rest_dir, rest_side, direction, _unit(side))
    return q


def _ball_of_foot(
    scene: GltfScene, foot: int, parents: np.ndarray, pos: np.ndarray, ankle: np.ndarray
) -> np.ndarray:
    """Without a toe bone: 75 % of the way to the front of the foot's vertices, near the sole."""
    under = np.zeros(parents.size, bool)
    for i in range(parents.size):
        k = i
        while k >= 0 and k != foot:
            k = int(parents[k])
        under[i] = k == foot
    main = scene.bones[np.arange(scene.bones.shape[0]), np.argmax(scene.weights, axis=1)]
    mine = under[main]
    if not mine.any():
        raise AvatarError(
            f"{scene.source}: no toe bone and no vertices on the foot "
            f"{scene.nodes[foot].name!r} to measure it by"
        )
    fp = pos[mine]
    front = float(fp[:, 1].max())
    sole = float(fp[:, 2].min())
    return np.array(
        [ankle[0], ankle[1] + 0.75 * (front - ankle[1]), sole + 0.35 * (ankle[2] - sole)]
    )


def _remap(
    bones: np.ndarray, weights: np.ndarray, node_joint: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per vertex: our joints (V, 4) uint16 and weights (V, 4) float32 summing to 1."""
    v = bones.shape[0]
    dense = np.zeros((v, N_JOINTS))
    ours = node_joint[bones]
    rows = np.repeat(np.arange(v), bones.shape[1])
    np.add.at(dense, (rows, ours.reshape(-1)), weights.reshape(-1))
    top = np.argsort(-dense, axis=1, kind="stable")[:, :MAX_INFLUENCES]
    w = np.take_along_axis(dense, top, axis=1)
    total = w.sum(axis=1, keepdims=True)
    empty = total[:, 0] <= 1e-12
    w[empty] = (1.0, 0.0, 0.0, 0.0)
    top[empty] = J["pelvis"]
    w /= np.maximum(w.sum(axis=1, keepdims=True), 1e-12)
    top = np.where(w > 0, top, 0)  # an unused influence names joint 0, as glTF asks
    return top.astype(np.uint16), w.astype(np.float32)
