"""Strict reading of TOML configuration files.

Kits, note maps and presets are hand-edited by drummers and show technicians, so a typo must
never be swallowed: every table is read through a :class:`Table` that knows the file it came
from and its path inside that file, converts and range-checks each value it hands out, and at
:meth:`Table.done` rejects every key nobody asked for (with a "did you mean" hint). Errors are
raised as the caller's :class:`~livedrummer.errors.ConfigError` subclass so the CLI can report
``file: [where] key: problem (got value)`` on one line.
"""

from __future__ import annotations

import difflib
import tomllib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from livedrummer.errors import ConfigError

_MISSING: Any = object()


def read_toml(path: Path, error: type[ConfigError]) -> dict[str, Any]:
    """Parse a TOML file, turning every failure into ``error`` naming the file (and line)."""
    if path.is_dir():
        raise error(f"{path}: is a directory, not a TOML file")
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise error(f"{path}: cannot read: {exc.strerror or exc}") from exc
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: byte {exc.start}: not UTF-8 text") from exc
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: {exc}") from exc


class Table:
    """One TOML table being read; hands out checked values and remembers which keys were used."""

    def __init__(self, data: object, source: str, where: str, error: type[ConfigError]) -> None:
        self._source = source
        self._where = where
        self._error = error
        if not isinstance(data, dict):
            raise self.fail(None, f"expected a table, got {type(data).__name__}", data)
        self._data: dict[str, Any] = data
        self._used: set[str] = set()

    @property
    def source(self) -> str:
        return self._source

    def fail(self, key: str | None, problem: str, value: object = _MISSING) -> ConfigError:
        """Build (not raise) an error located at ``key`` of this table."""
        place = f"{self._source}: [{self._where}]"
        if key is not None:
            place += f" {key}"
        got = "" if value is _MISSING else f" (got {value!r})"
        return self._error(f"{place}: {problem}{got}")

    def keys(self) -> list[str]:
        return list(self._data)

    def has(self, key: str) -> bool:
        return key in self._data

    def _get(self, key: str, default: Any) -> Any:
        self._used.add(key)
        if key in self._data:
            return self._data[key]
        if default is _MISSING:
            unread = [k for k in self._data if k not in self._used]
            typo = difflib.get_close_matches(key, unread, n=1)
            if typo:  # report the typo itself, as done() would have
                raise self.fail(typo[0], f"unknown key; did you mean {key!r}?")
            raise self.fail(key, "missing required key")
        return default

    def raw(self, key: str, default: Any = _MISSING) -> Any:
        """The value as TOML gave it, unchecked: for a key that may hold values of several
        types (a name or a number), which the caller then reads with the matching method."""
        return self._get(key, default)

    def text(self, key: str, default: Any = _MISSING, choices: Iterable[str] | None = None) -> Any:
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return value
        if not isinstance(value, str):
            raise self.fail(key, "expected a string", value)
        if choices is not None:
            allowed = sorted(choices)
            if value not in allowed:
                raise self.fail(key, f"must be one of {', '.join(allowed)}", value)
        return value

    def number(
        self,
        key: str,
        default: Any = _MISSING,
        lo: float | None = None,
        hi: float | None = None,
    ) -> Any:
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return value
        return self._check_number(key, value, lo, hi)

    def integer(
        self, key: str, default: Any = _MISSING, lo: int | None = None, hi: int | None = None
    ) -> Any:
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return value
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, "expected an integer", value)
        return int(self._check_number(key, value, lo, hi))

    def boolean(self, key: str, default: Any = _MISSING) -> Any:
        value = self._get(key, default)
        if not isinstance(value, bool):
            raise self.fail(key, "expected true or false", value)
        return value

    def vector(self, key: str, size: int, default: Any = _MISSING) -> Any:
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return value
        if not isinstance(value, list) or len(value) != size:
            raise self.fail(key, f"expected a list of {size} numbers", value)
        return tuple(self._check_number(key, v, None, None) for v in value)

    def texts(self, key: str, default: Any = _MISSING) -> Any:
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return value
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.fail(key, "expected a list of strings", value)
        return tuple(value)

    def table(self, key: str, default: Any = _MISSING) -> Any:
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return value
        return Table(
            value, self._source, f"{self._where}.{key}" if self._where else key, self._error
        )

    def tables(self, key: str, label: str | None = None) -> list[Table]:
        """An array of tables (``[[key]]``); each is located by ``label`` value or index."""
        value = self._get(key, [])
        if not isinstance(value, list):
            raise self.fail(key, "expected an array of tables ([[...]])", value)
        out = []
        for i, item in enumerate(value):
            name = item.get(label) if label and isinstance(item, dict) else None
            where = f"{key} {name!r}" if isinstance(name, str) else f"{key} #{i + 1}"
            out.append(Table(item, self._source, where, self._error))
        return out

    def done(self) -> None:
        """Reject keys that were never read: they are typos or unsupported settings."""
        for key in self._data:
            if key not in self._used:
                hint = difflib.get_close_matches(key, sorted(self._used), n=1)
                extra = f"; did you mean {hint[0]!r}?" if hint else ""
                raise self.fail(key, f"unknown key{extra}")

    def _check_number(self, key: str, value: object, lo: float | None, hi: float | None) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, "expected a number", value)
        if value != value or value in (float("inf"), float("-inf")):
            raise self.fail(key, "expected a finite number", value)
        if lo is not None and value < lo:
            raise self.fail(key, f"must be >= {lo}", value)
        if hi is not None and value > hi:
            raise self.fail(key, f"must be <= {hi}", value)
        return float(value)
