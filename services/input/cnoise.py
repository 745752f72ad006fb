"""C libraries' own stderr lines, caught while a MIDI client starts, logged at debug level.

Why. libasound prints ``ALSA lib seq_hw.c:...`` and libjack prints five lines ("Cannot
connect to server socket", ...) straight to file descriptor 2 whenever a client cannot
start; a daemon retrying a missing MIDI system ten times a second turned that into hundreds
of lines, drowning the one line that says what is wrong. :func:`c_stderr_to_log` points fd 2
at a temporary file for the duration of a client's creation (and deletion) and hands what was
written there to the ``livedrummer.input`` logger at debug level (``-v`` shows it); the
caller's own error (a :class:`~livedrummer.errors.MidiInputError`) stays the one line.

Limits: fd 2 is process-wide, so a line another thread writes to stderr in that window (a
few milliseconds) is logged at debug level too instead of printed; JACK's lines written
later from its own threads are not caught.
"""

from __future__ import annotations

import logging
import os
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager

log = logging.getLogger("livedrummer.input")


@contextmanager
def c_stderr_to_log(what: str) -> Iterator[None]:
    """Catch what C code writes to fd 2 inside the block; log it at debug level."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except OSError:  # no stderr at all: nothing to keep quiet
        yield
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            for line in sink.read().decode(errors="replace").splitlines():
                if line.strip():
                    log.debug("%s: %s", what, line.strip())
