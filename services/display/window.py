"""The window: the drummer on a monitor or projector, with camera keys and file transport.

GLFW makes the window and its OpenGL 3.3 core context (windowed, or full screen on a chosen
monitor for a projector); the same :class:`~services.display.renderer.Renderer` draws into the
window's framebuffer. Each frame the loop asks its clock how much time passed, advances the
:class:`~livedrummer.render.transport.Transport`, evaluates the scene at the transport's
position (the body model, :class:`~livedrummer.render.body_scene.BodyScene`, sampled at that
one time) and swaps; keys go through :data:`~livedrummer.render.transport.KEYS` (transport),
1..8 (cameras, with a smooth move), O and G (show or hide the score and the joint-angle
overlays, :data:`OVERLAY_KEYS`), F (full screen on and off), H (key help), I (the readout)
and Q/Esc (quit); the keys of :data:`~livedrummer.midi.keypads.KEYPADS` play pieces over the
file (:class:`~livedrummer.render.keydrum.KeyDrum`: heard through the player, the piece glows
and wobbles; the file's drummer does not change). A readout in the top-left corner
(:mod:`livedrummer.render.hud`) shows the position and length, speed,
playing/paused/reversed, the camera and a clear end-of-file line;
``WindowOptions.screenshot`` writes the last frame drawn as a PNG when the window closes. The clock
is injected (default ``time.monotonic``) as the style guide asks; with sound (a
:class:`~services.display.audio_out.TrackPlayer`) it is the output's sample clock, each frame
tells the player where the transport is, and the frame is drawn for the moment it will be
seen (the median time frames took to draw and swap, :class:`RenderAhead`), so the picture
follows what is heard (muted at other
speeds and in reverse, said in the readout). ``WindowOptions.frame_log`` writes one JSON line
per frame (the monotonic time just after the swap, the position shown) for tests and
measurements.

Limits: resizing keeps the
aspect ratio of the new size but not the pixel density of a HiDPI monitor.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from livedrummer.avatar.model import Avatar
from livedrummer.kit.lights import LightRig
from livedrummer.kit.model import Kit
from livedrummer.live.ahead import RenderAhead
from livedrummer.midi.keypads import KEYPADS, keypad_hit
from livedrummer.render.background import Background
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import CameraMove, kit_cameras
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.overlay import OverlayModels
from livedrummer.render.overlay_raster import overlay_image
from livedrummer.render.transport import KEYS, STEPS, Transport
from livedrummer.timeline.performance import Performance

from .audio_out import TrackPlayer, muted_reason
from .context import DisplayError, use_cpu_cores
from .renderer import Renderer
from .viewcontrol import ViewControl

if TYPE_CHECKING:
    from livedrummer.render.keydrum import KeyDrum

    from .midi_out import MidiFileOut

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class WindowOptions:
    size: tuple[int, int] = (1280, 720)
    fullscreen: bool = False
    monitor: int = 0
    camera: str = "stage"
    samples: int = 4
    vsync: bool = True
    quit_after_s: float | None = None  # close by itself (demos, smoke tests)
    overlays: frozenset[str] = frozenset()  # strips shown first: "score", "joints"
    screenshot: Path | None = None  # the last frame drawn, written as a PNG when it closes
    background: Background | None = None  # behind the stage (None: the dark hall)
    frame_log: Path | None = None  # per frame: {"mono": after the swap, "t": position shown}
    keys_port: str | None = None  # live: the MIDI input the drum keys play into (keysend)
    lights: LightRig | None = None  # the show lights (None: the default look)


DEFAULT_OPTIONS = WindowOptions()
#: window key -> the overlay it shows or hides (keys the transport does not use)
OVERLAY_KEYS: dict[str, str] = {"o": "score", "g": "joints"}
HUD_AT = (8, 8)  # the readout's top-left corner, pixels from the window's top-left


def toggle_fullscreen(glfw: Any, window: Any, options: WindowOptions) -> None:
    """F: full screen on the options' monitor, or back to a window of the options' size."""
    if glfw.get_window_monitor(window):
        w, h = options.size
        glfw.set_window_monitor(window, None, 40, 40, w, h, 0)
        return
    monitors = glfw.get_monitors()
    if not monitors:
        return
    monitor = monitors[options.monitor] if 0 <= options.monitor < len(monitors) else monitors[0]
    mode = glfw.get_video_mode(monitor)
    glfw.set_window_monitor(
        window, monitor, 0, 0, mode.size.width, mode.size.height, mode.refresh_rate
    )


class Readout:
    """The HUD texture of a window: repainted only when its lines or the frame's size change.

    The text is drawn at twice the font's size where it fits, else at its size (a 640x360
    window), else cropped to the frame's right and bottom edges (a thumbnail)."""

    def __init__(self) -> None:
        self.lines: list[str] | None = None
        self.size: tuple[int, int] | None = None
        self.image: Any = None

    def draw(self, renderer: Renderer, lines: list[str], target: Any) -> None:
        from livedrummer.render.hud import hud_image

        fb_w, fb_h = renderer.size
        if lines != self.lines or renderer.size != self.size:
            self.lines, self.size = lines, renderer.size
            for scale in (2, 1):
                self.image = hud_image(lines, scale)
                h, w = self.image.shape[:2]
                if w + HUD_AT[0] <= fb_w and h + HUD_AT[1] <= fb_h:
                    break
            self.image = self.image[: max(0, fb_h - HUD_AT[1]), : max(0, fb_w - HUD_AT[0])]
        h, w = self.image.shape[:2]
        if w > 0 and h > 0:
            renderer.draw_overlay(self.image, (*HUD_AT, w, h), target)


def save_screenshot(data: bytes, size: tuple[int, int], path: Path) -> None:
    """A frame read from the window's framebuffer (RGB, bottom row first) as a PNG."""
    import numpy as np

    from .png import write_png

    w, h = size
    write_png(path, np.ascontiguousarray(np.frombuffer(data, np.uint8).reshape(h, w, 3)[::-1]))


def key_name(glfw: Any, key: int, mods: int) -> str:
    """GLFW key code and modifiers as the names :data:`KEYS` uses."""
    names = {
        glfw.KEY_SPACE: "space", glfw.KEY_RIGHT: "right", glfw.KEY_LEFT: "left",
        glfw.KEY_HOME: "home", glfw.KEY_END: "end", glfw.KEY_EQUAL: "equal",
        glfw.KEY_MINUS: "minus", glfw.KEY_KP_ADD: "kp_add",
        glfw.KEY_KP_SUBTRACT: "kp_subtract", glfw.KEY_LEFT_BRACKET: "left_bracket",
        glfw.KEY_RIGHT_BRACKET: "right_bracket", glfw.KEY_ESCAPE: "escape",
    }  # fmt: skip
    if key in names:
        name = names[key]
    elif glfw.KEY_A <= key <= glfw.KEY_Z:
        name = chr(ord("a") + key - glfw.KEY_A)
    elif glfw.KEY_0 <= key <= glfw.KEY_9:
        name = chr(ord("0") + key - glfw.KEY_0)
    else:
        return ""
    shifted = name in ("left", "right") or name.isdigit()  # seek steps; store a viewpoint
    return f"shift+{name}" if mods & glfw.MOD_SHIFT and shifted else name


def key_drum(body: BodyScene, map_name: str, sr: int | None = None) -> KeyDrum | None:
    """The keys' drum on the body's kit under the file's note map (None if it won't load), its
    sounds at the player's rate ``sr`` (default the mixer's)."""
    from livedrummer.errors import LivedrummerError
    from livedrummer.midi.notemap import load_note_map
    from livedrummer.render.keydrum import KeyDrum

    try:
        drum = KeyDrum(body.kit, load_note_map(map_name))
        return drum if sr is None else KeyDrum(body.kit, drum.note_map, sr)
    except LivedrummerError as err:
        log.warning("keys: no drum keys (%s)", err)
        return None


def show(
    performance: Performance,
    kit: Kit,
    options: WindowOptions = DEFAULT_OPTIONS,
    clock: Callable[[], float] = time.monotonic,
    body: BodyScene | None = None,
    avatar: Avatar | None = None,
    sound: Callable[[], TrackPlayer | None] | None = None,
    midi: MidiFileOut | None = None,
) -> None:
    """Open the window and play ``performance`` until the user quits (the drummer drawn as
    ``avatar``, by default the built-in character).

    ``body`` is the performance animated on ``kit``; without it the body is animated here with
    the defaults (optimal sticking) and the note map the performance was read with. ``sound``
    opens the player once the window is open (so a machine with no screen says only that);
    when it returns one the drum track sounds and its clock replaces ``clock``. ``midi`` gets
    the transport's position each frame and sends the file's notes to a sampler."""
    if body is None:
        from livedrummer.midi.notemap import load_note_map

        body = BodyScene.perform(performance, kit, load_note_map(performance.map_name))
    with open_window(options) as (glfw, window, ctx):
        player = sound() if sound is not None else None
        try:
            _loop(
                glfw,
                window,
                ctx,
                performance,
                body,
                options,
                player.now if player is not None else clock,
                avatar,
                player,
                midi,
            )
        finally:
            if player is not None:
                player.close()


@contextmanager
def open_window(options: WindowOptions) -> Iterator[tuple[Any, Any, Any]]:
    """A GLFW window with an OpenGL 3.3 core context made current, and its moderngl context:
    yields ``(glfw, window, ctx)`` and terminates GLFW afterwards."""
    import glfw
    import moderngl

    glfw.ERROR_REPORTING = "log"  # GLFW's complaints go to logging, not to warnings
    use_cpu_cores()  # llvmpipe's threads, where the window's context is software
    if not glfw.init():
        raise DisplayError("no display for a window (is DISPLAY set?); use `livedrummer render`")
    try:
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        glfw.window_hint(glfw.SAMPLES, options.samples)
        monitor = None
        size = options.size
        if options.fullscreen:
            monitors = glfw.get_monitors()
            if not 0 <= options.monitor < len(monitors):
                raise DisplayError(f"monitor {options.monitor}: there are {len(monitors)}")
            monitor = monitors[options.monitor]
            mode = glfw.get_video_mode(monitor)
            size = (mode.size.width, mode.size.height)
        window = glfw.create_window(size[0], size[1], "livedrummer", monitor, None)
        if not window:
            raise DisplayError("could not open an OpenGL 3.3 window")
        glfw.make_context_current(window)
        glfw.swap_interval(1 if options.vsync else 0)
        yield glfw, window, moderngl.create_context()
    finally:
        glfw.terminate()


def _loop(
    glfw: Any,
    window: Any,
    ctx: Any,
    performance: Performance,
    body: BodyScene,
    options: WindowOptions,
    clock: Callable[[], float],
    avatar: Avatar | None = None,
    player: TrackPlayer | None = None,
    midi: MidiFileOut | None = None,
) -> None:
    kit = body.kit
    transport = Transport(performance.duration_s + 1.0)
    cameras = kit_cameras(kit)
    move = CameraMove(cameras[options.camera], cameras[options.camera], 0.0, 0.0)
    mesh = build_kit_mesh(kit)
    size = glfw.get_framebuffer_size(window)
    renderer = Renderer(
        ctx,
        mesh,
        BODY_SKELETON,
        size,
        offscreen=False,
        avatar=avatar,
        background=options.background,
        lights=options.lights,
    )
    models = OverlayModels(body, transport.duration_s)
    shown = frozenset(options.overlays)
    strips = overlay_image(size, shown, models)
    pending: list[str] = []
    pads: list[tuple[int, int]] = []  # (note, velocity) of keys played since the last frame
    drum = key_drum(body, performance.map_name, player.sr if player is not None else None)

    def on_key(_w: Any, key: int, _scancode: int, action: int, mods: int) -> None:
        name = key_name(glfw, key, mods)
        if name in KEYPADS:  # a drum key: the first press only (repeat is no roll)
            hit = keypad_hit(name, bool(mods & glfw.MOD_SHIFT), bool(mods & glfw.MOD_CONTROL))
            if action == glfw.PRESS and hit is not None:
                pads.append(hit)
        elif action in (glfw.PRESS, glfw.REPEAT):
            pending.append(name)

    glfw.set_key_callback(window, on_key)
    view = ViewControl(glfw, window)
    transport.apply("play_pause")
    last = started = clock()
    frames = 0
    readout, show_readout, show_help = Readout(), True, False
    shot: tuple[tuple[int, int], bytes] | None = None
    camera = options.camera
    frame_log = options.frame_log.open("w") if options.frame_log is not None else None
    muted: str | None = None
    ahead = RenderAhead(quantile=0.5)  # with sound: draw for when the frame is seen
    while not glfw.window_should_close(window):
        if options.quit_after_s is not None and last - started >= options.quit_after_s:
            break
        glfw.poll_events()
        begun = time.monotonic()
        now = clock()
        for name in pending:
            if name in ("q", "escape"):
                glfw.set_window_should_close(window, True)
            elif name in KEYS:
                transport.apply(KEYS[name])
            elif name in OVERLAY_KEYS:
                shown = shown ^ {OVERLAY_KEYS[name]}
            elif name == "h":
                show_help = not show_help
            elif name == "i":
                show_readout = not show_readout
            elif name == "f":
                toggle_fullscreen(glfw, window, options)
            else:
                move, label = view.key(name, move, cameras, now)
                camera = label or camera
        pending.clear()
        for note, velocity in pads:
            sound = drum.hit(note, velocity, now) if drum is not None else None
            if sound is not None and player is not None:
                player.renderer.hit(sound)
            log.info("keys: note %d velocity %d", note, velocity)
        pads.clear()
        move = view.mouse(move, now, renderer.size)
        t = transport.advance(now - last)
        last = now
        if midi is not None:  # each note when the frame showing it is seen (drawn + swapped)
            reason = muted_reason(transport.playing, transport.speed, transport.reverse)
            midi.follow(t, time.monotonic() + ahead.seconds, transport.playing and reason is None)
        if player is not None or midi is not None:
            reason = muted_reason(transport.playing, transport.speed, transport.reverse)
            if reason != muted and reason is not None:
                log.info("window: %s (the drum track sounds at 1x forward)", reason)
            muted = reason
        if player is not None:
            player.follow(t, now, transport.playing and muted is None)
            if transport.playing:
                step = ahead.seconds * transport.speed
                t = min(max(t - step if transport.reverse else t + step, 0.0), transport.duration_s)
        fb = glfw.get_framebuffer_size(window)
        if fb != renderer.size and fb[0] > 0 and fb[1] > 0:
            renderer.size = fb
        frame = body.frame_at(t)
        if drum is not None:
            frame = drum.light(frame, now)
        renderer.draw(frame, move.at(now), target=ctx.screen)
        if strips.names != shown or strips.frame_size != renderer.size:
            strips = overlay_image(renderer.size, shown, models)
        if not strips.empty:
            r = strips.rect
            renderer.draw_overlay(strips.paint(t), (r.x, r.y, r.width, r.height), ctx.screen)
        if show_readout or show_help:
            from livedrummer.render.hud import hud_lines

            shown_step = None if transport.step_s == STEPS[0] else transport.step_s  # not default
            lines = hud_lines(
                t,
                transport.duration_s,
                transport.speed,
                transport.playing,
                transport.reverse,
                camera,
                show_help,
                transport.loop,
                shown_step,
            )
            readout.draw(renderer, lines + ([muted.upper()] if muted else []), ctx.screen)
        if options.screenshot is not None:  # read before the swap: the back buffer is defined
            shot = (renderer.size, ctx.screen.read(viewport=(0, 0, *renderer.size), components=3))
        glfw.swap_buffers(window)
        ahead.add(time.monotonic() - begun)
        if frame_log is not None:
            frame_log.write(f'{{"mono": {time.monotonic():.6f}, "t": {t:.6f}}}\n')
        frames += 1
    if frame_log is not None:
        frame_log.close()
    if shot is not None and options.screenshot is not None:
        save_screenshot(shot[1], shot[0], options.screenshot)
    elapsed = clock() - started
    log.info("window: %d frames in %.2f s (%.1f fps)", frames, elapsed, frames / max(elapsed, 1e-9))
