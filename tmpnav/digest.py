"""Digests of tmpnav's own source code, for cache keys that change when the code that decides
a cached value does (the oracle's results, remembered task plans)."""

from __future__ import annotations

import hashlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent


def source_digest(files: tuple[str, ...]) -> hashlib._Hash:
    """A SHA-256 over the names and bytes of tmpnav source files (paths relative to the package)."""
    h = hashlib.sha256()
    for rel in files:
        h.update(rel.encode())
        h.update((ROOT / rel).read_bytes())
    return h


def folders_digest(folders: tuple[str, ...]) -> str:
    """The hex SHA-256 of every module of the package's ``folders`` (names and bytes)."""
    return source_digest(tuple(f"{f}/{p.name}" for f in folders for p in sorted((ROOT / f).glob("*.py")))).hexdigest()
