"""Render docs/assets/frames/*.png, the frames the avatar guide shows (issue 28's item 7).

Each is one frame, 6.5 s into the demo groove at 640x360, drawn by ``livedrummer render``
itself (the concert look, FXAA): the ``front``, ``stage`` and ``drummer`` cameras with the
built-in character; ``front`` with a 0.66 m VRM 1.0 (the test suite's generated humanoid,
written to a temporary folder), which ``--fit auto`` scales to the kit; and ``render
--stage`` of one performer with three ensemble copies on an arc (spacing 3.0). Run from the
repository root: ``.venv/bin/python deploy/media/frames.py``.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
OUT = REPO / "docs" / "assets" / "frames"
GROOVE = REPO / "kits" / "grooves" / "gmd-drummer1-funk-80.mid"
AT_S = 6.5


def frame(name: str, tmp: Path, *extra: str) -> None:
    """One frame of ``livedrummer render ... extra`` at :data:`AT_S` into OUT/name.png."""
    folder = tmp / name
    argv = [sys.executable, "-m", "services", "render", "--frames-dir", str(folder), "--start",
            str(AT_S), "--end", f"{AT_S + 0.02:.2f}", "--size", "640x360", *extra]  # fmt: skip
    subprocess.run(argv, check=True, cwd=REPO)
    shutil.copy(sorted(folder.glob("*.png"))[0], OUT / f"{name}.png")


def main() -> None:
    sys.path.insert(0, str(REPO / "tests"))
    from avatar_files import Spec, build

    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as name:
        tmp = Path(name)
        for camera in ("front", "stage", "drummer"):
            frame(camera, tmp, "--camera", camera)
        vrm = tmp / "small.vrm"
        vrm.write_bytes(build(Spec(height_m=0.66, pose="A", facing="+z", vrm="1", faces=True)))
        frame("front-vrm-0.66m", tmp, "--camera", "front", "--avatar", str(vrm))
        stage = tmp / "arc.toml"
        stage.write_text(
            f'[formation]\nshape = "arc"\nspacing = 3.0\n\n[[performer]]\nid = "a"\n'
            f'file = "{GROOVE}"\nmap = "roland-td"\n\n[ensemble]\ncopies = 3\n'
        )
        frame("stage-arc-3-copies", tmp, "--stage", str(stage))


if __name__ == "__main__":
    main()
