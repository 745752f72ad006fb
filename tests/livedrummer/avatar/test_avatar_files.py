"""Avatar files onto the body: bone maps, frame and scale, proportions, binding, bad files.

Every avatar here is written by :mod:`tests.avatar_files` (pygltflib), read back by
:mod:`livedrummer.avatar`, and checked through the numpy skinning reference.
"""

from __future__ import annotations

import json
from pathlib import Path

import avatar_files as af
import numpy as np
import pytest

from livedrummer.avatar.bonemap import BoneMapError
from livedrummer.avatar.gltf import parse_gltf, read_gltf_file
from livedrummer.avatar.loader import inspect_avatar, load_avatar, load_avatar_file
from livedrummer.avatar.model import Avatar, AvatarError
from livedrummer.avatar.skinning import joint_matrices, skin, skin_matrices
from livedrummer.body import quat
from livedrummer.body.fk import forward
from livedrummer.body.rig import build_rig
from livedrummer.body.skeleton import N_JOINTS, J, build_skeleton
from livedrummer.errors import UnreachableError
from livedrummer.kit.loader import load_kit


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    return af.write_all(tmp_path_factory.mktemp("avatars"))


@pytest.fixture(scope="module")
def avatars(files: dict[str, Path]) -> dict[str, Avatar]:
    return {name: load_avatar_file(path) for name, path in files.items()}


def posed(avatar: Avatar, local: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Skinned vertices and joint positions in ``local`` (default: our rest pose)."""
    sk = build_skeleton(avatar.lengths)
    if local is None:
        local = np.tile([1.0, 0, 0, 0], (1, N_JOINTS, 1))
    wq, wp = forward(sk, local, sk.root_m[None])
    out, _ = skin(avatar.mesh, skin_matrices(joint_matrices(wq[0], wp[0]), avatar.mesh.bind))
    return out, wp[0]


def main_joint(avatar: Avatar, name: str) -> np.ndarray:
    return np.asarray(avatar.mesh.joints[:, 0] == J[name])


@pytest.mark.parametrize(
    ("name", "convention"),
    [("short.glb", "Blender/Rigify"), ("tall.glb", "Unreal"), ("vrm0.vrm", "VRM 0.x"),
     ("vrm1.vrm", "VRM 1.0"), ("rigid.glb", "Blender/Rigify"), ("mixamo.glb", "Mixamo")],
)  # fmt: skip
def test_each_convention_maps_every_joint(
    files: dict[str, Path], name: str, convention: str
) -> None:
    info = inspect_avatar(files[name])
    assert info.error == "" and info.convention == convention
    assert info.avatar is not None
    mapped = info.avatar.bones
    for ours in (
        "pelvis",
        "lower_back",
        "chest",
        "neck",
        "head",
        "r_shoulder",
        "r_elbow",
        "r_wrist",
        "l_hip",
        "l_knee",
        "l_ankle",
    ):
        assert ours in mapped
    # VRM "right" is the drummer's right (+x): the right wrist came from the right hand
    assert af.node_name("rightHand", af.AVATARS[name].naming) == mapped["r_wrist"]
    assert "Hair_01" not in mapped.values()  # no counterpart: weighted to the head


@pytest.mark.parametrize("name", list(af.AVATARS))
def test_rest_pose_hangs_the_arms_and_faces_forward(avatars: dict[str, Avatar], name: str) -> None:
    a = avatars[name]
    verts, joints = posed(a)
    for side, sign in (("r", 1.0), ("l", -1.0)):
        hand = verts[main_joint(a, f"{side}_wrist")]
        shoulder = joints[J[f"{side}_shoulder"]]
        assert hand.size
        # straight down under the shoulder (a T- or A-pose arm swung down), on its own side
        assert hand[:, 2].max() < shoulder[2] - 0.9 * (a.lengths.upper_arm + a.lengths.forearm)
        assert abs(hand[:, 0].mean() - shoulder[0]) < 0.06
        assert sign * hand[:, 0].mean() > 0.05
        forearm = verts[main_joint(a, f"{side}_elbow")]
        assert abs(forearm[:, 0].mean() - shoulder[0]) < 0.05
    k = af.AVATARS[name].height_m / af.HEIGHT_M
    head = verts[main_joint(a, "head")] - joints[J["head"]]
    face = head[(head[:, 2] > 0.03 * k) & (head[:, 2] < 0.07 * k)]  # at the nose's height
    # the nose sticks out of the 0.18 m head box at the front (+y), nothing at the back
    assert face[:, 1].max() > 0.095 * k and face[:, 1].min() > -0.095 * k
    assert np.abs(face[:, 0]).max() < 0.095 * k
    # feet forward: the toes' vertices in front of the ankle, near the floor
    toes = verts[main_joint(a, "r_ankle")]
    assert toes[:, 1].max() > joints[J["r_ankle"], 1] + 0.1


@pytest.mark.parametrize("name", ["short.glb", "vrm0.vrm"])
def test_a_bent_elbow_bends_the_mesh_forward(avatars: dict[str, Avatar], name: str) -> None:
    a = avatars[name]
    local = np.tile([1.0, 0, 0, 0], (1, N_JOINTS, 1))
    local[0, J["r_elbow"]] = quat.from_axis_angle(np.array([1.0, 0, 0]), np.radians(90.0))
    rest, _ = posed(a)
    bent, joints = posed(a, local)
    fore = main_joint(a, "r_elbow") | main_joint(a, "r_wrist")
    elbow = joints[J["r_elbow"]]
    moved = bent[fore] - elbow
    # the forearm and hand now point forward (+y), level with the elbow
    assert np.median(moved[:, 1]) > 0.1 and np.abs(np.median(moved[:, 2])) < 0.06
    upper = main_joint(a, "r_shoulder")
    assert np.allclose(bent[upper], rest[upper], atol=1e-5)


def test_proportions_are_the_avatars_own(avatars: dict[str, Avatar]) -> None:
    for name in ("short.glb", "tall.glb", "rigid.glb"):
        k = af.AVATARS[name].height_m / af.HEIGHT_M
        s = avatars[name].lengths
        assert s.upper_arm == pytest.approx(0.29 * k, abs=1e-5)
        assert s.forearm == pytest.approx(0.26 * k, abs=1e-5)
        assert s.hand == pytest.approx(0.09 * k, abs=1e-5)  # wrist to the middle knuckle
        assert s.shoulder_half_width == pytest.approx(0.18 * k, abs=1e-5)
        # our hip is level with the pelvis (and a few mm forward of it), the knee the avatar's
        assert s.thigh == pytest.approx(np.hypot(0.45 * k, 0.01 * k - s.hip_forward), abs=1e-5)
        assert s.shin == pytest.approx(np.hypot(0.42, 0.01) * k, abs=1e-5)
        assert s.stick == pytest.approx(0.30)  # a prop, not the body
    assert avatars["tall.glb"].lengths.shin / avatars["short.glb"].lengths.shin == (
        pytest.approx(1.95 / 1.55)
    )


def test_facing_and_scale_are_found(files: dict[str, Path]) -> None:
    facing = {n: inspect_avatar(files[n]).fitted for n in ("vrm0.vrm", "vrm1.vrm", "mixamo.glb")}
    assert facing["vrm0.vrm"] is not None and facing["vrm0.vrm"].facing == "-z"
    assert facing["vrm1.vrm"] is not None and facing["vrm1.vrm"].facing == "+z"
    mixamo = facing["mixamo.glb"]
    assert mixamo is not None and mixamo.unit_scale == 0.01  # written in centimetres
    assert mixamo.height_m == pytest.approx(1.72, abs=0.06)
    for f in facing.values():
        assert f is not None and f.up == "+y"


def test_mesh_skins_materials_and_textures(
    avatars: dict[str, Avatar], files: dict[str, Path]
) -> None:
    scene = read_gltf_file(files["vrm1.vrm"])
    assert scene.textures == 1
    a = avatars["vrm1.vrm"]
    mats = {m.name: m for m in a.mesh.materials}
    assert mats["cloth"].texture is not None and mats["cloth"].texture.shape == (4, 4, 4)
    assert mats["cloth"].texture[0, 0].tolist() == [10, 20, 30, 255]  # row 0 at the top
    assert mats["skin"].shading == "toon" and mats["cloth"].shading == "lit"  # MToon
    assert mats["hair"].alpha_mode == "MASK" and mats["hair"].alpha_cutoff == pytest.approx(0.4)
    assert avatars["vrm0.vrm"].mesh.materials[1].shading == "toon"  # VRM 0.x materialProperties
    assert len(a.mesh.primitives) == 3  # two skins: body (cloth), face (skin, hair)
    assert a.mesh.weights.sum(axis=1) == pytest.approx(1.0, abs=1e-5)
    # the hair bone has no counterpart: its vertices follow the head
    hair = next(p for p in a.mesh.primitives if a.mesh.materials[p.material].name == "hair")
    idx = a.mesh.indices[hair.first : hair.first + hair.count]
    assert set(a.mesh.joints[idx, 0].tolist()) == {J["head"]}


def test_fingers_are_curled_towards_the_palm(
    files: dict[str, Path], avatars: dict[str, Avatar]
) -> None:
    a = avatars["short.glb"]
    verts, joints = posed(a)
    k = af.AVATARS["short.glb"].height_m / af.HEIGHT_M
    fingers = verts[main_joint(a, "r_wrist")]
    wrist = joints[J["r_wrist"]]
    # straight, the middle finger would reach 0.18 * k below the wrist; curled it does not
    assert wrist[2] - fingers[:, 2].min() < 0.16 * k
    # ... they close towards the palm, which hangs facing the thigh (-x for the right hand)
    assert (fingers[:, 0] - wrist[0]).min() < -0.035 * k
    assert (fingers[:, 0] - wrist[0]).max() < 0.04 * k  # the palm box, nothing outward


def test_reach_error_names_piece_limb_and_shortfall(tmp_path: Path) -> None:
    child = load_avatar_file(af.write(tmp_path, "child.glb", af.Spec(height_m=0.9, vrm="1")))
    with pytest.raises(UnreachableError, match=r"out of reach of the .* by \d+ mm"):
        build_rig(load_kit("rock5"), child.lengths)


def test_names_and_user_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LIVEDRUMMER_HOME", str(tmp_path))
    (tmp_path / "avatars").mkdir()
    af.write(tmp_path / "avatars", "vrm1.vrm")
    found = load_avatar("vrm1")
    assert found is not None and found.source.endswith("vrm1.vrm")
    assert load_avatar("default") is None
    with pytest.raises(AvatarError, match=r"no such file or name .*known: default, vrm1"):
        load_avatar("nobody")


# --- bad input: one line naming the file and what is wrong ---------------------------------


def one_line(exc: pytest.ExceptionInfo[AvatarError], path: Path | str) -> str:
    text = str(exc.value)
    assert "\n" not in text and str(path) in text
    return text


def broken(tmp_path: Path, change: object, name: str = "bad.vrm") -> Path:
    data = af.build(af.AVATARS["vrm1.vrm"])
    doc = af.glb_json(data)
    change(doc)  # type: ignore[operator]
    path = tmp_path / name
    path.write_bytes(af.glb_with_json(data, doc))
    return path


def test_not_gltf(tmp_path: Path) -> None:
    for data, problem in (
        (b"MThd\x00\x00\x00\x06", "not a glTF file"),
        (b"glTF\x02\x00\x00\x00\xff\xff", "not a readable glTF file"),
        (b'{"asset": {"version": "1.0"}}', "glTF version 1.0"),
    ):
        path = tmp_path / "x.glb"
        path.write_bytes(data)
        with pytest.raises(AvatarError) as exc:
            load_avatar_file(path)
        assert problem in one_line(exc, path)


def test_no_humanoid(tmp_path: Path) -> None:
    def strip(doc: dict) -> None:  # type: ignore[type-arg]
        del doc["extensions"]
        for i, node in enumerate(doc["nodes"]):
            node["name"] = f"Bone{i}"

    path = broken(tmp_path, strip)
    with pytest.raises(AvatarError) as exc:
        load_avatar_file(path)
    assert "no humanoid" in one_line(exc, path)


def test_missing_bones_are_named(tmp_path: Path) -> None:
    path = af.write(tmp_path, "gap.vrm", af.Spec(vrm="1", drop=("leftHand", "rightLowerLeg")))
    with pytest.raises(AvatarError) as exc:
        load_avatar_file(path)
    assert one_line(exc, path).endswith(
        "required bone(s) missing (VRM 1.0): leftHand, rightLowerLeg"
    )
    info = inspect_avatar(path)
    assert info.missing == ["leftHand", "rightLowerLeg"] and info.avatar is None


@pytest.mark.parametrize(
    ("change", "problem"),
    [
        (lambda d: d["buffers"][0].update(byteLength=10**7), "buffer 0 is"),
        (lambda d: d["accessors"][3].update(count=10**6), "accessor 3"),
        (lambda d: d["bufferViews"][2].update(byteOffset=10**7), "runs past buffer 0"),
        (lambda d: d["meshes"][0]["primitives"][0].update(material=9), "names material 9"),
        (lambda d: d["skins"][0]["joints"].append(999), "skin 0 names joint 999"),
        (lambda d: d["extensions"]["VRMC_vrm"]["humanoid"]["humanBones"]["hips"].update(
            node=500), "names node 500"),
        (lambda d: d["bufferViews"][0].update(byteLength=30), "cannot decode the image"),
        (lambda d: d.update(extensionsRequired=["KHR_draco_mesh_compression"]),
         "compressed with KHR_draco_mesh_compression"),
    ],
)  # fmt: skip
def test_broken_buffers_accessors_textures(tmp_path: Path, change: object, problem: str) -> None:
    path = broken(tmp_path, change)
    with pytest.raises(AvatarError) as exc:
        load_avatar_file(path)
    assert problem in one_line(exc, path)


def test_bone_map_file_is_strict(tmp_path: Path) -> None:
    path = af.write(tmp_path, "odd.glb", af.Spec(naming="vrm"))  # J_ names: no known rig
    with pytest.raises(AvatarError, match="no humanoid"):
        load_avatar_file(path)
    lines = ["[bones]"] + [f'{b} = "J_{b}"' for b in af.BONES if b != "hair"]
    bones = tmp_path / "odd.bones.toml"  # found beside the file
    bones.write_text("\n".join(lines) + "\n")
    a = load_avatar_file(path)
    assert a.bones["r_wrist"] == "J_rightHand"
    bones.write_text("\n".join([*lines, 'leftHnd = "J_leftHand"']) + "\n")
    with pytest.raises(BoneMapError) as exc:
        load_avatar_file(path)
    assert "[bones] leftHnd: unknown key; did you mean 'leftHand'?" in one_line(exc, bones)
    bones.write_text('[bones]\nhips = "Nope"\n')
    with pytest.raises(BoneMapError, match=r"\[bones\] hips: no node of that name"):
        load_avatar_file(path)
    bones.write_text("[bone]\n")
    with pytest.raises(BoneMapError, match="bone"):
        load_avatar_file(path)


def test_json_gltf_with_external_buffer(tmp_path: Path) -> None:
    data = af.build(af.AVATARS["short.glb"])
    doc = af.glb_json(data)
    length = int.from_bytes(data[12:16], "little")
    blob = data[20 + length + 8 :]
    (tmp_path / "body.bin").write_bytes(blob)
    doc["buffers"][0]["uri"] = "body.bin"
    path = tmp_path / "short.gltf"
    path.write_text(json.dumps(doc))
    a = load_avatar_file(path)
    assert a.mesh.triangle_count == 420
    with pytest.raises(AvatarError, match="cannot read"):
        parse_gltf(path.read_bytes(), str(path), base_dir=tmp_path / "elsewhere")


def test_a_mesh_that_stops_below_the_head_gets_a_skull_from_the_bones(tmp_path: Path) -> None:
    def headless(doc: dict) -> None:  # type: ignore[type-arg]
        face = next(i for i, n in enumerate(doc["nodes"]) if n.get("name") == "Face")
        doc["scenes"][0]["nodes"].remove(face)  # the head and hair mesh is not in the scene

    a = load_avatar_file(broken(tmp_path, headless, "headless.vrm"))
    k = af.AVATARS["vrm1.vrm"].height_m / af.HEIGHT_M
    # neither zero nor the mesh's (which ends at the head joint): the default skull, scaled
    assert 0.1 * k < a.lengths.head_top < 0.3 * k
