"""How one livedrummer process starts another: the same interpreter, the same package.

The process layer is the package ``services`` in a source checkout (and an editable install)
and ``livedrummer._services`` inside an installed wheel (which puts nothing but
``livedrummer`` into site-packages). Every module here imports its siblings relatively, so
the code is the same under both names; a child process (``up`` starting input, synth and
displays, a benchmark starting a daemon) is started with ``python -m`` and this package's
own name, so it runs the same copy of the code as its parent.
"""

from __future__ import annotations

import sys

#: ``services`` in a checkout, ``livedrummer._services`` in a wheel.
#: (This module lives in the package's ``process`` folder: the package is its parent.)
PACKAGE = (__package__ or __name__.rpartition(".")[0]).rpartition(".")[0] or "services"


def program_argv(*args: str) -> list[str]:
    """The command line that runs ``livedrummer ARGS`` with this interpreter and package."""
    return [sys.executable, "-m", PACKAGE, *args]
