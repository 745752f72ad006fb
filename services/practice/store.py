"""The practice database: one SQLite file keeping every judged session, for progress over days.

Where: ``--db FILE``, else ``$LIVEDRUMMER_HOME/practice.sqlite`` when ``LIVEDRUMMER_HOME`` is
set (the project's one override of where user files go; tests and benches set it), else
``$XDG_DATA_HOME/livedrummer/practice.sqlite`` (``~/.local/share/livedrummer/`` by default):
the database is data the user made, not configuration.

One table, ``session``: a row per judged take with its totals (the columns ``history`` lists
and plots) and the whole ``practice score --json`` object as JSON text, so a later report can
read everything and an older row never needs a migration for a new field. ``user_version``
holds the schema version; a database of a newer version, or a file that is not SQLite, is one
line naming the file. Writes are one transaction each; the file is opened and closed per
command (a practice rig writes a row a minute at most).
"""

from __future__ import annotations

import datetime as dt
import json
import os
import sqlite3
from pathlib import Path
from types import TracebackType
from typing import Any

from livedrummer.errors import LivedrummerError
from livedrummer.resources import user_home

SCHEMA_VERSION = 1
_COLUMNS = (
    "reference_notes",
    "hits",
    "missed",
    "extra",
    "wrong_piece",
    "accuracy_pct",
    "score",
    "mean_offset_ms",
    "sd_offset_ms",
)
_REALS = frozenset({"accuracy_pct", "score", "mean_offset_ms", "sd_offset_ms"})


class PracticeStoreError(LivedrummerError):
    """The practice database cannot be opened, read or written."""


def default_db() -> Path:
    """Where the database lives (see the module docstring)."""
    if os.environ.get("LIVEDRUMMER_HOME"):
        return user_home() / "practice.sqlite"
    xdg = os.environ.get("XDG_DATA_HOME")
    base = Path(xdg) if xdg else Path.home() / ".local" / "share"
    return base / "livedrummer" / "practice.sqlite"


class PracticeStore:
    """An open practice database (a context manager; see the module docstring)."""

    def __init__(self, path: Path, db: sqlite3.Connection) -> None:
        self.path = path
        self._db = db

    @classmethod
    def open(cls, path: Path | None = None) -> PracticeStore:
        where = path if path is not None else default_db()
        try:
            where.parent.mkdir(parents=True, exist_ok=True)
            db = sqlite3.connect(where)
            version = int(db.execute("PRAGMA user_version").fetchone()[0])
            if version > SCHEMA_VERSION:
                db.close()
                raise PracticeStoreError(
                    f"{where}: practice database version {version} is newer than this "
                    f"livedrummer's ({SCHEMA_VERSION})"
                )
            with db:
                db.execute(
                    "CREATE TABLE IF NOT EXISTS session (id INTEGER PRIMARY KEY, "
                    "started TEXT NOT NULL, kind TEXT NOT NULL, reference TEXT NOT NULL, "
                    + ", ".join(f"{c} {'REAL' if c in _REALS else 'INTEGER'}" for c in _COLUMNS)
                    + ", result TEXT NOT NULL)"
                )
                db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
        except (sqlite3.Error, OSError) as exc:
            raise PracticeStoreError(f"{where}: cannot open the practice database: {exc}") from None
        return cls(where, db)

    def __enter__(self) -> PracticeStore:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._db.close()

    def add(self, result: dict[str, Any], kind: str, started: dt.datetime | None = None) -> int:
        """Keep one judged take (a ``practice score --json`` object); returns its id."""
        when = (started or dt.datetime.now().astimezone()).isoformat(timespec="seconds")
        values = [result.get(c) for c in _COLUMNS]
        try:
            with self._db:
                cur = self._db.execute(
                    f"INSERT INTO session (started, kind, reference, {', '.join(_COLUMNS)}, "
                    f"result) VALUES (?, ?, ?, {', '.join('?' * len(_COLUMNS))}, ?)",
                    [when, kind, str(result.get("reference", "")), *values, json.dumps(result)],
                )
        except sqlite3.Error as exc:
            raise PracticeStoreError(f"{self.path}: cannot write: {exc}") from None
        return int(cur.lastrowid or 0)

    def sessions(self) -> list[dict[str, Any]]:
        """Every session's totals, oldest first (without the per-note JSON)."""
        try:
            rows = self._db.execute(
                f"SELECT id, started, kind, reference, {', '.join(_COLUMNS)} FROM session "
                "ORDER BY started, id"
            ).fetchall()
        except sqlite3.Error as exc:
            raise PracticeStoreError(f"{self.path}: cannot read: {exc}") from None
        names = ("id", "started", "kind", "reference", *_COLUMNS)
        return [dict(zip(names, row, strict=True)) for row in rows]

    def result(self, session_id: int) -> dict[str, Any]:
        """The whole JSON result of session ``session_id``."""
        row = self._db.execute("SELECT result FROM session WHERE id = ?", (session_id,)).fetchone()
        if row is None:
            raise PracticeStoreError(f"{self.path}: no practice session {session_id}")
        out: dict[str, Any] = json.loads(row[0])
        return out
