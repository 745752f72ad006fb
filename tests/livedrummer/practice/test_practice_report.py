"""The practice reports in a real headless Chromium: the page loads and every plot renders."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.practice_takes import plant_take

SCRIPT = Path(sys.executable).parent / "livedrummer"
SOUL = "drummer1/eval_session/3_soul-groove3_86_beat_4-4.mid"

# Appended to a copy of the report (the report itself has no script): once every plot has a
# size, the title says how many plots there are and the smallest width and height.
PROBE = """<script>
window.addEventListener('load', () => {
  const boxes = [...document.querySelectorAll('svg, img')].map(e => e.getBoundingClientRect());
  const w = Math.min(...boxes.map(b => b.width)), h = Math.min(...boxes.map(b => b.height));
  document.title = 'plots=' + boxes.length + ' minw=' + Math.round(w) + ' minh=' + Math.round(h);
});
</script>"""


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    if os.environ.get("CI"):
        pytest.fail("chromium is not installed (deploy/system-deps.sh installs it)")
    pytest.skip("chromium is not installed")


def browse(page: Path, tmp_path: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [
            chromium(),
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            f"--user-data-dir={tmp_path / 'chromium'}",
            "--window-size=1100,2400",
            *extra,
            page.as_uri(),
        ],
        capture_output=True,
        text=True,
        timeout=90,
    )


def run(*args: str, **env: str) -> subprocess.CompletedProcess[str]:
    command = [str(SCRIPT)] if SCRIPT.exists() else [sys.executable, "-m", "services"]
    return subprocess.run(
        [*command, *args], capture_output=True, text=True, timeout=120, env={**os.environ, **env}
    )


def plots_in(report: Path, tmp_path: Path) -> str:
    probe = tmp_path / f"probe-{report.name}"
    probe.write_text(report.read_text(encoding="utf-8").replace("</body>", PROBE + "</body>"))
    proc = browse(probe, tmp_path, "--dump-dom", "--virtual-time-budget=3000")
    assert proc.returncode == 0, proc.stderr[-2000:]
    start = proc.stdout.index("<title>") + len("<title>")
    return proc.stdout[start : proc.stdout.index("</title>")]


def test_take_and_history_reports_render_in_chromium(groove_dir: Path, tmp_path: Path) -> None:
    ref = groove_dir / SOUL
    take = tmp_path / "take.mid"
    plant_take(ref, take, seed=5)
    report = tmp_path / "take.html"
    home = str(tmp_path / "home")
    proc = run(
        "practice",
        "score",
        str(ref),
        str(take),
        "--map",
        "roland-td",
        "--take-map",
        "roland-td",
        "--report",
        str(report),
        "--save",
        LIVEDRUMMER_HOME=home,
    )
    assert proc.returncode == 0, proc.stderr
    text = report.read_text(encoding="utf-8")
    # Self-contained: no link leaves the page (only the SVGs' own #id references).
    assert re.findall(r'(?:src|href)="(?!#)', text) == []
    title = plots_in(report, tmp_path)
    fields = dict(part.split("=") for part in title.split())
    assert fields["plots"] == "4", title  # timing, histograms, drift, limbs
    assert int(fields["minw"]) > 300 and int(fields["minh"]) > 100, title
    shot = tmp_path / "shot.png"
    proc = browse(report, tmp_path, f"--screenshot={shot}")
    assert proc.returncode == 0, proc.stderr[-2000:]
    import matplotlib.pyplot as plt

    pixels = plt.imread(shot)[..., :3]
    ink = np.mean(pixels < 0.9)  # share of pixels that are not near white
    assert 0.03 < ink < 0.8, ink
    assert np.unique((pixels * 8).astype(int).reshape(-1, 3), axis=0).shape[0] > 20  # colours

    history = tmp_path / "history.html"
    proc = run("practice", "history", "--report", str(history), LIVEDRUMMER_HOME=home)
    assert proc.returncode == 0, proc.stderr
    assert "1_funk" not in proc.stdout and "3_soul-groove3_86_beat_4-4.mid" in proc.stdout
    title = plots_in(history, tmp_path)
    assert title.startswith("plots=1 "), title
    assert int(dict(p.split("=") for p in title.split())["minh"]) > 100, title
