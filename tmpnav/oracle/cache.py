"""The oracle's content-addressed disk cache (SQLite, JSON values, no pickle).

A key is the SHA-256 of everything a result depends on (see :mod:`tmpnav.oracle.keys`),
so a changed scenario can never read a stale cost. The store is one SQLite database:
several processes may read and write at once (WAL journal, busy timeout), and a crash or
Ctrl-C in the middle of a write leaves the previous state (transactions are atomic).
Each value carries its own SHA-256; an entry that does not match, or a database file that
is not a database any more, is reported once as a warning and recomputed: the bad file
is set aside (:func:`tmpnav.cachedir.set_aside`), never read again, never a crash. Where the
database lives is :mod:`tmpnav.cachedir`'s business.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import sqlite3
import time
import warnings
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tmpnav.cachedir import CacheDir, set_aside

SCHEMA = """
CREATE TABLE IF NOT EXISTS entries (
    key TEXT PRIMARY KEY,
    digest TEXT NOT NULL,
    value BLOB NOT NULL,
    created REAL NOT NULL
);
"""


class CacheWarning(UserWarning):
    """Something in the cache was unusable and is being recomputed."""


def _digest(value: bytes) -> str:
    return hashlib.sha256(value).hexdigest()


@dataclass
class CacheStats:
    hits: int = 0
    misses: int = 0
    corrupt: int = 0
    writes: int = 0
    warnings: list[str] = field(default_factory=list)


class NullCache:
    """``--no-cache``: never stores, never finds."""

    path: Path | None = None

    def __init__(self) -> None:
        self.stats = CacheStats()

    def get_many(self, keys: Iterable[str]) -> dict[str, Any]:
        keys = list(keys)
        self.stats.misses += len(keys)
        return {}

    def put_many(self, items: dict[str, Any]) -> None:
        return None

    def close(self) -> None:
        return None


class DiskCache:
    """A JSON key-value store in one SQLite file, safe for concurrent processes."""

    def __init__(self, directory: Path):
        cache = CacheDir(Path(directory))
        self.directory = cache.ensure()
        self.path = cache.database
        self.stats = CacheStats()
        self._conn: sqlite3.Connection | None = None
        self._connect()

    # ------------------------------------------------------------------ connection
    def _connect(self) -> None:
        try:
            conn = sqlite3.connect(self.path, timeout=60.0, isolation_level=None)
            conn.execute("PRAGMA journal_mode=WAL")
            conn.execute("PRAGMA synchronous=NORMAL")
            conn.executescript(SCHEMA)
            conn.execute("SELECT count(*) FROM entries").fetchone()
            self._conn = conn
        except sqlite3.DatabaseError as err:
            self._quarantine(f"cache file {self.path} is unreadable ({err})")
            conn = sqlite3.connect(self.path, timeout=60.0, isolation_level=None)
            conn.execute("PRAGMA journal_mode=WAL")
            conn.executescript(SCHEMA)
            self._conn = conn

    def _quarantine(self, reason: str) -> None:
        """Move a broken database aside (with its WAL files) and warn once."""
        if self._conn is not None:
            with contextlib.suppress(sqlite3.Error):
                self._conn.close()
            self._conn = None
        for suffix in ("", "-wal", "-shm"):
            set_aside(Path(str(self.path) + suffix))
        self._warn(f"{reason}; moved it aside and recomputing")

    def _warn(self, message: str) -> None:
        self.stats.warnings.append(message)
        warnings.warn(message, CacheWarning, stacklevel=3)

    @property
    def conn(self) -> sqlite3.Connection:
        assert self._conn is not None
        return self._conn

    # ------------------------------------------------------------------ access
    def get_many(self, keys: Iterable[str]) -> dict[str, Any]:
        """The cached values of those keys that are present and intact."""
        keys = list(dict.fromkeys(keys))
        found: dict[str, Any] = {}
        bad: list[str] = []
        try:
            for start in range(0, len(keys), 500):
                chunk = keys[start : start + 500]
                marks = ",".join("?" * len(chunk))
                rows = self.conn.execute(
                    f"SELECT key, digest, value FROM entries WHERE key IN ({marks})", chunk
                ).fetchall()
                for key, digest, value in rows:
                    if not isinstance(value, bytes) or _digest(value) != digest:
                        bad.append(key)
                        continue
                    try:
                        found[key] = json.loads(value)
                    except (UnicodeDecodeError, json.JSONDecodeError):
                        bad.append(key)
        except sqlite3.DatabaseError as err:
            self._quarantine(f"cache file {self.path} is corrupted ({err})")
            self._connect()
            found, bad = {}, []
        if bad:
            self.stats.corrupt += len(bad)
            self._warn(
                f"{len(bad)} cache entr{'y' if len(bad) == 1 else 'ies'} in {self.path} "
                "failed the integrity check; recomputing"
            )
            with contextlib.suppress(sqlite3.DatabaseError):
                self.conn.executemany("DELETE FROM entries WHERE key = ?", [(k,) for k in bad])
        self.stats.hits += len(found)
        self.stats.misses += len(keys) - len(found)
        return found

    def put_many(self, items: dict[str, Any]) -> None:
        """Store values in one transaction: all of them become visible, or none."""
        if not items:
            return
        rows = []
        now = time.time()
        for key, value in items.items():
            blob = json.dumps(value, separators=(",", ":"), allow_nan=True).encode()
            rows.append((key, _digest(blob), blob, now))
        try:
            self.conn.execute("BEGIN IMMEDIATE")
            self.conn.executemany(
                "INSERT OR REPLACE INTO entries (key, digest, value, created) VALUES (?, ?, ?, ?)", rows
            )
            self.conn.execute("COMMIT")
            self.stats.writes += len(rows)
        except sqlite3.DatabaseError as err:
            with contextlib.suppress(sqlite3.Error):
                self.conn.execute("ROLLBACK")
            self._quarantine(f"cache file {self.path} could not be written ({err})")
            self._connect()

    def close(self) -> None:
        if self._conn is not None:
            self._conn.close()
            self._conn = None
