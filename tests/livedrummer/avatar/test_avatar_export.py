"""``export --format gltf``: the avatar and its motion as a .glb, read back with pygltflib.

The re-import is independent of our reader: pygltflib parses the file, numpy reads its
accessors, and the skinned vertices at a frame (glTF's ``world(joint) @ inverseBindMatrix``
with the animation's values) are compared with our own skinning of the same pose.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import avatar_files as af
import numpy as np
import pygltflib
import pytest

from livedrummer.avatar.gltf_export import KIT_TO_GLTF, performance_glb
from livedrummer.avatar.loader import load_avatar_file
from livedrummer.avatar.skinning import joint_matrices, skin, skin_matrices
from livedrummer.body import quat
from livedrummer.body.fk import forward
from livedrummer.body.skeleton import LEAVES, N_JOINTS, build_skeleton

_DT = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}
_W = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def read(g: pygltflib.GLTF2, index: int) -> np.ndarray:
    acc = g.accessors[index]
    view = g.bufferViews[acc.bufferView]
    blob = g.binary_blob()
    n = _W[acc.type]
    out = np.frombuffer(
        blob, _DT[acc.componentType], acc.count * n, (view.byteOffset or 0) + (acc.byteOffset or 0)
    )
    return out.reshape(acc.count, n)


def trs(
    node: pygltflib.Node, t: np.ndarray | None = None, r: np.ndarray | None = None
) -> np.ndarray:
    m = np.eye(4)
    rot = r if r is not None else np.asarray(node.rotation or [0, 0, 0, 1.0])
    x, y, z, w = rot
    m[:3, :3] = quat.to_matrix(np.array([w, x, y, z]))
    m[:3, 3] = t if t is not None else (node.translation or [0, 0, 0])
    return m


def test_exported_skin_matches_our_skinning(tmp_path: Path) -> None:
    avatar = load_avatar_file(af.write(tmp_path, "vrm0.vrm"))
    sk = build_skeleton(avatar.lengths)
    rng = np.random.default_rng(4)
    times = np.array([0.0, 0.5, 1.0])
    local = quat.exp(rng.normal(0, 0.4, (3, N_JOINTS, 3)))
    root = sk.root_m + rng.normal(0, 0.02, (3, 3))
    g = pygltflib.GLTF2.load_from_bytes(performance_glb(avatar, sk, times, local, root))
    skin_ = g.skins[0]
    assert len(skin_.joints) == N_JOINTS
    anim = g.animations[0]
    assert len(anim.channels) == N_JOINTS - len(LEAVES) + 1
    clock = read(g, anim.samplers[0].input)[:, 0]
    assert clock.tolist() == times.tolist() and g.accessors[anim.samplers[0].input].max == [1.0]
    k = 1  # the middle frame, from the animation's own values
    values: dict[tuple[int, str], np.ndarray] = {}
    for ch in anim.channels:
        values[(ch.target.node, ch.target.path)] = read(g, anim.samplers[ch.sampler].output)[k]
    world = {}
    for i in [g.scenes[0].nodes[0]]:  # walk from the root
        stack = [(i, np.eye(4))]
        while stack:
            n, parent = stack.pop()
            node = g.nodes[n]
            m = parent @ trs(node, values.get((n, "translation")), values.get((n, "rotation")))
            world[n] = m
            stack.extend((c, m) for c in node.children or [])
    ibm = read(g, skin_.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
    joint_m = np.stack([world[j] for j in skin_.joints]) @ ibm
    prim = g.meshes[0].primitives[0]
    pos = read(g, prim.attributes.POSITION).astype(np.float64)
    joints = read(g, prim.attributes.JOINTS_0).astype(int)
    weights = read(g, prim.attributes.WEIGHTS_0).astype(np.float64)
    m = np.einsum("vk,vkij->vij", weights, joint_m[joints])
    theirs = np.einsum("vij,vj->vi", m[:, :3, :3], pos) + m[:, :3, 3]
    wq, wp = forward(sk, local[k : k + 1], root[k : k + 1])
    ours, _ = skin(avatar.mesh, skin_matrices(joint_matrices(wq[0], wp[0]), avatar.mesh.bind))
    assert np.abs(theirs - ours @ KIT_TO_GLTF.T).max() < 1e-4
    # the texture and the toon material came along
    assert len(g.images) == 1 and g.materials[1].extensions == {"KHR_materials_unlit": {}}


def test_kit_moves_as_the_renderer_moves_it(tmp_path: Path) -> None:
    from livedrummer.kit.loader import load_kit
    from livedrummer.render.kitmesh import build_kit_mesh
    from livedrummer.render.scene import N_CHANNELS

    avatar = load_avatar_file(af.write(tmp_path, "short.glb"))
    sk = build_skeleton(avatar.lengths)
    kit = build_kit_mesh(load_kit("rock5"), floor=False)
    rng = np.random.default_rng(9)
    t = 4
    channels = rng.uniform(-0.2, 0.2, (t, kit.pieces, N_CHANNELS))
    local = np.tile([1.0, 0, 0, 0], (t, N_JOINTS, 1))
    root = np.tile(sk.root_m, (t, 1))
    data = performance_glb(avatar, sk, np.arange(t) / 10.0, local, root, kit, channels)
    g = pygltflib.GLTF2.load_from_bytes(data)
    anim = g.animations[0]
    k = 2
    values = {
        (c.target.node, c.target.path): read(g, anim.samplers[c.sampler].output)[k]
        for c in anim.channels
    }
    movers = [i for i, n in enumerate(g.nodes) if n.name.endswith(" motion")]
    assert movers
    expect = kit.instances(channels[k])[:, :16].reshape(-1, 4, 4).transpose(0, 2, 1)
    for n in movers:
        node = g.nodes[n]
        placed = g.nodes[node.children[0]]
        index = int(placed.name.split()[1])
        motion = trs(node, values[(n, "translation")], values[(n, "rotation")])
        model = motion @ np.asarray(placed.matrix).reshape(4, 4).T
        assert np.abs(model - expect[index]).max() < 1e-5, placed.name


def test_export_cli_writes_a_glb_a_player_can_read(groove_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "show.glb"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "export",
            str(groove_dir / "drummer1/session1/1_funk_80_beat_4-4.mid"),
            "--map",
            "roland-td",
            "-o",
            str(out),
            "--fps",
            "30",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    frames = int(proc.stdout.split(": ")[1].split()[0])
    g = pygltflib.GLTF2.load(str(out))
    assert len(g.skins[0].joints) == N_JOINTS
    clock = g.accessors[g.animations[0].samplers[0].input]
    assert clock.count == frames and clock.max[0] == pytest.approx((frames - 1) / 30, abs=1e-4)
    assert g.meshes[0].primitives and {n.name for n in g.nodes} >= {"r_stick_geo", "pelvis"}
    assert any(n.name.startswith("kit ") and n.mesh is not None for n in g.nodes)
    assert len(g.animations[0].channels) > N_JOINTS - len(LEAVES) + 1  # cymbals, hi-hat, beater
    bad = subprocess.run(
        [
            sys.executable,
            "-m",
            "services",
            "export",
            str(groove_dir / "drummer1/session1/1_funk_80_beat_4-4.mid"),
            "-o",
            str(tmp_path / "x.gltf"),
            "--format",
            "gltf",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert bad.returncode == 2 and "name the file .glb" in bad.stderr
