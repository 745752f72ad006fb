"""Where a benchmark finds its inputs: the source checkout, the corpus, the bundled data.

Benchmarks run from a source checkout (``livedrummer bench NAME`` or ``python -m services
bench NAME``) and from an installed wheel, where they live in ``livedrummer._services.bench``
and there is no checkout around them. :data:`CHECKOUT` is the checkout's root, or None inside
a wheel. The Groove MIDI Dataset is looked for beside the checkout (``../shared/data/groove``,
the layout CI provides); from a wheel, or when it is elsewhere, ``--corpus DIR`` names it and
:func:`corpus` says so in one line instead of searching site-packages. Bundled files (the demo
groove, kits, shaders) come from :func:`livedrummer.resources.data_dir` in both layouts.
"""

from __future__ import annotations

from pathlib import Path

from livedrummer.errors import ConfigError

HERE = Path(__file__).resolve().parent


def _checkout() -> Path | None:
    root = HERE.parent.parent
    if (root / "pyproject.toml").is_file() and (root / "livedrummer").is_dir():
        return root
    return None


#: The source checkout this code runs from, or None inside an installed wheel.
CHECKOUT = _checkout()
#: The working folder for child processes: the checkout, else where the user ran the command.
WORKDIR = CHECKOUT or Path.cwd()
#: Where the Groove MIDI Dataset is looked for when ``--corpus`` is not given.
DEFAULT_CORPUS = (CHECKOUT or Path.cwd()).parent / "shared" / "data" / "groove"


def corpus(path: Path, what: str = "--corpus") -> Path:
    """``path`` if it is a folder holding MIDI files, else a one-line error naming the option."""
    if path.is_dir() and next(path.rglob("*.mid"), None) is not None:
        return path
    where = "an installed wheel has no corpus beside it" if CHECKOUT is None else "not found"
    raise ConfigError(
        f"{path}: no Groove MIDI Dataset here ({where}); pass {what} DIR, the dataset's folder "
        "of .mid files (https://magenta.tensorflow.org/datasets/groove, CC BY 4.0)"
    )
