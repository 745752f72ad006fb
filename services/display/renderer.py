"""The renderer: kit instances, the drummer and the sticks drawn with the ``shaders/`` programs.

The drummer is a skinned avatar (``avatar``; by default the built-in character of
:func:`livedrummer.avatar.character.build_character`) posed by the frame's world rotations
and joint positions on the GPU (:mod:`.avatar_gl`, ``shaders/skin.*``), or, with
``avatar="mannequin"`` or for a frame without rotations or a skeleton other than the body's
24 joints, the capsule mannequin described next.

Built once per (context, kit, skeleton, size): unit meshes are uploaded once; per frame only
the instance buffers change. The kit's instances come from :meth:`KitMesh.instances` (one
array for all pieces); the body goes in as joint positions gathered by the skeleton's parent
index (one numpy gather, no per-joint Python loop) and the segment shader builds each
capsule's basis on the GPU. Drawing is one instanced call per unit mesh and program.

Off-screen, it draws into a texture framebuffer, or with ``samples > 0`` into a multisampled
one resolved into it (multisampling costs about 2.7x on llvmpipe), and with ``fxaa`` a
full-screen anti-aliasing pass (``shaders/fxaa.frag``) runs once over the drawn scene, before
the first read-back or overlay (overlays are painted over it unfiltered; off screen only).
:meth:`Renderer.read_rgb` returns top-down RGB rows as PNG writers expect;
:meth:`Renderer.read_rgba` returns the driver's own bottom-up RGBA, the cheapest read-back,
and :meth:`Renderer.read_i420` converts the frame to the video encoder's planar YUV 4:2:0 on
the GPU first (full-screen passes, ``shaders/i420_*.frag``), so the encoder gets 1.5 bytes a
pixel, already top-down, and the CPU neither flips nor converts. A window passes its framebuffer to
:meth:`Renderer.draw`. The key light casts shadows (``shadows``, on by default): each frame the
casters (kit pieces, the drummer, the sticks; not the floor) are drawn depth-only from the key
spot into a :data:`SHADOW_SIZE` square depth texture, which every lit surface and the floor
look up with a hardware-compared 2x2 filter (``shaders/shadow.glsl``). Limits: one shadowed
light; the kit's surfaces are opaque (the avatar's BLEND parts cast no shadow); every surface
is lit by the same rig; the window must set :attr:`Renderer.size` when its framebuffer is
resized.
The frame is cleared to the ``background`` (:mod:`livedrummer.render.background`: the dark hall,
a colour, chroma green, alpha 0, or an image stretched over it first by a full-screen pass);
the floor is blended last so its rim fades into whatever is behind it.
:meth:`Renderer.draw_overlay` blends a 2D RGBA image (the score and joint-angle strips of
:mod:`livedrummer.render.overlay_raster`) over the drawn frame (``shaders/overlay.frag``).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from livedrummer.avatar.model import Avatar
from livedrummer.body.face import FaceTrack
from livedrummer.body.skeleton import N_JOINTS, J
from livedrummer.render.background import HALL, Background
from livedrummer.render.camera import Camera, look_at, perspective
from livedrummer.render.geometry import Mesh, all_meshes
from livedrummer.render.kitmesh import (
    INSTANCE_FLOATS,
    MATERIAL_PLAIN,
    MOTION_STATIC,
    STAGE_RADIUS_M,
    KitMesh,
)
from livedrummer.render.lights import DEFAULT_LOOK, LightRig, look_rig
from livedrummer.render.scene import CH_HIGHLIGHT, SceneFrame, Skeleton, Tone, empty_channels
from livedrummer.render.shaders import PROGRAMS, program_sources, shader_source

from .avatar_gl import SkinnedDraw

BACKGROUND = HALL
#: colour per :class:`Tone`
PALETTE = np.zeros((len(Tone), 3), np.float32)
PALETTE[Tone.SHIRT] = (0.14, 0.26, 0.50)
PALETTE[Tone.TROUSERS] = (0.10, 0.10, 0.12)
PALETTE[Tone.SKIN] = (0.82, 0.60, 0.46)
PALETTE[Tone.SHOES] = (0.85, 0.85, 0.85)
PALETTE[Tone.HAIR] = (0.12, 0.07, 0.04)
STICK_COLOR = (0.80, 0.60, 0.34)
STICK_RADIUS_M = 0.0075
SEGMENT_FLOATS = 15  # a xyz, b xyz, radius, colour rgba, material
BALL_FLOATS = 12  # centre xyz radius, colour rgba, material
SHADOW_SIZE = 512  # texels a side: ~7 mm at the kit, from the key light 4.6 m away
SHADOW_RADIUS_M = 1.8  # the sphere round the kit's centre that the shadow map covers
MAX_CELL_OTHERS = 128  # neighbours a stage floor's cell is cut by (shaders/floor_cell.glsl)
SHADOW_UNIT = 1  # texture unit of the shadow map (unit 0 is the avatar's base colour)


class Renderer:
    """Draws one kit and one skeleton; see the module docstring."""

    def __init__(
        self,
        ctx: Any,
        kit_mesh: KitMesh,
        skeleton: Skeleton | None,
        size: tuple[int, int],
        *,
        samples: int = 4,
        offscreen: bool = True,
        avatar: Avatar | Literal["mannequin"] | None = None,
        shadows: bool = True,
        background: Background | None = None,
        fxaa: bool = False,
        kit_occludes_only: bool = False,
        cache_static_shadow: bool = True,
        lights: LightRig | None = None,
    ) -> None:
        self.ctx = ctx
        #: the show lights (:mod:`livedrummer.render.lights`); replace it to relight the next
        #: frame (a live OSC or cue change)
        self.lights = lights if lights is not None else look_rig(DEFAULT_LOOK)
        # the kit drawn into depth only, before the body: the body alone is seen, hidden where
        # the kit is in front of it (a practice teacher's ghost, :mod:`.practice_view`)
        self.kit_occludes_only = kit_occludes_only
        self.background = background if background is not None else Background()
        self._background_pass: tuple[Any, Any] | None = None
        self.kit_mesh = kit_mesh
        self.skeleton = skeleton
        self.size = size
        self.programs = {
            name: ctx.program(vertex_shader=v, fragment_shader=f)
            for name, (v, f) in ((n, program_sources(n)) for n in PROGRAMS)
        }
        import moderngl

        meshes = all_meshes()
        self._vbo = {n: ctx.buffer(m.vertices.tobytes()) for n, m in meshes.items()}
        self._ibo = {n: ctx.buffer(m.indices.tobytes()) for n, m in meshes.items()}
        groups = kit_mesh.groups
        self._kit_groups = {k: groups[k] for k in sorted(groups, key=lambda k: k == "floor")}
        self._kit_vaos: list[tuple[Any, Any, np.ndarray]] = []
        self._kit_depth: list[tuple[Any, np.ndarray]] = []
        for name, idx in self._kit_groups.items():
            buf = ctx.buffer(reserve=max(1, len(idx)) * INSTANCE_FLOATS * 4, dynamic=True)
            program = "floor" if name == "floor" else "mesh"
            vao = self._vao(program, meshes[name], buf, "16f 4f 4f/i",
                            "in_model", "in_color", "in_material")  # fmt: skip
            self._kit_vaos.append((vao, buf, idx))
            if name != "floor":  # the floor receives shadows, it casts none
                depth = self._vao("depth_mesh", meshes[name], buf, "16f 4f 4f/i",
                                  "in_model", "in_color", "in_material")  # fmt: skip
                self._kit_depth.append((depth, idx))
        self._body_setup(meshes)
        self.shadows = shadows
        side = SHADOW_SIZE if shadows else 1
        self._shadow_map = ctx.depth_texture((side, side))
        self._shadow_map.compare_func = "<="
        self._shadow_map.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._shadow_map.repeat_x = self._shadow_map.repeat_y = False
        # a colour attachment, never looked at: a blit copies depth only between framebuffers
        # that have one (Mesa)
        self._shadow_fbo = ctx.framebuffer(color_attachments=[ctx.renderbuffer((side, side), 1)],
                                           depth_attachment=self._shadow_map)  # fmt: skip
        self.cache_static_shadow = cache_static_shadow and shadows
        self._caster_setup(meshes, side)
        for prog in self.programs.values():
            if "u_shadow_map" in prog:
                prog["u_shadow_map"].value = SHADOW_UNIT
        self.skinned: SkinnedDraw | None = None
        if skeleton is not None and skeleton.size == N_JOINTS and avatar != "mannequin":
            if avatar is None:
                from livedrummer.avatar.character import build_character

                avatar = build_character()
            self.skinned = SkinnedDraw(ctx, self.programs["skin"], avatar)
        self._face: FaceTrack | None = None  # blinks, looks and reactions (body.face)
        if self.skinned is not None and self.skinned.has_face:
            self._face = FaceTrack(kit_mesh.crash_like)
        self._pose: tuple[np.ndarray, np.ndarray] | None = None
        #: the other drummers' pool centres on a stage, in this kit's frame: the floor is drawn
        #: only nearer to its own (``shaders/floor_cell.glsl``); empty for one drummer
        self.floor_cell_others = np.zeros((0, 2), np.float32)
        self._fbo: Any = None
        self._resolve: Any = None
        if offscreen:
            w, h = size
            self._rgb = ctx.texture((w, h), 4)
            self._rgb.filter = (moderngl.LINEAR, moderngl.LINEAR)
            plain = ctx.framebuffer(color_attachments=[self._rgb])
            if samples > 0:
                color = ctx.renderbuffer((w, h), 4, samples=samples)
                depth = ctx.depth_renderbuffer((w, h), samples=samples)
                self._fbo = ctx.framebuffer(color_attachments=[color], depth_attachment=depth)
                self._resolve = plain
            else:
                depth = ctx.depth_renderbuffer((w, h))
                self._fbo = ctx.framebuffer(color_attachments=[self._rgb], depth_attachment=depth)
                self._resolve = self._fbo
        self.samples = samples
        self.fxaa = fxaa and offscreen
        self._final, self._final_tex = self._resolve, getattr(self, "_rgb", None)
        self._fxaa: Any = None
        self._stale = False  # a frame drawn since the anti-aliasing pass last ran
        if self.fxaa:
            post = ctx.texture(size, 4)
            self._final, self._final_tex = ctx.framebuffer(color_attachments=[post]), post
            prog = ctx.program(vertex_shader=shader_source("fullscreen.vert"),
                               fragment_shader=shader_source("fxaa.frag"))  # fmt: skip
            prog["u_image"].value = 0
            sampler = ctx.sampler(texture=self._rgb, filter=(moderngl.LINEAR, moderngl.LINEAR),
                                  repeat_x=False, repeat_y=False)  # fmt: skip
            self._fxaa = (ctx.vertex_array(prog, []), sampler)
        self._i420: tuple[list[tuple[Any, Any]], Any] | None = None  # made on first use
        self._overlay: tuple[Any, Any] | None = None  # (vao, texture), made on first use

    def _vao(self, program: str, mesh: Mesh, inst: Any, fmt: str, *names: str) -> Any:
        prog = self.programs[program]
        return self.ctx.vertex_array(
            prog,
            [
                _used(prog, self._vbo[mesh.name], "3f 3f", ("in_pos", "in_normal")),
                _used(prog, inst, fmt, names),
            ],
            index_buffer=self._ibo[mesh.name],
        )

    def _caster_setup(self, meshes: dict[str, Mesh], side: int) -> None:
        """The kit's shadow casters split into those that never move (drawn once into
        :attr:`_static_fbo` per key light) and those that may (drawn each frame)."""
        km = self.kit_mesh
        moving = km.motion != MOTION_STATIC
        rest = km.instances(empty_channels(km.pieces))
        self._casters_static: list[tuple[Any, int]] = []
        self._casters_moving: list[tuple[Any, Any, np.ndarray]] = []
        self._static_key: bytes | None = None  # the light the static map was drawn for
        self._static_fbo: Any = None
        if not self.cache_static_shadow:
            return
        for name, idx in self._kit_groups.items():
            if name == "floor":
                continue
            still, move = idx[~moving[idx]], idx[moving[idx]]
            if len(still):
                buf = self.ctx.buffer(rest[still].tobytes())
                vao = self._vao("depth_mesh", meshes[name], buf, "16f 4f 4f/i",
                                "in_model", "in_color", "in_material")  # fmt: skip
                self._casters_static.append((vao, len(still)))
            if len(move):
                buf = self.ctx.buffer(reserve=len(move) * INSTANCE_FLOATS * 4, dynamic=True)
                vao = self._vao("depth_mesh", meshes[name], buf, "16f 4f 4f/i",
                                "in_model", "in_color", "in_material")  # fmt: skip
                self._casters_moving.append((vao, buf, move))
        depth = self.ctx.depth_texture((side, side))
        self._static_fbo = self.ctx.framebuffer(
            color_attachments=[self.ctx.renderbuffer((side, side), 1)], depth_attachment=depth
        )

    def _body_setup(self, meshes: dict[str, Mesh]) -> None:
        sk = self.skeleton
        material = np.array([0.0, 14.0, MATERIAL_PLAIN, 0.0], np.float32)
        if sk is None:
            self._bones = np.zeros(0, np.int64)
            self._balls = np.zeros(0, np.int64)
        else:
            self._bones = sk.bones[sk.segment_radius_m[sk.bones] > 0]
            self._balls = np.flatnonzero(sk.joint_radius_m > 0)
        nb = len(self._bones)
        seg = np.zeros((nb + 2, SEGMENT_FLOATS), np.float32)
        if sk is not None:
            seg[:nb, 6] = sk.segment_radius_m[self._bones]
            seg[:nb, 7:10] = PALETTE[sk.tone[self._bones]]
        seg[nb:, 6] = STICK_RADIUS_M
        seg[nb:, 7:10] = STICK_COLOR
        seg[:, 11:15] = material
        self._seg = seg
        ball = np.zeros((len(self._balls), BALL_FLOATS), np.float32)
        if sk is not None:
            ball[:, 3] = sk.joint_radius_m[self._balls]
            ball[:, 4:7] = PALETTE[sk.tone[self._balls]]
        ball[:, 8:12] = material
        self._ball = ball
        self._seg_buf = self.ctx.buffer(reserve=seg.nbytes, dynamic=True)
        self._ball_buf = self.ctx.buffer(reserve=max(ball.nbytes, 4), dynamic=True)
        self._seg_vao = self._vao("segment", meshes["limb"], self._seg_buf,
                                  "3f 3f 1f 4f 4f/i", "in_a", "in_b", "in_radius", "in_color",
                                  "in_material")  # fmt: skip
        self._ball_vao = self._vao("ball", meshes["sphere"], self._ball_buf, "4f 4f 4f/i",
                                   "in_centre_radius", "in_color", "in_material")  # fmt: skip
        self._seg_depth = self._vao("depth_segment", meshes["limb"], self._seg_buf,
                                    "3f 3f 1f 4f 4f/i", "in_a", "in_b", "in_radius", "in_color",
                                    "in_material")  # fmt: skip
        self._ball_depth = self._vao("depth_ball", meshes["sphere"], self._ball_buf, "4f 4f 4f/i",
                                     "in_centre_radius", "in_color", "in_material")  # fmt: skip

    def upload(self, frame: SceneFrame | None) -> None:
        """Copy one frame's kit channels, joints and sticks into the instance buffers."""
        channels = frame.channels if frame is not None else empty_channels(self.kit_mesh.pieces)
        inst = self.kit_mesh.instances(channels)
        for _vao, buf, idx in self._kit_vaos:
            buf.write(inst[idx].tobytes())
        for _vao, buf, idx in self._casters_moving:
            buf.write(inst[idx].tobytes())
        self._draw_body = frame is not None
        if frame is None:
            return
        frame.check(self.skeleton, self.kit_mesh.pieces)
        nb = len(self._bones)
        has_body = self.skeleton is not None and len(frame.joints_m) > 0
        self._pose = None
        if has_body and self.skinned is not None and frame.rotations_q is not None:
            self._pose = (frame.rotations_q, frame.joints_m)
            if self._face is not None and self.skinned is not None:
                self.skinned.set_face(self._face.weights(frame.time_s,
                                                         frame.channels[:, CH_HIGHLIGHT],
                                                         frame.rotations_q[J["head"]]))  # fmt: skip
            has_body = False  # the avatar, not the capsules; the sticks stay
        self._seg_count = len(self._seg) if has_body else 2
        if has_body and self.skeleton is not None:
            j = frame.joints_m
            self._seg[:nb, 0:3] = j[self.skeleton.parent[self._bones]]
            self._seg[:nb, 3:6] = j[self._bones]
            self._ball[:, 0:3] = j[self._balls]
        self._seg[nb:, 0:6] = frame.sticks_m.reshape(2, 6)
        self._seg_buf.write(self._seg[nb:].tobytes() if not has_body else self._seg.tobytes())
        self._ball_count = len(self._ball) if has_body else 0
        if self._ball_count:
            self._ball_buf.write(self._ball.tobytes())

    def draw(self, frame: SceneFrame | None, camera: Camera, target: Any = None,
             clear: bool = True) -> None:  # fmt: skip
        """Draw ``frame`` (None: the kit at rest and no drummer) seen from ``camera``;
        ``clear=False`` draws over what ``target`` holds, depth-tested (a stage's drummers)."""
        import moderngl

        fbo = target if target is not None else self._fbo
        self._stale = True
        fbo.use()
        w, h = self.size
        self.ctx.viewport = (0, 0, w, h)
        self.ctx.enable(moderngl.DEPTH_TEST)
        self.ctx.disable(moderngl.CULL_FACE)
        if clear:
            bg = self.background
            fbo.clear(*bg.rgb, bg.alpha, depth=1.0)
            if bg.image is not None:
                self._draw_background_image(bg.image)
                self.ctx.enable(moderngl.DEPTH_TEST)
        self.upload(frame)
        vp = camera.view_projection(w / h)
        centre = self.kit_mesh.model[0, :3, 3] if len(self.kit_mesh.model) else np.zeros(3)
        eye = np.asarray(camera.eye, np.float32)
        uniforms: dict[str, Any] = {
            "u_view_proj": vp.T.tobytes(),
            "u_eye": tuple(eye),
            "u_stage_centre": (float(centre[0]), float(centre[1]), 0.0),
            "u_stage_radius": STAGE_RADIUS_M,
            **self.lights.uniforms(np.array([centre[0], centre[1], 0.6])),
        }
        key = np.array(uniforms["u_key_pos"])
        light_vp = key_light_view_projection(key, np.array([centre[0], centre[1], 0.6]))
        uniforms["u_light_vp"] = light_vp.T.tobytes()
        uniforms["u_shadow_on"] = int(self.shadows)
        self._floor_cell_uniforms()
        for prog in self.programs.values():
            for name, value in uniforms.items():
                if name in prog:
                    if name in ("u_view_proj", "u_light_vp"):
                        prog[name].write(value)
                    else:
                        prog[name].value = value
        if self.shadows:
            self._shadow_pass(light_vp)
            fbo.use()
            self.ctx.viewport = (0, 0, w, h)
        self._shadow_map.use(location=SHADOW_UNIT)
        if self.kit_occludes_only:
            self._kit_depth_pass(fbo, vp)
        # Nearest and largest first, the floor last: hidden fragments fail the depth test
        # before they are shaded (llvmpipe tests depth early for these shaders).
        if self._draw_body:
            if self._pose is not None and self.skinned is not None:
                self.skinned.draw(*self._pose, fbo)
            self._seg_vao.render(instances=self._seg_count)
            if self._ball_count:
                self._ball_vao.render(instances=self._ball_count)
        for name, (vao, _buf, idx) in zip(self._kit_groups, self._kit_vaos, strict=True):
            if self.kit_occludes_only:
                break
            if name == "floor":  # its rim fades into whatever background is behind it
                self.ctx.enable(moderngl.BLEND)
                self.ctx.blend_func = (moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA,
                                       moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA)  # fmt: skip
            vao.render(instances=len(idx))
        self.ctx.disable(moderngl.BLEND)

    def pool_centre(self) -> np.ndarray:
        """The centre (x, y) of the floor's pool of key light, in this kit's frame."""
        if not len(self.kit_mesh.model):
            return np.zeros(2)
        return np.asarray(self.kit_mesh.model[0, :2, 3], float)

    def _floor_cell_uniforms(self) -> None:
        prog = self.programs["floor"]
        if "u_cell_count" not in prog:
            return
        others = np.asarray(self.floor_cell_others, np.float32).reshape(-1, 2)[:MAX_CELL_OTHERS]
        prog["u_cell_count"].value = len(others)
        if len(others):
            padded = np.zeros((MAX_CELL_OTHERS, 2), np.float32)
            padded[: len(others)] = others
            prog["u_cell_others"].write(padded.tobytes())

    def _draw_background_image(self, image: np.ndarray) -> None:
        """Stretch ``image`` ((H, W, 3) uint8, top row first) over the whole frame, writing no
        depth; its texture is made once (``overlay.frag`` with the frame as its rectangle)."""
        import moderngl

        if self._background_pass is None:
            prog = self.ctx.program(vertex_shader=shader_source("fullscreen.vert"),
                                    fragment_shader=shader_source("overlay.frag"))  # fmt: skip
            prog["u_image"].value = 0
            h, w = image.shape[:2]
            rgba = np.dstack([image, np.full((h, w), 255, np.uint8)])
            tex = self.ctx.texture((w, h), 4, np.ascontiguousarray(rgba).tobytes())
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x = tex.repeat_y = False
            self._background_pass = (self.ctx.vertex_array(prog, []), tex)
        vao, tex = self._background_pass
        w, h = self.size
        vao.program["u_rect"].value = (0.0, 0.0, float(w), float(h))
        self.ctx.disable(moderngl.DEPTH_TEST)
        tex.use(location=0)
        vao.render(moderngl.TRIANGLES, vertices=3)

    def _kit_depth_pass(self, fbo: Any, vp: np.ndarray) -> None:
        """The kit (not the floor) into ``fbo``'s depth from the camera, no colour written."""
        self.programs["depth_mesh"]["u_view_proj"].write(vp.T.tobytes())
        fbo.color_mask = (False, False, False, False)
        fbo.use()  # moderngl applies a framebuffer's colour mask when it is bound
        try:
            for vao, idx in self._kit_depth:
                vao.render(instances=len(idx))
        finally:
            fbo.color_mask = (True, True, True, True)
            fbo.use()

    def _shadow_pass(self, light_vp: np.ndarray) -> None:
        """Draw every caster depth-only from the key light into the shadow map.

        With :attr:`cache_static_shadow`, the kit's parts that never move are drawn once per
        key light into a map of their own, which each frame starts from (a blit), and only the
        drummer, the sticks and the parts that may move are drawn over it: the same depths (the
        nearest of all casters at every texel, in whatever order drawn)."""
        vp = light_vp.T.tobytes()
        for name in ("depth_mesh", "depth_segment", "depth_ball", "depth_skin"):
            self.programs[name]["u_view_proj"].write(vp)
        if self.cache_static_shadow:
            if self._static_key != vp:
                self._static_fbo.use()
                self.ctx.viewport = (0, 0, SHADOW_SIZE, SHADOW_SIZE)
                self._static_fbo.clear(depth=1.0)
                for vao, count in self._casters_static:
                    vao.render(instances=count)
                self._static_key = vp
            self.ctx.copy_framebuffer(self._shadow_fbo, self._static_fbo)
            self._shadow_fbo.use()
            self.ctx.viewport = (0, 0, SHADOW_SIZE, SHADOW_SIZE)
        else:
            self._shadow_fbo.use()
            self.ctx.viewport = (0, 0, SHADOW_SIZE, SHADOW_SIZE)
            self._shadow_fbo.clear(depth=1.0)
        if self._draw_body:
            if self._pose is not None and self.skinned is not None:
                self.skinned.draw_depth(self.programs["depth_skin"], *self._pose)
            self._seg_depth.render(instances=self._seg_count)
            if self._ball_count:
                self._ball_depth.render(instances=self._ball_count)
        if self.cache_static_shadow:
            for vao, _buf, idx in self._casters_moving:
                vao.render(instances=len(idx))
            return
        for vao, idx in self._kit_depth:
            vao.render(instances=len(idx))

    def draw_overlay(self, image: np.ndarray, rect: tuple[int, int, int, int],
                     target: Any = None) -> None:  # fmt: skip
        """Blend ``image`` ((h, w, 4) uint8, straight alpha, top row first) over the frame
        drawn last, at ``rect`` = (x, y, w, h) in pixels from the frame's top-left corner.

        Same target as :meth:`draw` (the off-screen frame by default), so the read-backs
        include it. The texture is made once per image size and rewritten each call."""
        import moderngl

        h_img, w_img = image.shape[:2]
        x, y, w, h = rect
        if (w_img, h_img) != (w, h):
            raise ValueError(f"overlay image is {w_img}x{h_img}, its rectangle {w}x{h}")
        if w <= 0 or h <= 0:
            return
        if self._overlay is None:
            prog = self.ctx.program(vertex_shader=shader_source("fullscreen.vert"),
                                    fragment_shader=shader_source("overlay.frag"))  # fmt: skip
            prog["u_image"].value = 0
            self._overlay = (self.ctx.vertex_array(prog, []), None)
        vao, tex = self._overlay
        if tex is None or tex.size != (w, h):
            if tex is not None:
                tex.release()
            tex = self.ctx.texture((w, h), 4)
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
            tex.repeat_x = tex.repeat_y = False
            self._overlay = (vao, tex)
        tex.write(np.ascontiguousarray(image, np.uint8))
        if target is None and self._fxaa is not None:
            self._resolved()  # the scene is anti-aliased; the overlay goes over it as painted
            self._final.use()
        else:
            (target if target is not None else self._fbo).use()
            self._stale = True
        bottom = self.size[1] - y - h  # GL rows count from the bottom
        self.ctx.viewport = (x, bottom, w, h)
        vao.program["u_rect"].value = (float(x), float(bottom), float(w), float(h))
        self.ctx.disable(moderngl.DEPTH_TEST)
        self.ctx.enable(moderngl.BLEND)
        self.ctx.blend_func = (moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA,
                               moderngl.ZERO, moderngl.ONE)  # fmt: skip
        tex.use(location=0)
        vao.render(moderngl.TRIANGLES, vertices=3)
        self.ctx.disable(moderngl.BLEND)
        self.ctx.viewport = (0, 0, *self.size)

    def _resolved(self) -> None:
        """The frame drawn since the last call resolved (multisampling) and anti-aliased (FXAA)
        into :attr:`_final`; nothing to do when nothing was drawn since."""
        if not self._stale:
            return
        if self.samples > 0:
            self.ctx.copy_framebuffer(self._resolve, self._fbo)
        if self._fxaa is not None:
            import moderngl

            vao, sampler = self._fxaa
            self._final.use()
            self.ctx.viewport = (0, 0, *self.size)
            self.ctx.disable(moderngl.DEPTH_TEST)
            vao.program["u_texel"].value = (1.0 / self.size[0], 1.0 / self.size[1])
            sampler.use(location=0)
            vao.render(moderngl.TRIANGLES, vertices=3)
            sampler.clear(location=0)
        self._stale = False

    def read_rgb(self) -> np.ndarray:
        """The last off-screen frame as (H, W, 3) uint8, top row first."""
        w, h = self.size
        self._resolved()
        data = self._final.read(components=3, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(h, w, 3)[::-1]

    def read_rgba(self) -> np.ndarray:
        """The last off-screen frame as (H, W, 4) uint8, bottom row first (GL order).

        The driver's native layout: the fastest read-back; the encoder flips it for free.
        """
        w, h = self.size
        self._resolved()
        return np.frombuffer(self._final.read(components=4, alignment=1), np.uint8).reshape(h, w, 4)

    def read_rgba_top(self) -> np.ndarray:
        """The last off-screen frame as (H, W, 4) uint8 with its alpha, top row first (PNG)."""
        return np.ascontiguousarray(self.read_rgba()[::-1])

    def read_i420(self) -> np.ndarray:
        """The last off-screen frame as I420, (H*3/2, W) uint8, top row first.

        Rows ``[0, H)`` are the luma plane; the rest hold the Cb then the Cr plane, each
        (W/2) x (H/2) bytes laid end to end (BT.709, limited range; see ``shaders/bt709.glsl``).
        Two full-screen passes write it into an RGBA8 target W/4 wide, four bytes a fragment,
        whose read-back is the same bytes as a W-wide single-channel one; W must be a multiple
        of 8 (:func:`i420_ok`).
        """
        import moderngl

        w, h = self.size
        if not i420_ok(self.size):
            raise ValueError(f"I420 read-back needs a width that is a multiple of 8, not {w}")
        self._resolved()
        if self._i420 is None:
            self._i420 = self._i420_setup()
        passes, fbo = self._i420
        fbo.use()
        self.ctx.disable(moderngl.DEPTH_TEST)
        for (vao, sampler), rows in zip(passes, ((0, h), (h, h // 2)), strict=True):
            sampler.use(location=0)
            vao.program["u_size"].value = (w, h)
            self.ctx.viewport = (0, rows[0], w // 4, rows[1])
            vao.render(moderngl.TRIANGLES, vertices=3)
            sampler.clear(location=0)  # leave unit 0 to the texture's own filtering
        data = fbo.read(components=4, alignment=1)
        return np.frombuffer(data, np.uint8).reshape(h * 3 // 2, w)

    def _i420_setup(self) -> tuple[list[tuple[Any, Any]], Any]:
        import moderngl

        w, h = self.size
        passes = []
        for frag, filt in (("i420_luma.frag", moderngl.NEAREST),
                           ("i420_chroma.frag", moderngl.LINEAR)):  # fmt: skip
            prog = self.ctx.program(vertex_shader=shader_source("fullscreen.vert"),
                                    fragment_shader=shader_source(frag))  # fmt: skip
            prog["u_image"].value = 0
            sampler = self.ctx.sampler(texture=self._final_tex, filter=(filt, filt), repeat_x=False,
                                       repeat_y=False)  # fmt: skip
            passes.append((self.ctx.vertex_array(prog, []), sampler))
        target = self.ctx.texture((w // 4, h * 3 // 2), 4)
        return passes, self.ctx.framebuffer(color_attachments=[target])

    def finish(self) -> None:
        self.ctx.finish()


def key_light_view_projection(key: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The key spot's view-projection (row-major float32): from ``key`` at ``target``, a
    frustum just wide enough for a sphere of :data:`SHADOW_RADIUS_M` round the target."""
    dist = float(np.linalg.norm(target - key))
    fov = float(np.degrees(2.0 * np.arcsin(min(SHADOW_RADIUS_M / dist, 0.95))))
    near = max(dist - SHADOW_RADIUS_M - 0.5, 0.1)
    vp: np.ndarray = (perspective(fov, 1.0, near, dist + SHADOW_RADIUS_M + 0.5)
                      @ look_at(key, target)).astype(np.float32)  # fmt: skip
    return vp


def i420_ok(size: tuple[int, int]) -> bool:
    """Whether :meth:`Renderer.read_i420` can convert frames of ``size`` (W, H)."""
    return size[0] % 8 == 0 and size[1] % 2 == 0


def _used(prog: Any, buf: Any, fmt: str, names: tuple[str, ...]) -> tuple[Any, ...]:
    """A buffer binding that skips attributes the linker optimized out of ``prog``."""
    tokens = fmt.split()
    divisor = tokens[-1][tokens[-1].index("/") :] if "/" in tokens[-1] else ""
    tokens = [t.split("/")[0] for t in tokens]
    keep: list[str] = []
    out: list[str] = []
    for token, name in zip(tokens, names, strict=True):
        if name in prog:
            out.append(token)
            keep.append(name)
        else:
            count = int(token[:-1] or 1)
            out.append(f"{4 * count}x")
    return (buf, " ".join(out) + divisor, *keep)
