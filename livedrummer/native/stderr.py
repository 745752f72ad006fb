"""C libraries' own stderr lines, caught while they start, handed to a logger at debug level.

Why. libasound prints ``ALSA lib seq_hw.c:...`` and libjack prints five lines ("Cannot
connect to server socket", ...) straight to file descriptor 2 whenever a client cannot start;
Debian's FluidSynth tries its libinstpatch DLS reader on a file its SF2 reader refused, and
GLib prints CRITICAL lines. A daemon retrying a missing MIDI system ten times a second turned
that into hundreds of lines, drowning the one line that says what is wrong.
:func:`native_stderr_to_log` points fd 2 at a temporary file for the duration of a block and
hands what was written there to a logger at debug level (``-v`` shows it); the caller's own
error stays the one line. The MIDI input (:mod:`services.input.midiport`) and the SoundFont
loader (:mod:`livedrummer.audio.soundfont`) both use it.

Limits: fd 2 is process-wide, so a line another thread writes to stderr in that window (a
few milliseconds) is logged at debug level too instead of printed; lines a library writes
later from its own threads are not caught.
"""

from __future__ import annotations

import logging
import os
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def native_stderr_to_log(log: logging.Logger, what: str) -> Iterator[None]:
    """Catch what C code writes to fd 2 inside the block; log it at debug level as
    ``what: line``."""
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
