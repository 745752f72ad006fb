"""SFZ drum kits: the text format parsed, strictly, into regions (pure: no audio is read here).

SFZ is the open sampler format: headers (``<control>``, ``<global>``, ``<master>``,
``<group>``, ``<region>``) each followed by ``opcode=value`` pairs; a region inherits the
opcodes of the global, master and group above it and overrides them. A value runs to the
next opcode or header on its line, so a sample path may hold spaces; ``//`` starts a comment
to the end of the line and ``/* */`` spans lines. ``<control>``'s ``default_path`` is put in
front of every sample path, which is relative to the .sfz file's folder (``\\`` read as
``/``).

The subset drum kits use is understood (:data:`KNOWN`): ``sample``; ``key`` or
``lokey``/``hikey`` (MIDI numbers or note names, ``c4`` = 60) and ``pitch_keycenter``;
``lovel``/``hivel``; round robin by ``seq_length``/``seq_position`` or by
``lorand``/``hirand``; choke groups ``group``/``off_by``; ``ampeg_release`` (seconds);
``loop_mode`` (``one_shot`` and ``no_loop`` play the whole sample; drums have no note-off);
``volume`` (dB), ``pan`` (-100..100), ``tune`` (cents). Any other opcode is kept in
:attr:`SfzKit.unknown` (name -> first line) for the caller to list once; it is not an error.
A value that is not what its opcode takes (``lovel=loud``, ``pan=300``) is an
:class:`SfzError` naming the file, the line, the opcode and the value; so is an opcode
outside a header, a region without a sample and an unknown header.

Limits: ``#define`` and ``#include`` are not expanded (listed as unknown); no
``<curve>``/``<effect>``/``<midi>`` headers; velocity tracking is the SFZ default (100 %, gain
``(velocity / 127)²``); looping modes other than the two above are read but played as
one-shots.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from livedrummer.errors import LivedrummerError

KNOWN = frozenset({
    "sample", "key", "lokey", "hikey", "pitch_keycenter", "lovel", "hivel", "seq_length",
    "seq_position", "lorand", "hirand", "group", "off_by", "ampeg_release", "loop_mode",
    "volume", "pan", "tune", "default_path",
})  # fmt: skip
HEADERS = ("control", "global", "master", "group", "region")
NOTE_NAMES = {"c": 0, "d": 2, "e": 4, "f": 5, "g": 7, "a": 9, "b": 11}
LOOP_MODES = ("no_loop", "one_shot", "loop_continuous", "loop_sustain")
_TOKEN = re.compile(r"<(\w+)>|([A-Za-z_][A-Za-z0-9_]*)=")


class SfzError(LivedrummerError):
    """An SFZ file (or a sample it names) cannot be used; the message names file and line."""


@dataclass(frozen=True)
class Region:
    """One region: what it plays and when. ``line`` is where its ``<region>`` header is."""

    sample: Path
    line: int
    sample_line: int  # where its ``sample`` opcode is (errors about the file name it)
    lokey: int = 0
    hikey: int = 127
    lovel: int = 1
    hivel: int = 127
    keycenter: int = 60
    seq_length: int = 1
    seq_position: int = 1
    lorand: float = 0.0
    hirand: float = 1.0
    group: int = 0
    off_by: int = 0
    release_s: float = 0.001
    loop_mode: str = "no_loop"
    volume_db: float = 0.0
    pan: float = 0.0
    tune_cents: float = 0.0

    def plays(self, note: int, velocity: int) -> bool:
        return self.lokey <= note <= self.hikey and self.lovel <= velocity <= self.hivel


@dataclass
class SfzKit:
    path: Path
    regions: list[Region] = field(default_factory=list)
    unknown: dict[str, int] = field(default_factory=dict)  # opcode or directive -> first line


def note_number(text: str) -> int | None:
    """A MIDI note from a number or a name (``c4`` = 60, ``f#3``, ``eb2``); None if neither."""
    t = text.strip().lower()
    if re.fullmatch(r"-?\d+", t):
        return int(t)
    m = re.fullmatch(r"([a-g])([#b]?)(-?\d+)", t)
    if m is None:
        return None
    shift = {"#": 1, "b": -1, "": 0}[m.group(2)]
    return NOTE_NAMES[m.group(1)] + shift + 12 * (int(m.group(3)) + 1)


def _strip_comments(text: str) -> str:
    """Comments blanked out, line breaks kept (so line numbers stay right)."""
    text = re.sub(r"/\*.*?\*/", lambda m: re.sub(r"[^\n]", " ", m.group(0)), text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def _tokens(text: str) -> list[tuple[int, str, str, str | None]]:
    """(line, kind, name, value): kind "header" (value None) or "opcode"; unknown directives
    (``#define``) as kind "directive"."""
    out: list[tuple[int, str, str, str | None]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped.startswith("#"):
            out.append((number, "directive", stripped.split()[0], None))
            continue
        matches = list(_TOKEN.finditer(line))
        pos = 0
        for k, m in enumerate(matches):
            if line[pos : m.start()].strip():
                raise SfzError(f"line {number}: cannot read {line[pos : m.start()].strip()!r}")
            if m.group(1) is not None:
                out.append((number, "header", m.group(1), None))
                pos = m.end()
                continue
            end = matches[k + 1].start() if k + 1 < len(matches) else len(line)
            out.append((number, "opcode", m.group(2), line[m.end() : end].strip()))
            pos = end
        if line[pos:].strip():
            raise SfzError(f"line {number}: cannot read {line[pos:].strip()!r}")
    return out


def _int(name: str, value: str, lo: int, hi: int) -> int:
    try:
        got = int(value)
    except ValueError:
        raise ValueError(f"expected an integer {lo}..{hi}") from None
    if not lo <= got <= hi:
        raise ValueError(f"expected an integer {lo}..{hi}")
    return got


def _float(name: str, value: str, lo: float, hi: float) -> float:
    try:
        got = float(value)
    except ValueError:
        raise ValueError(f"expected a number {lo:g}..{hi:g}") from None
    if not lo <= got <= hi:
        raise ValueError(f"expected a number {lo:g}..{hi:g}")
    return got


def _key(value: str) -> int:
    n = note_number(value)
    if n is None or not 0 <= n <= 127:
        raise ValueError("expected a MIDI note 0..127 or a note name such as c4")
    return n


def _apply(region: Region, name: str, value: str) -> Region:
    """``region`` with one understood opcode applied (ValueError saying what was expected)."""
    change: dict[str, Any]
    if name == "key":
        k = _key(value)
        change = {"lokey": k, "hikey": k, "keycenter": k}
    elif name in ("lokey", "hikey", "pitch_keycenter"):
        change = {"keycenter" if name == "pitch_keycenter" else name: _key(value)}
    elif name in ("lovel", "hivel"):
        change = {name: _int(name, value, 0, 127)}
    elif name in ("seq_length", "seq_position"):
        change = {name: _int(name, value, 1, 100)}
    elif name in ("lorand", "hirand"):
        change = {name: _float(name, value, 0.0, 1.0)}
    elif name in ("group", "off_by"):
        change = {name: _int(name, value, -(2**31), 2**31 - 1)}
    elif name == "ampeg_release":
        change = {"release_s": _float(name, value, 0.0, 100.0)}
    elif name == "loop_mode":
        if value not in LOOP_MODES:
            raise ValueError(f"expected one of {', '.join(LOOP_MODES)}")
        change = {"loop_mode": value}
    elif name == "volume":
        change = {"volume_db": _float(name, value, -144.0, 6.0)}
    elif name == "pan":
        change = {"pan": _float(name, value, -100.0, 100.0)}
    elif name == "tune":
        change = {"tune_cents": _float(name, value, -100.0, 100.0)}
    else:
        raise AssertionError(name)
    return replace(region, **change)


def parse_sfz(text: str, path: Path) -> SfzKit:
    """The regions of ``text`` (the content of ``path``); see the module docstring."""
    kit = SfzKit(path)
    scopes: dict[str, list[tuple[int, str, str]]] = {h: [] for h in HEADERS}
    current: str | None = None
    default_path = ""
    region_line = 0

    def close_region() -> None:
        if current != "region":
            return
        opcodes = [*scopes["global"], *scopes["master"], *scopes["group"], *scopes["region"]]
        sample = [(line, v) for line, n, v in opcodes if n == "sample"]
        if not sample:
            raise SfzError(f"{path}:{region_line}: <region> without a sample")
        line, name = sample[-1]
        file = path.parent / (default_path + name).replace("\\", "/")
        region = Region(file, region_line, line)
        for op_line, op, value in opcodes:
            if op in ("sample", "default_path") or op not in KNOWN:
                continue
            try:
                region = _apply(region, op, value)
            except ValueError as exc:
                raise SfzError(f"{path}:{op_line}: {op}={value}: {exc}") from None
        kit.regions.append(region)

    try:
        tokens = _tokens(_strip_comments(text))
    except SfzError as exc:
        raise SfzError(f"{path}: {exc}") from None
    for line, kind, name, value in tokens:
        if kind == "directive":
            kit.unknown.setdefault(name, line)
        elif kind == "header":
            if name not in HEADERS:
                raise SfzError(f"{path}:{line}: unknown header <{name}>")
            close_region()
            current = name
            lower = HEADERS[HEADERS.index(name) :]
            for h in lower:  # a new header starts its scope and those below it afresh
                scopes[h] = []
            region_line = line
        else:
            assert value is not None
            if current is None:
                raise SfzError(f"{path}:{line}: {name}= before any header")
            if name == "default_path" and current == "control":
                default_path = value.replace("\\", "/")
            elif name not in KNOWN:
                kit.unknown.setdefault(name, line)
            scopes[current].append((line, name, value))
    close_region()
    return kit


def load_sfz(path: Path) -> SfzKit:
    """Read and parse ``path``; a missing or unreadable file is an :class:`SfzError`."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise SfzError(f"{path}: cannot read the SFZ file: {exc.strerror}") from None
    return parse_sfz(text, path)
