"""Render docs/assets/default-character.png, the picture of the built-in drummer in the docs.

The demo groove (Roland map, rock5 kit) performed by the body model, 2.05 s in, seen from the
``front`` camera at 720x405 with 4x multisampling. Run from the repository root:
``.venv/bin/python deploy/media/default_character.py``.
"""

from __future__ import annotations

from pathlib import Path

from livedrummer.kit.loader import load_kit
from livedrummer.midi.notemap import load_note_map
from livedrummer.midi.smf import read_midi_file
from livedrummer.render.body_scene import BODY_SKELETON, BodyScene
from livedrummer.render.camera import pick_camera
from livedrummer.render.kitmesh import build_kit_mesh
from services.cli.files import DEMO_MAP, demo_groove
from services.display.context import headless_context
from services.display.png import write_png
from services.display.renderer import Renderer

OUT = Path(__file__).resolve().parents[2] / "docs" / "assets" / "default-character.png"


def main() -> None:
    kit = load_kit("rock5")
    note_map = load_note_map(DEMO_MAP)
    body = BodyScene.perform(read_midi_file(demo_groove(), note_map), kit, note_map)
    ctx = headless_context()
    renderer = Renderer(ctx, build_kit_mesh(kit), BODY_SKELETON, (720, 405), samples=4)
    renderer.draw(body.frame_at(2.05), pick_camera(kit, "front"))
    write_png(OUT, renderer.read_rgb())


if __name__ == "__main__":
    main()
