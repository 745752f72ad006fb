"""``render --jobs N``: frames drawn by worker processes are the frames one process draws.

The deal of frames (:mod:`livedrummer.render.frame_split`) is pure logic; the workers are real
forked processes, each with its own EGL context (llvmpipe where there is no GPU), and the
comparisons are of the PNG files' pixels and of the videos decoded by PyAV.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import av
import numpy as np
import pytest

from livedrummer.errors import ConfigError
from livedrummer.render.frame_split import (
    default_jobs,
    owner_of,
    parse_jobs,
    threads_per_worker,
    usable_cores,
    worker_frames,
)
from services.cli import main
from services.display.context import DisplayError
from services.display.parallel import FrameStream, frame_stream
from tests.livedrummer.stage.test_stage import write_band

SIZE = "256x144"


@pytest.mark.parametrize(("frames", "jobs", "chunk"), [(0, 2, 4), (1, 3, 4), (37, 2, 16),
                                                       (100, 3, 7), (64, 4, 16)])  # fmt: skip
def test_workers_share_every_frame_once_in_chunks(frames: int, jobs: int, chunk: int) -> None:
    dealt = [worker_frames(frames, jobs, k, chunk) for k in range(jobs)]
    every = np.sort(np.concatenate(dealt))
    assert every.tolist() == list(range(frames))
    for k, mine in enumerate(dealt):
        assert (np.diff(mine) > 0).all()
        assert all(owner_of(int(i), jobs, chunk) == k for i in mine)
        assert all(int(i) // chunk % jobs == k for i in mine)


def test_jobs_and_threads_fit_the_cores() -> None:
    assert default_jobs(2, 1000) == 2
    assert default_jobs(16, 64, chunk=16) == 2  # two chunks at least for each worker
    assert default_jobs(16, 48, chunk=16) == 1
    assert default_jobs(8, 1) == 1
    assert threads_per_worker(2, 2) == 1
    assert threads_per_worker(16, 2) == 8
    assert threads_per_worker(2, 4) == 1
    assert parse_jobs("auto") is None
    assert parse_jobs(None) is None
    assert parse_jobs(" 3 ") == 3


@pytest.mark.parametrize("text", ["0", "-1", "two", "65", "1.5", ""])
def test_bad_jobs_are_named(text: str) -> None:
    with pytest.raises(ConfigError, match=r"--jobs .*expected auto or a worker count 1\.\.64"):
        parse_jobs(text)


def _numbered(wanted: np.ndarray) -> Iterator[np.ndarray | None]:
    """A draw without a GPU: frame i is an array full of i (and it checks it is asked in order)."""
    for i in range(int(wanted[-1]) + 1):
        yield np.full((3, 5), i % 251, np.uint8)


def test_forked_workers_hand_frames_back_in_order() -> None:
    stream = FrameStream.fork(_numbered, 70, jobs=3, threads=1, chunk=4)
    try:
        assert stream.workers == 3
        got = [int(image[0, 0]) for image in stream if image is not None]
    finally:
        stream.close()
    assert got == [i % 251 for i in range(70)]
    assert len(stream.cpu_s) == 3 and all(s >= 0.0 for s in stream.cpu_s)  # each one's report


def _failing(wanted: np.ndarray) -> Iterator[np.ndarray | None]:
    for i in range(int(wanted[-1]) + 1):
        if i == 21:
            raise ValueError("frame 21 cannot be drawn")
        yield np.zeros((2, 2), np.uint8)


def test_a_failing_worker_is_named_with_its_error() -> None:
    stream = FrameStream.fork(_failing, 40, jobs=2, threads=1, chunk=4)
    try:
        with pytest.raises(DisplayError, match=r"render worker 1: frame 21 cannot be drawn"):
            for _image in stream:
                pass
    finally:
        stream.close()


def read_png(path: Path) -> np.ndarray:
    """A PNG's RGB pixels, decoded by PyAV (FFmpeg's PNG decoder: a reader of its own)."""
    with av.open(str(path)) as container:
        return next(container.decode(video=0)).to_ndarray(format="rgb24")


def _render(*extra: str) -> None:
    code = main(
        [
            "render",
            "--size",
            SIZE,
            "--fps",
            "20",
            "--start",
            "2.5",
            "--end",
            "4.2",
            "--tail",
            "0",
            *extra,
        ]
    )
    assert code == 0


def test_a_scene_that_cannot_go_to_workers(caplog: pytest.LogCaptureFixture) -> None:
    """A draw that does not pickle (a local function here): asked for 2 workers, a named
    error; on auto, the frames are drawn in this process, with a warning on a multi-core box."""
    calls = []

    def local(wanted: np.ndarray) -> Iterator[np.ndarray | None]:
        calls.append(wanted.size)
        yield from _numbered(wanted)

    with pytest.raises(DisplayError, match=r"cannot send the scene to them .*use --jobs 1"):
        frame_stream(local, 40, jobs=2, chunk=4)
    stream = frame_stream(local, 40, jobs=None, chunk=4)
    try:
        got = [int(image[0, 0]) for image in stream if image is not None]
    finally:
        stream.close()
    assert got == list(range(40))
    assert calls == [40]  # one draw, here, of every frame
    if usable_cores() > 1:
        assert "drawing in this process" in caplog.text


@pytest.mark.usefixtures("gl_ok")  # which also makes a context here first: workers still start
def test_workers_draw_the_frames_one_process_draws(tmp_path: Path) -> None:
    """PNGs from 2 workers (one llvmpipe thread each) equal one process's, pixel for pixel;
    the span starts mid-file, so the face's reactions to hits before each chunk count."""
    one, two = tmp_path / "one", tmp_path / "two"
    _render("--jobs", "1", "--frames-dir", str(one))
    _render("--jobs", "2", "--frames-dir", str(two))
    names = sorted(p.name for p in one.iterdir())
    assert len(names) == 34  # 1.7 s at 20 fps: chunks 0 and 2 by worker 0, 1 by worker 1
    assert names == sorted(p.name for p in two.iterdir())
    for name in names:
        a, b = read_png(one / name), read_png(two / name)
        assert a.shape == (144, 256, 3)
        assert np.array_equal(a, b), name
    assert len({read_png(one / n).tobytes() for n in names}) > 10  # the drummer moves


def _decoded(path: Path) -> list[np.ndarray]:
    with av.open(str(path)) as container:
        return [f.to_ndarray(format="yuv420p") for f in container.decode(video=0)]


@pytest.mark.usefixtures("gl_ok")
def test_a_video_from_workers_decodes_to_one_process_frames(tmp_path: Path) -> None:
    one, two = tmp_path / "one.mp4", tmp_path / "two.mp4"
    _render("--jobs", "1", "-o", str(one))
    _render("--jobs", "3", "-o", str(two))
    a, b = _decoded(one), _decoded(two)
    assert len(a) == len(b) == 34
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        assert np.array_equal(x, y), f"frame {i}"


@pytest.mark.usefixtures("gl_ok")
def test_a_stage_from_workers_is_one_process_stage(tmp_path: Path) -> None:
    """``render --stage``: two drummers, each with its own face, 2 workers or one process."""
    counts = write_band(tmp_path / "band.mid")
    (tmp_path / "duo.toml").write_text(
        '[formation]\nshape = "line"\nspacing = 4.0\n\n'
        + "".join(
            f'[[performer]]\nid = "d{c}"\nfile = "band.mid"\nchannel = {c}\n'
            f'map = "general-midi"\n\n'
            for c in list(counts)[:2]
        )
    )
    dirs = []
    for jobs in ("1", "2"):
        dirs.append(tmp_path / f"jobs{jobs}")
        assert (
            main(
                [
                    "render",
                    "--stage",
                    str(tmp_path / "duo.toml"),
                    "--frames-dir",
                    str(dirs[-1]),
                    "--size",
                    "192x108",
                    "--fps",
                    "12",
                    "--end",
                    "3",
                    "--jobs",
                    jobs,
                ]
            )
            == 0
        )
    names = sorted(p.name for p in dirs[0].iterdir())
    assert len(names) == 36
    assert names == sorted(p.name for p in dirs[1].iterdir())
    for name in names:
        assert np.array_equal(read_png(dirs[0] / name), read_png(dirs[1] / name)), name


def test_bad_jobs_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["render", "--jobs", "0", "-o", str(tmp_path / "x.mp4")])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err == "livedrummer: error: --jobs 0: expected auto or a worker count 1..64"
    assert not list(tmp_path.iterdir())
