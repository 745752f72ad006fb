"""Finding and loading avatars by file or name: ``--avatar FILE|NAME`` and ``livedrummer avatars``.

One front door: :func:`load_avatar` takes what a user typed. A path with a ``.vrm``, ``.glb``
or ``.gltf`` suffix (or any existing file) is read; any other word is a NAME looked up as
``NAME.vrm|.glb|.gltf`` in the bundled ``kits/avatars/`` and then in the user's
``~/.config/livedrummer/avatars/`` (:func:`livedrummer.resources.user_home`; a user's file
wins over a bundled one of the same name). ``default`` is the built-in character, drawn by
the renderer from the body's own proportions: it loads as ``None``. A bone map is the given
``bone_map``, else ``FILE.bones.toml`` beside the file (:mod:`~livedrummer.avatar.bonemap`).

:func:`inspect_avatar` is ``avatar info``'s view: it reports what was found even when the
avatar cannot be used (bones missing, or a kit it cannot be fitted to: the same
:func:`~livedrummer.avatar.fit.fit_avatar` the commands call), with the one-line reason.
Limits: files are read whole into memory; nothing is cached between calls (a CLI command
loads its avatar once).
"""

from __future__ import annotations

__all__ = ["DEFAULT", "SUFFIXES", "avatar_dirs", "list_avatars", "load_avatar", "resolve_avatar"]

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from livedrummer.avatar.bonemap import REQUIRED, Humanoid, find_humanoid, sidecar
from livedrummer.avatar.catalog import DEFAULT, SUFFIXES, avatar_dirs, list_avatars
from livedrummer.avatar.fit import Fitting, fit_avatar
from livedrummer.avatar.gltf import GltfScene, read_gltf_file
from livedrummer.avatar.model import Avatar, AvatarError
from livedrummer.avatar.retarget import Fitted, retarget
from livedrummer.errors import UnreachableError
from livedrummer.kit.model import Kit
from livedrummer.resources import user_home


def resolve_avatar(spec: str) -> Path | None:
    """The file ``spec`` names (None for the built-in character); unknown names are an error
    listing the known ones."""
    path = Path(spec).expanduser()
    if path.suffix.lower() in SUFFIXES or path.is_file() or "/" in spec:
        if not path.is_file():
            raise AvatarError(f"{path}: no such avatar file")
        return path
    if spec == DEFAULT:
        return None
    hits = [Path(p) for name, _, p in list_avatars() if name == spec and p]
    if hits:
        return hits[-1]
    names = ", ".join(name for name, _, _ in list_avatars())
    raise AvatarError(
        f"avatar {spec!r}: no such file or name (known: {names}; add .vrm/.glb "
        f"files to {user_home() / 'avatars'})"
    )


def _bone_map_for(path: Path, bone_map: Path | None) -> Path | None:
    if bone_map is not None:
        return bone_map
    side = sidecar(path)
    return side if side.is_file() else None


def load_avatar(spec: str, bone_map: Path | None = None) -> Avatar | None:
    """The avatar ``spec`` names, bound to the body's skeleton (None: the built-in one)."""
    path = resolve_avatar(spec)
    if path is None:
        return None
    return load_avatar_file(path, bone_map)


def load_avatar_file(path: Path, bone_map: Path | None = None) -> Avatar:
    scene = read_gltf_file(path)
    human = find_humanoid(scene, _bone_map_for(path, bone_map))
    avatar, _ = retarget(scene, human, path.stem)
    return avatar


@dataclass
class AvatarInfo:
    """``avatar info``: what the file holds and how it maps, and why it cannot be used."""

    source: str
    nodes: int = 0
    convention: str = ""
    humanoid: dict[str, str] = field(default_factory=dict)  # humanoid bone -> node name
    missing: list[str] = field(default_factory=list)
    avatar: Avatar | None = None
    fitted: Fitted | None = None
    textures: int = 0
    error: str = ""
    #: how it will play the kit asked about (:func:`~livedrummer.avatar.fit.fit_avatar`, the
    #: call render and check make), when a kit was given and the avatar binds
    fitting: Fitting | None = None

    def as_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "file": self.source, "usable": self.avatar is not None and not self.error,
            "error": self.error or None,
            "nodes": self.nodes, "convention": self.convention or None,
            "humanoid_bones": self.humanoid, "required_missing": self.missing,
        }  # fmt: skip
        a, f = self.avatar, self.fitted
        if a is not None and f is not None:
            from dataclasses import asdict

            out.update({
                "name": a.name, "digest": a.digest, "mapped": a.bones,
                "height_m": round(f.height_m, 4), "unit_scale": f.unit_scale,
                "faces": f.facing, "up": f.up, "curled_finger_bones": f.curled_fingers,
                "proportions_m": {k: round(v, 4) for k, v in asdict(a.lengths).items()},
                "vertices": a.mesh.vertex_count, "triangles": a.mesh.triangle_count,
                "primitives": len(a.mesh.primitives),
                "materials": [{"name": m.name, "alpha": m.alpha_mode, "shading": m.shading,
                               "texture": None if m.texture is None
                               else list(m.texture.shape[1::-1])}
                              for m in a.mesh.materials],
                "textures": self.textures,
            })  # fmt: skip
            if self.fitting is not None:
                out["fit"] = self.fitting.as_json()
        return out


def inspect_avatar(
    path: Path, bone_map: Path | None = None, kit: Kit | None = None, fit: str = "auto"
) -> AvatarInfo:
    """Everything ``avatar info`` shows; a file that is not glTF at all still raises. With
    ``kit``, the avatar is also fitted to it as ``render --fit FIT`` would (the same call), and
    a piece it would leave out of reach makes it unusable with that reason."""
    scene: GltfScene = read_gltf_file(path)
    info = AvatarInfo(str(path), nodes=len(scene.nodes), textures=scene.textures)
    try:
        human = find_humanoid(scene, _bone_map_for(path, bone_map))
    except AvatarError as exc:
        info.error = str(exc)
        partial = _partial(scene)
        if partial is not None:
            info.convention = partial.convention
            info.humanoid = {b: scene.nodes[i].name for b, i in partial.bones.items()}
            info.missing = partial.missing()
        else:
            info.missing = list(REQUIRED)
        return info
    info.convention = human.convention
    info.humanoid = {b: scene.nodes[i].name for b, i in human.bones.items()}
    try:
        info.avatar, info.fitted = retarget(scene, human, path.stem)
    except AvatarError as exc:
        info.error = str(exc)
        return info
    if kit is not None:
        try:
            info.fitting = fit_avatar(kit, info.avatar, fit)
        except UnreachableError as exc:
            info.error = str(exc)
    return info


def _partial(scene: GltfScene) -> Humanoid | None:
    from livedrummer.avatar import bonemap

    try:
        found = bonemap.from_vrm(scene.extensions, len(scene.nodes), scene.source)
    except AvatarError:
        return None
    return found if found is not None else bonemap.from_names(scene)
