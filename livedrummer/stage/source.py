"""A live performer's ``source`` in a stage file: what its input daemon opens.

Syntax (one string, ``KIND:VALUE[,key=value...]``)::

    midi:PORT                      a kit on a MIDI port (name or substring)
    virtual:NAME                   a virtual MIDI input NAME that a keyboard or a DAW plays
    serial:DEV                     a serial trigger board (31250 baud)
    file:PART.mid                  a MIDI file played as if live, looped (rehearsals, tests)
    remote:ENDPOINT                another site's input daemon (its pub), hits stamped on arrival
    remote:ENDPOINT,control=EP     ... with its control endpoint: clock offset and jitter buffer
                                   keep the remote drummer's timing (``input --remote-control``)

Endpoints are ZeroMQ TCP endpoints (``tcp://HOST:PORT``); a ``file`` path is relative to the
stage file. Pure parsing: :func:`parse_source` raises ``ValueError`` with the problem, which
the stage file reader turns into one line naming the file and the performer.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

KINDS = ("midi", "virtual", "serial", "file", "remote")
_ENDPOINT = re.compile(r"^tcp://[^\s:/]+:\d{1,5}$")


@dataclass(frozen=True)
class LiveSource:
    kind: str  # one of KINDS
    value: str  # the port, name, device, file path or endpoint
    control: str | None = None  # remote: the other site's control endpoint (clock sync)

    def input_argv(self) -> list[str]:
        """The ``livedrummer input`` options that open this source."""
        if self.kind == "midi":
            return ["--midi", self.value]
        if self.kind == "virtual":
            return ["--virtual", self.value]
        if self.kind == "serial":
            return ["--serial", self.value]
        if self.kind == "file":
            return ["--file", self.value, "--loop"]
        extra = [] if self.control is None else ["--remote-control", self.control]
        return ["--remote", self.value, *extra]

    @property
    def opens_midi(self) -> bool:
        """Whether the source is a MIDI port of this machine (``--api`` applies)."""
        return self.kind in ("midi", "virtual")


def parse_source(text: str, folder: Path | None = None) -> LiveSource:
    """Parse a ``source`` string (see the module docstring); ``folder`` resolves files."""
    kind, sep, rest = text.partition(":")
    if not sep or kind not in KINDS:
        raise ValueError(f"expected KIND:VALUE with KIND one of {', '.join(KINDS)}")
    value, *options = rest.split(",")
    value = value.strip()
    if not value:
        raise ValueError(f"{kind}: nothing after the colon")
    control = None
    for opt in options:
        key, eq, val = opt.partition("=")
        if kind != "remote" or key.strip() != "control" or not eq:
            raise ValueError(f"unknown option {opt.strip()!r} (only remote takes control=EP)")
        control = val.strip()
        if not _ENDPOINT.match(control):
            raise ValueError(f"control={control!r}: expected tcp://HOST:PORT")
    if kind == "remote" and not _ENDPOINT.match(value):
        raise ValueError("remote: expected tcp://HOST:PORT")
    if kind == "file" and folder is not None:
        value = str(folder / value)
    return LiveSource(kind, value, control)
