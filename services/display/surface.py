"""Where a live display draws: off screen (headless, recording, CI) or in a window (the stage).

Both hold a :class:`~services.display.renderer.Renderer` and the current camera, and give the
live loop the same three calls: :meth:`draw` a scene frame (or the empty kit), :meth:`present`
it (a window swaps and handles its keys; headless does nothing) and :meth:`close`. The window
is the file window's (:func:`~services.display.window.open_window`: windowed or full screen on
a chosen monitor, for projectors) with the camera keys 1..8 (a smooth move between stored
viewpoints), O and G (SMED's score and joint-angle strips, :data:`~.window.OVERLAY_KEYS`),
H (key help), I (hide the readout), F (full screen) and Q/Esc to quit; a live
show has no transport, since the drummer sets the time. The window's readout says what the
show is doing: waiting for poses, playing, or holding the last pose while the stream is
stalled (:attr:`WindowSurface.state`, set by the live loop), and the camera. Both surfaces
name the strips shown in :attr:`overlays` and blend the live loop's strip image with
:meth:`overlay` (:mod:`livedrummer.render.live_overlay`). With
``WindowOptions.keys_port`` the drum keys (:mod:`livedrummer.midi.keypads`, Shift loud, Ctrl
soft) go out as MIDI notes into that input port (:mod:`services.display.keysend` says why
this route), so the drummer plays them like a kit's strokes.

The window's frame is drawn off screen, into the renderer's own target, and copied into the
window's framebuffer by one blit before the swap (:meth:`Renderer.present`): so the static kit
layer (:mod:`services.display.passes.layer`) serves the window as it does a render, drawing
again only what moved. The window is opened without multisampling: ``WindowOptions.samples``
above 0 (``--aa N``) gives FXAA instead, 0 no anti-aliasing (4 samples cost about 2.4x the CPU
of the FXAA path at 720p, ``livedrummer bench render --live-window``).
A resize makes a new renderer (its targets have one size).

Limits: recording and PNG frames are headless only.
"""

from __future__ import annotations

from contextlib import ExitStack
from dataclasses import replace
from typing import Any

import numpy as np

from livedrummer.avatar.model import Avatar
from livedrummer.kit.lights import LightRig
from livedrummer.kit.model import Kit
from livedrummer.live.stage import Stage
from livedrummer.midi.keypads import KEYPADS, keypad_hit
from livedrummer.render.background import Background
from livedrummer.render.body_scene import BODY_SKELETON
from livedrummer.render.camera import Camera, CameraMove, kit_cameras
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.scene import SceneFrame

from .keysend import KeySender
from .renderer import Renderer
from .showctl import darken
from .viewcontrol import ViewControl
from .window import (
    OVERLAY_KEYS,
    Readout,
    WindowOptions,
    key_name,
    open_window,
    toggle_fullscreen,
)


class HeadlessSurface:
    """An off-screen renderer on an EGL context; read frames back from :attr:`renderer`."""

    def __init__(
        self,
        kit: Kit,
        size: tuple[int, int],
        camera: str,
        avatar: Avatar | None = None,
        background: Background | None = None,
        lights: LightRig | None = None,
    ) -> None:
        from livedrummer.render.camera import pick_camera

        from .context import headless_context

        self._ctx = headless_context()
        # no static layer here: it saves CPU but not wall time on llvmpipe, and a live frame
        # is judged by when it is done (bench latency, one run each, idle 2 cores: frame
        # rendered p50 43.7 ms with the layer, 35.4-36.5 ms without; p99 64-68 / 50-61 ms)
        self.renderer = Renderer(
            self._ctx,
            build_kit_mesh(kit),
            BODY_SKELETON,
            size,
            samples=0,
            avatar=avatar,
            background=background,
            lights=lights,
            static_layer=False,
        )
        self._camera = pick_camera(kit, camera)
        self.stage: Stage | None = None  # show control: camera and blackout (showctl)
        self.overlays: frozenset[str] = frozenset()  # the strips drawn (score, joints)
        self.view: Camera | None = None  # the camera of the last frame drawn
        self.target: Any = None  # what the frame is drawn into (the renderer's own)

    def draw(self, frame: SceneFrame | None, now_s: float) -> None:
        stage = self.stage
        self.view = self._camera if stage is None else stage.view(now_s)
        if stage is not None:
            self.renderer.lights = stage.lights_at(now_s)
        self.renderer.draw(frame, self.view)
        if stage is not None:
            darken(self.renderer, stage.darkness(now_s))

    def overlay(self, image: np.ndarray, rect: tuple[int, int, int, int]) -> None:
        self.renderer.draw_overlay(image, rect)

    def present(self) -> bool:
        return True

    def close(self) -> None:
        self._ctx.release()


class WindowSurface:
    """A GLFW window (see the module docstring); :meth:`present` is False once the user quits."""

    def __init__(self, kit: Kit, options: WindowOptions, avatar: Avatar | None = None) -> None:
        self._stack = ExitStack()
        try:  # no multisampled screen: the frame is drawn off screen and copied in
            glfw, window, ctx = self._stack.enter_context(open_window(replace(options, samples=0)))
        except BaseException:
            self._stack.close()
            raise
        self._glfw, self._window, self._ctx = glfw, window, ctx
        self._kit, self._avatar, self._options = kit, avatar, options
        self.renderer = self._renderer(glfw.get_framebuffer_size(window))
        self._cameras = kit_cameras(kit)
        start = self._cameras[options.camera]
        self._move = CameraMove(start, start, 0.0, 0.0)
        self._keys: list[str] = []
        self._now = 0.0
        self._options = options
        self.camera = options.camera
        self.state = "waiting for poses"  # set by the live loop each frame
        self.stage: Stage | None = None  # show control: camera and blackout (showctl)
        self._readout = Readout()
        self._show_readout, self._show_help = True, False
        self.overlays = frozenset(options.overlays)  # the strips drawn; O and G toggle them
        self.keys = KeySender(options.keys_port) if options.keys_port else None
        self.view: Camera | None = None  # the camera of the last frame drawn
        self.target: Any = None  # what the frame is drawn into (the renderer's own)

        def on_key(_w: Any, key: int, _scancode: int, action: int, mods: int) -> None:
            name = key_name(glfw, key, mods)
            if name in KEYPADS:  # a drum key: the first press only (repeat is no roll)
                hit = keypad_hit(name, bool(mods & glfw.MOD_SHIFT), bool(mods & glfw.MOD_CONTROL))
                if action == glfw.PRESS and hit is not None and self.keys is not None:
                    self.keys.send(*hit)  # at once: the poll is on this thread, each frame
            elif action in (glfw.PRESS, glfw.REPEAT):
                self._keys.append(name)

        glfw.set_key_callback(window, on_key)
        self._view = ViewControl(glfw, window)

    def _renderer(self, size: tuple[int, int]) -> Renderer:
        """The window's renderer: its own off-screen target of the window's size (FXAA where
        the options ask for anti-aliasing), and so the static layer (see the module
        docstring)."""
        options = self._options
        return Renderer(
            self._ctx,
            build_kit_mesh(self._kit),
            BODY_SKELETON,
            size,
            samples=0,
            fxaa=options.samples > 0,
            avatar=self._avatar,
            background=options.background,
            lights=options.lights,
        )

    def draw(self, frame: SceneFrame | None, now_s: float) -> None:
        self._now = now_s
        fb = self._glfw.get_framebuffer_size(self._window)
        if fb != self.renderer.size and fb[0] > 0 and fb[1] > 0:
            lights = self.renderer.lights
            self.renderer = self._renderer(fb)  # its targets are made for one size
            self.renderer.lights = lights
        stage = self.stage
        if stage is None:
            self._move = self._view.mouse(self._move, now_s, self.renderer.size)
            view = self._move.at(now_s)
        else:
            view = stage.view(now_s)
            self.renderer.lights = stage.lights_at(now_s)
        self.view = view
        self.renderer.draw(frame, view)
        if stage is not None:
            darken(self.renderer, stage.darkness(now_s))
            self.camera = stage.camera
        if self._show_readout or self._show_help:
            from livedrummer.render.hud import live_lines

            lines = live_lines(self.state, self.camera, self._show_help, self.keys is not None)
            self._readout.draw(self.renderer, lines, None)

    def overlay(self, image: np.ndarray, rect: tuple[int, int, int, int]) -> None:
        self.renderer.draw_overlay(image, rect)

    def present(self) -> bool:
        glfw = self._glfw
        self.renderer.present(self._ctx.screen)
        glfw.swap_buffers(self._window)
        glfw.poll_events()
        for name in self._keys:
            if name in ("q", "escape"):
                glfw.set_window_should_close(self._window, True)
            elif name == "h":
                self._show_help = not self._show_help
            elif name == "i":
                self._show_readout = not self._show_readout
            elif name == "f":
                toggle_fullscreen(glfw, self._window, self._options)
            elif name in OVERLAY_KEYS:
                self.overlays = self.overlays ^ {OVERLAY_KEYS[name]}
            elif self.stage is not None and name.isdigit() and 1 <= int(name) <= 8:
                self.stage.set_camera(name, self._now)
            else:
                self._move, label = self._view.key(name, self._move, self._cameras, self._now)
                self.camera = label or self.camera
        self._keys.clear()
        return not glfw.window_should_close(self._window)

    def close(self) -> None:
        if self.keys is not None:
            self.keys.close()
        self._stack.close()
