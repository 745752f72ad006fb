"""The practice rig's part of a live display: the teacher drummer and the readout.

``livedrummer practice REF --virtual Kit`` runs a live display (``display --live``) with a
:class:`PracticeView`, which the display's loop calls once per frame after it drew the player
(:class:`~services.display.live.LiveConfig` ``extra``). It reads the rig's readout stream, a
SUB socket on loopback carrying one JSON object a message (``{"plan": ...}``,
``{"plan_again": ...}``, ``{"hit": ...}``, ``{"summary": ...}``: sent by
:mod:`services.practice.readout_out`); a message that is not JSON or not one of those is
dropped and counted (:class:`~services.wire.badmsg.BadMessages`), never fatal. Plans also feed the
teacher's clock (:class:`~livedrummer.practice.teacher.TeacherClock`).

The teacher is the reference animated offline (``teacher``: a
:class:`~livedrummer.render.body_scene.BodyScene`, made once when the display starts), drawn at
the reference second the clock gives for the frame's show time, from the camera the player's
frame was drawn from (``surface.view``):

* ``ghost``: the body alone (transparent background; the kit drawn into depth only first, so
  the ghost is hidden where a drum or a stand is in front of it, as the player's body is) in
  an off-screen renderer of the frame's size, recoloured translucent by
  :func:`~livedrummer.render.ghost.ghost_image` and blended over the player's frame: where the
  player's sticks should be now;
* ``ahead``: the whole scene (kit and teacher) in a third-size inset at the top right, ahead by
  the clock's ``ahead_s``, with a label; the player sees what comes next beside their own
  drummer.

Then the readout (:mod:`livedrummer.render.practice_hud`) is blended bottom left, repainted only
when a message changed it. Each frame's teacher time is kept in :attr:`last_reference_s` (the
display writes it to ``frames.jsonl``, with the readout's version, so tests and benches can
check the teacher and the readout without pixels).

Cost: one more scene render per frame (the ghost's body alone over the kit's depth, or the
inset's small frame; no shadow pass in either) and its read-back; ``livedrummer bench
practice_view`` measures it (on llvmpipe the ghost nearly doubles a 640x360 frame). Limits:
the teacher is depth-tested against the kit but not against the player (a ghost is seen
through); one teacher; resizing the window builds the teacher's renderer anew (the old one's
GL objects stay until the window closes).
"""

from __future__ import annotations

import json
import logging
from typing import Any, Literal

import numpy as np
import zmq

from livedrummer.avatar.model import Avatar
from livedrummer.kit.model import Kit
from livedrummer.practice.teacher import PassTime, TeacherClock
from livedrummer.render.background import Background
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.ghost import ghost_image
from livedrummer.render.kitmesh import build_kit_mesh
from livedrummer.render.overlay_raster import draw_text
from livedrummer.render.practice_hud import PracticePanel, panel_image

from ..wire.badmsg import BadMessages
from ..wire.net import connect, socket
from ..wire.stream_rx import DRAIN_BUDGET, waiting
from .renderer import Renderer

log = logging.getLogger("livedrummer.display")
TeacherMode = Literal["ghost", "ahead", "off"]
#: The ahead inset's share of the frame's width and height.
INSET = 1 / 3
MARGIN = 8


class PracticeView:
    """See the module docstring."""

    def __init__(
        self,
        ctx: zmq.Context[zmq.Socket[bytes]],
        endpoint: str,
        kit: Kit,
        mode: TeacherMode = "off",
        teacher: BodyScene | None = None,
        ahead_s: float = 0.0,
        avatar: Avatar | None = None,
    ) -> None:
        if mode != "off" and teacher is None:
            raise ValueError(f"teacher {mode}: needs the reference's body scene")
        self.kit, self.mode, self.teacher, self.avatar = kit, mode, teacher, avatar
        self.clock = TeacherClock(ahead_s if mode == "ahead" else 0.0)
        self.panel = PracticePanel()
        self.bad = BadMessages("practice readout stream", log)
        self.messages = 0
        self.last_reference_s: float | None = None
        self._sub = socket(ctx, zmq.SUB)
        self._sub.setsockopt(zmq.SUBSCRIBE, b"")
        connect(self._sub, endpoint, "practice readout endpoint")
        self._renderer: Renderer | None = None
        self._image: tuple[tuple[int, int], np.ndarray] | None = None  # ((version, scale), image)

    # -- the stream ------------------------------------------------------------------------

    def poll(self) -> None:
        """Apply every message waiting; a bad one is counted and dropped."""
        for data in waiting(self._sub, DRAIN_BUDGET, multipart=False):
            try:
                msg = json.loads(data)
                if not isinstance(msg, dict):
                    raise TypeError(f"expected an object, got {type(msg).__name__}")
                if "plan_again" not in msg:  # a plan sent again moves the teacher only
                    self.panel.apply(msg)
                p = msg.get("plan", msg.get("plan_again"))
                if p is not None:
                    self.clock.add(
                        PassTime(
                            float(p["start_s"]),
                            float(p["scale"]),
                            float(p["seg_start_s"]),
                            float(p["seg_end_s"]),
                        )
                    )
            except (ValueError, KeyError, TypeError, IndexError) as exc:
                self.bad.count(type(exc).__name__, str(exc))
                continue
            self.messages += 1

    # -- drawing ---------------------------------------------------------------------------

    def draw(self, surface: Any, show_s: float) -> None:
        """The teacher and the readout over the frame the surface just drew."""
        self.poll()
        target = getattr(surface, "target", None)
        if self.mode != "off":
            self._draw_teacher(surface, show_s, target)
        fw, fh = surface.renderer.size
        key = (self.panel.version, 2 if fh >= 480 else 1)  # the font's size follows the frame's
        if self._image is None or self._image[0] != key:
            self._image = (key, panel_image(self.panel, key[1]))
        image = self._image[1]  # cropped to the frame when a long summary does not fit
        image = np.ascontiguousarray(image[: max(0, fh - 2 * MARGIN), : max(0, fw - 2 * MARGIN)])
        h, w = image.shape[:2]
        if w > 0 and h > 0:
            surface.renderer.draw_overlay(image, (MARGIN, fh - h - MARGIN, w, h), target)

    def _draw_teacher(self, surface: Any, show_s: float, target: Any) -> None:
        ref = self.clock.reference_s(show_s)
        self.last_reference_s = ref
        view = getattr(surface, "view", None)
        if ref is None or view is None or self.teacher is None:
            return
        main = surface.renderer
        fw, fh = main.size
        if self.mode == "ghost":
            size = (fw, fh)
        else:
            size = (max(16, int(fw * INSET)) // 2 * 2, max(16, int(fh * INSET)) // 2 * 2)
        if self._renderer is None or self._renderer.size != size:
            mesh = build_kit_mesh(self.kit)
            ghost = self.mode == "ghost"
            self._renderer = Renderer(
                main.ctx,
                mesh,
                BODY_SKELETON,
                size,
                samples=0,
                avatar=self.avatar,
                shadows=False,
                background=Background(kind="transparent") if ghost else None,
                kit_occludes_only=ghost,
            )
        r = self._renderer
        r.lights = main.lights  # the teacher stands under the player's lights
        r.draw(self.teacher.frame_at(ref), view)
        rgba = r.read_rgba_top()
        if self.mode == "ghost":
            main.draw_overlay(ghost_image(rgba), (0, 0, fw, fh), target)
            return
        image = rgba.copy()
        image[..., 3] = 255
        label = f"TEACHER +{self.clock.ahead_s:.2f} S"
        draw_text(image, label, 4, 4, 1 if size[1] < 200 else 2, (40, 235, 255, 255))
        image[:2, :] = image[-2:, :] = image[:, :2] = image[:, -2:] = (40, 235, 255, 255)
        main.draw_overlay(image, (fw - size[0] - MARGIN, MARGIN, *size), target)

    def record(self) -> dict[str, Any]:
        return {"teacher_s": self.last_reference_s, "readout": self.panel.version}

    def close(self) -> None:
        self._sub.close(0)
        self.bad.log_summary()
