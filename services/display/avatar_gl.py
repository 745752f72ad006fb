"""A skinned avatar on the GPU: one vertex buffer, one skin-matrix upload per frame.

The mesh (:class:`livedrummer.avatar.model.SkinnedMesh`) goes to the GPU once, interleaved
(position, normal, uv, four joint indices as floats, four weights: 16 floats a vertex), with
its index buffer. Per frame the CPU does only the 24 matrix products of
:func:`skin_matrices` (``world(pose) @ inverse(bind)``, bind inverses computed once) and
writes them to the ``u_skin`` uniform array; ``shaders/skin.vert`` blends a vertex's up to four
matrices, renormalising its weights. Primitives are drawn in index-buffer runs, one draw per
primitive with its material's uniforms: OPAQUE and MASK ones first, BLEND ones after them with
blending on and depth writes off (in mesh order, not sorted by depth: a character's few
transparent parts rarely overlap one another).

:meth:`SkinnedDraw.skinned_positions` runs the same vertex shader through transform feedback
and returns the skinned positions, which is how the tests compare the GPU with the numpy
reference (:func:`livedrummer.avatar.skinning.skin`). The face (:meth:`SkinnedDraw.set_face`) is
a second vertex buffer of offsets added to the bind-pose positions before skinning, the
avatar's face shapes summed at their weights. Limits: 24 joints (the body's), one
base-colour texture per material, sampled linear with mipmaps; no shadows of its own.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from livedrummer.avatar.model import Avatar, Material
from livedrummer.avatar.skinning import joint_matrices
from livedrummer.render.shaders import shader_source

VERTEX_FLOATS = 16
_ALPHA = {"OPAQUE": 0, "MASK": 1, "BLEND": 2}
_SHADING = {"lit": 0, "toon": 1}


def interleave(avatar: Avatar) -> np.ndarray:
    """The vertex buffer's contents, float32 (V, 16)."""
    m = avatar.mesh
    return np.ascontiguousarray(
        np.column_stack(
            [
                m.positions,
                m.normals,
                m.uv,
                m.joints.astype(np.float32),
                m.weights,
            ]
        ),
        np.float32,
    )


def shininess(material: Material) -> float:
    """A specular exponent for the stage shader from a glTF roughness factor."""
    r = min(max(material.roughness, 0.0), 1.0)
    return float(4.0 + 90.0 * (1.0 - r) ** 2)


#: words in a material's name that mark it as skin (wrapped diffuse, ``shaders/lighting.glsl``)
SKIN_WORDS = ("skin", "face", "body", "lip", "ear", "hand", "neck")
KIND_SKIN = 4


def surface_kind(material: Material) -> int:
    """The stage shader's material kind for an avatar material: skin by its name, else 0."""
    name = material.name.lower()
    return KIND_SKIN if any(w in name for w in SKIN_WORDS) else 0


class SkinnedDraw:
    """One avatar's GPU buffers and its per-primitive draws (see the module docstring)."""

    def __init__(self, ctx: Any, program: Any, avatar: Avatar) -> None:
        import moderngl

        avatar.mesh.check(avatar.source)
        self.ctx = ctx
        self.program = program
        self.avatar = avatar
        mesh = avatar.mesh
        self._vbo = ctx.buffer(interleave(avatar).tobytes())
        self._ibo = ctx.buffer(mesh.indices.tobytes())
        # the face: shapes summed on the CPU into one offset per vertex, rewritten only where
        # the shapes reach and only when the weights change (most frames: none do)
        self._faces = {k: f for k, f in avatar.faces.items() if f.vertices.size}
        self._offset_vbo: Any = None
        self._face_key: tuple[float, ...] = ()
        if self._faces:
            touched = np.concatenate([f.vertices for f in self._faces.values()])
            self._face_span = (int(touched.min()), int(touched.max()) + 1)
            self._offsets = np.zeros((mesh.vertex_count, 3), np.float32)
            self._offset_vbo = ctx.buffer(self._offsets.tobytes(), dynamic=True)
        self._vao = ctx.vertex_array(
            program, self._content(program), index_buffer=self._ibo, index_element_size=4
        )
        self._inv_bind = np.linalg.inv(mesh.bind.astype(np.float64))
        self._textures: list[Any] = []
        for mat in mesh.materials:
            tex = None
            if mat.texture is not None:
                img = np.ascontiguousarray(mat.texture, np.uint8)
                tex = ctx.texture((img.shape[1], img.shape[0]), 4, img.tobytes())
                tex.build_mipmaps()
                tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
            self._textures.append(tex)
        order = sorted(
            range(len(mesh.primitives)),
            key=lambda i: mesh.materials[mesh.primitives[i].material].alpha_mode == "BLEND",
        )
        self._order = [mesh.primitives[i] for i in order]
        self._feedback: tuple[Any, Any, Any] | None = None
        self._depth: Any = None

    @property
    def has_face(self) -> bool:
        return bool(self._faces)

    def set_face(self, weights: dict[str, float]) -> None:
        """The face of the next draws: each shape of the avatar at its weight (0..1; names
        of :data:`livedrummer.body.face.FACES`; a name the avatar has no shape for is
        ignored)."""
        if not self._faces:
            return
        key = tuple(round(float(weights.get(k, 0.0)), 4) for k in self._faces)
        if key == self._face_key:
            return
        self._face_key = key
        lo, hi = self._face_span
        self._offsets[lo:hi] = 0.0
        for w, (_name, f) in zip(key, self._faces.items(), strict=True):
            if w:
                self._offsets[f.vertices] += np.float32(w) * f.deltas
        self._offset_vbo.write(self._offsets[lo:hi].tobytes(), offset=lo * 12)

    def _content(self, program: Any) -> list[tuple[Any, ...]]:
        out = [self._layout(program)]
        if self._offset_vbo is not None and "in_offset" in program:
            out.append((self._offset_vbo, "3f", "in_offset"))
        return out

    def _layout(self, program: Any) -> tuple[Any, ...]:
        names = ("in_pos", "in_normal", "in_uv", "in_joints", "in_weights")
        sizes = (3, 3, 2, 4, 4)
        fmt, keep = [], []
        for name, n in zip(names, sizes, strict=True):
            if name in program:
                fmt.append(f"{n}f")
                keep.append(name)
            else:
                fmt.append(f"{4 * n}x")
        return (self._vbo, " ".join(fmt), *keep)

    def skin_matrices(self, rotations_q: np.ndarray, joints_m: np.ndarray) -> np.ndarray:
        """``world @ inverse(bind)`` per joint, float32 (24, 4, 4), from a frame's pose."""
        world = joint_matrices(rotations_q, joints_m)
        return (world @ self._inv_bind).astype(np.float32)

    def _write_skin(self, program: Any, skin_m: np.ndarray) -> None:
        program["u_skin"].write(np.ascontiguousarray(skin_m.transpose(0, 2, 1)).tobytes())

    def draw(self, rotations_q: np.ndarray, joints_m: np.ndarray, fbo: Any) -> None:
        """Draw the avatar in the pose (the frame's world rotations and joint positions)."""
        import moderngl

        prog = self.program
        self._write_skin(prog, self.skin_matrices(rotations_q, joints_m))
        materials = self.avatar.mesh.materials
        blending = False
        for prim in self._order:
            mat = materials[prim.material]
            if mat.alpha_mode == "BLEND" and not blending:
                blending = True
                self.ctx.enable(moderngl.BLEND)
                self.ctx.blend_func = (
                    moderngl.SRC_ALPHA,
                    moderngl.ONE_MINUS_SRC_ALPHA,
                    moderngl.ZERO,
                    moderngl.ONE,
                )
                fbo.depth_mask = False
            prog["u_base_color"].value = tuple(float(c) for c in mat.base_color)
            prog["u_alpha_mode"].value = _ALPHA[mat.alpha_mode]
            prog["u_alpha_cutoff"].value = float(mat.alpha_cutoff)
            prog["u_shading"].value = _SHADING[mat.shading]
            prog["u_shininess"].value = shininess(mat)
            if "u_kind" in prog:
                prog["u_kind"].value = surface_kind(mat)
            tex = self._textures[prim.material]
            prog["u_has_texture"].value = tex is not None
            if tex is not None:
                prog["u_texture"].value = 0
                tex.use(location=0)
            self._vao.render(moderngl.TRIANGLES, vertices=prim.count, first=prim.first)
        if blending:
            fbo.depth_mask = True
            self.ctx.disable(moderngl.BLEND)

    def draw_depth(self, program: Any, rotations_q: np.ndarray, joints_m: np.ndarray) -> None:
        """Depth only, for the key light's shadow map: every primitive but the BLEND ones (a
        MASK primitive casts its whole outline: the depth pass does not read textures)."""
        import moderngl

        if self._depth is None:
            self._depth = self.ctx.vertex_array(
                program, self._content(program), index_buffer=self._ibo, index_element_size=4
            )
        self._write_skin(program, self.skin_matrices(rotations_q, joints_m))
        materials = self.avatar.mesh.materials
        for prim in self._order:
            if materials[prim.material].alpha_mode != "BLEND":
                self._depth.render(moderngl.TRIANGLES, vertices=prim.count, first=prim.first)

    def skinned_positions(self, rotations_q: np.ndarray, joints_m: np.ndarray) -> np.ndarray:
        """The vertex shader's skinned positions, float32 (V, 3), read back by transform
        feedback (tests compare them with the numpy reference)."""
        import moderngl

        if self._feedback is None:
            prog = self.ctx.program(vertex_shader=shader_source("skin.vert"), varyings=["v_pos"])
            vao = self.ctx.vertex_array(prog, self._content(prog))
            # a stand-alone (EGL) context has no default framebuffer: without one bound the
            # draw is refused (GL_INVALID_FRAMEBUFFER_OPERATION) even with nothing rasterised
            fbo = self.ctx.framebuffer(color_attachments=[self.ctx.renderbuffer((1, 1))])
            self._feedback = (prog, vao, fbo)
        prog, vao, fbo = self._feedback
        fbo.use()
        self._write_skin(prog, self.skin_matrices(rotations_q, joints_m))
        n = self.avatar.mesh.vertex_count
        out = self.ctx.buffer(reserve=n * 12)
        vao.transform(out, mode=moderngl.POINTS, vertices=n)
        data = np.frombuffer(out.read(), np.float32).reshape(n, 3).copy()
        out.release()
        return data
