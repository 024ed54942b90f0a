"""The cache directory: what tmpnav keeps between runs, and the only code that knows its layout.

::

    <cache>/oracle-v1.sqlite3           the cost database: the oracle's action costs, whole cost
                                        tables and remembered task plans (tmpnav.oracle.cache)
    <cache>/oracle-v1.sqlite3-wal, -shm SQLite's journal files
    <cache>/roadmaps/<key>.npz          grown roadmaps (tmpnav.roadmap.store)
    <cache>/roadmaps/<key>.scans.npz    a range sensor's scan information of a map (the same)
    <cache>/roadmaps/<key>.localisability.npz
                                        a map's localisability as plan.png draws it (the same)
    <cache>/roadmaps/<key>.safe.npz     a grown roadmap's safe edge weights for a robot radius
                                        and a clearance (the same)
    <file>.corrupt-<date>-<pid>         a damaged file, set aside: never read again, kept for a
                                        bug report, removed by ``tmpnav cache clear``
    .<file>.tmpnav-<pid>-<hex>.tmp      a file being written (tmpnav.atomic); removed by the next
                                        write when its writer was killed

Every cache file is checked when it is read (checksums, shapes); a damaged one is set aside
with one warning and its content computed again, never a crash. The directory is
``--cache-dir``, else ``$TMPNAV_CACHE_DIR``, else the platform's user cache directory
(``~/.cache/tmpnav`` on Linux).
"""

from __future__ import annotations

import contextlib
import os
import sqlite3
import time
from dataclasses import dataclass
from pathlib import Path

from tmpnav.atomic import remove_stale
from tmpnav.errors import CacheError

DATABASE = "oracle-v1.sqlite3"
ROADMAPS = "roadmaps"
SCANS = ".scans.npz"  # a scan information table beside the roadmaps
LOCALISABILITY = ".localisability.npz"  # a localisability map beside them
SAFE = ".safe.npz"  # a grown roadmap's safe edge weights beside them
#: the files beside the roadmaps that are not roadmaps
BESIDE = (SCANS, LOCALISABILITY, SAFE)
SET_ASIDE = ".corrupt-"


def default_cache_dir() -> Path:
    """``$TMPNAV_CACHE_DIR``, else ``$XDG_CACHE_HOME/tmpnav`` (``~/.cache/tmpnav``)."""
    env = os.environ.get("TMPNAV_CACHE_DIR")
    if env:
        return Path(env)
    from platformdirs import user_cache_dir

    return Path(user_cache_dir("tmpnav", appauthor=False))


def set_aside(path: Path) -> Path | None:
    """Move a damaged cache file out of the way (``<path>.corrupt-<date>-<pid>``); returns its
    new name, or None when it could only be deleted (or was already gone)."""
    target = Path(f"{path}{SET_ASIDE}{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}")
    try:
        os.replace(path, target)
        return target
    except FileNotFoundError:
        return None
    except OSError:
        with contextlib.suppress(OSError):
            os.unlink(path)
        return None


@dataclass(frozen=True)
class CacheInfo:
    """What ``tmpnav cache info`` prints."""

    directory: Path
    database: Path
    database_exists: bool
    entries: int | None  # None when the database is unreadable
    database_bytes: int  # with its journal files
    error: str | None  # why the database is unreadable
    roadmaps: int
    roadmap_bytes: int
    set_aside: int  # damaged files kept aside


@dataclass(frozen=True)
class CacheDir:
    """A cache directory (it need not exist yet)."""

    root: Path

    @classmethod
    def at(cls, directory: Path | None) -> CacheDir:
        """The cache in ``directory``, or in the default directory when None."""
        return cls(Path(directory) if directory is not None else default_cache_dir())

    @property
    def database(self) -> Path:
        return self.root / DATABASE

    @property
    def roadmaps(self) -> Path:
        return self.root / ROADMAPS

    def roadmap(self, key: str) -> Path:
        return self.roadmaps / f"{key}.npz"

    def scans(self, key: str) -> Path:
        return self.roadmaps / f"{key}{SCANS}"

    def localisability(self, key: str) -> Path:
        return self.roadmaps / f"{key}{LOCALISABILITY}"

    def safe_weights(self, key: str) -> Path:
        return self.roadmaps / f"{key}{SAFE}"

    def ensure(self, folder: Path | None = None) -> Path:
        """Create the directory (or its sub-folder ``folder``) if needed; a CacheError when it
        cannot be created or written, with what to do instead."""
        folder = self.root if folder is None else folder
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise CacheError(
                f"cache directory {self.root} cannot be used: {folder}: {err.strerror} "
                "(use --cache-dir DIR or --no-cache)"
            ) from None
        if not os.access(folder, os.W_OK | os.X_OK):
            raise CacheError(f"cache directory {self.root} is not writable (use --cache-dir DIR or --no-cache)")
        return folder

    def database_files(self) -> list[Path]:
        """The database, its journal files, and database files set aside."""
        return sorted(self.root.glob(DATABASE + "*")) if self.root.is_dir() else []

    def roadmap_files(self) -> list[Path]:
        """Stored roadmaps, roadmaps set aside, and temporary files of killed writers."""
        if not self.roadmaps.is_dir():
            return []
        return sorted(p for p in self.roadmaps.iterdir() if p.is_file() and (".npz" in p.name or ".tmpnav-" in p.name))

    def info(self) -> CacheInfo:
        """Location, size and content of the cache (the database is opened read-only)."""
        files = self.database_files()
        stored = [p for p in self.roadmap_files() if p.suffix == ".npz"]  # with the scan tables
        roadmaps = [p for p in stored if not p.name.endswith(BESIDE)]
        entries, error = count_entries(self.database) if self.database.exists() else (0, None)
        return CacheInfo(
            directory=self.root,
            database=self.database,
            database_exists=self.database.exists(),
            entries=entries,
            database_bytes=sum(_size(p) for p in files if SET_ASIDE not in p.name),
            error=error,
            roadmaps=len(roadmaps),
            roadmap_bytes=sum(_size(p) for p in stored),
            set_aside=sum(SET_ASIDE in p.name for p in [*files, *self.roadmap_files()]),
        )

    def clear(self) -> tuple[int, int]:
        """Delete every cache file; returns (database files, roadmaps) removed.

        A file that cannot be removed (a read-only cache) is a CacheError naming it; the
        others are removed all the same."""
        remove_stale(self.root)
        database, roadmaps = self.database_files(), self.roadmap_files()
        failed: list[tuple[Path, OSError]] = []
        for path in [*database, *roadmaps]:
            try:
                path.unlink(missing_ok=True)
            except OSError as err:
                failed.append((path, err))
        if failed:
            first, why = failed[0]
            more = f" ({len(failed)} files could not be removed)" if len(failed) > 1 else ""
            raise CacheError(f"cannot clear the cache {self.root}: {first}: {why.strerror}{more}")
        return len(database), sum(p.suffix == ".npz" and not p.name.endswith(BESIDE) for p in roadmaps)


def _size(path: Path) -> int:
    try:
        return path.stat().st_size
    except OSError:
        return 0


def count_entries(path: Path) -> tuple[int | None, str | None]:
    """How many entries the cost database at ``path`` holds (its table ``entries``,
    tmpnav.oracle.cache), read-only: (count, None), or (None, why) when it is unreadable."""
    try:
        conn = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=10.0)
        try:
            (entries,) = conn.execute("SELECT count(*) FROM entries").fetchone()
        finally:
            conn.close()
    except sqlite3.DatabaseError as err:
        return None, f"unreadable: {err}"
    return int(entries), None
