"""Roadmaps kept on disk next to the oracle cache, so a warm run does not regrow them.

A roadmap is stored as a ``.npz`` file (numpy arrays and a JSON header, read with
``allow_pickle=False``) named by the SHA-256 of everything it depends on: the world, the
largest robot radius, the robot starts, the roadmap parameters, OMPL's version and this
package's roadmap code. Files are written to a temporary name and renamed, so a reader
never sees half a file; one that fails its checksum is reported and rebuilt.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import tempfile
import warnings
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from tmpnav.errors import CacheError
from tmpnav.types import Roadmap, RoadmapParams, RobotSpec
from tmpnav.world import World

CODE = Path(__file__).with_name("prm.py")


class RoadmapCacheWarning(UserWarning):
    """A stored roadmap was unreadable and is being rebuilt."""


def roadmap_key(world: World, robots: tuple[RobotSpec, ...], params: RoadmapParams) -> str:
    try:
        ompl_version = version("ompl")
    except PackageNotFoundError:
        ompl_version = "unknown"
    parts = (
        world.fingerprint,
        max(r.radius for r in robots),
        [(r.name, r.pose.x, r.pose.y) for r in robots],
        repr(params),
        ompl_version,
        hashlib.sha256(CODE.read_bytes()).hexdigest(),
    )
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def load(directory: Path, key: str) -> Roadmap | None:
    path = Path(directory) / "roadmaps" / f"{key}.npz"
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            header = json.loads(bytes(data["header"]).decode())
            arrays = {k: data[k] for k in ("nodes", "edges", "weights")}
        digest = hashlib.sha256(b"".join(a.tobytes() for a in arrays.values())).hexdigest()
        if digest != header["digest"]:
            raise ValueError("checksum mismatch")
        return Roadmap(
            nodes=arrays["nodes"],
            edges=arrays["edges"],
            weights=arrays["weights"],
            instantiations={k: tuple(v) for k, v in header["instantiations"].items()},
            starts={k: int(v) for k, v in header["starts"].items()},
            fingerprint=header["fingerprint"],
        )
    except (OSError, ValueError, KeyError, json.JSONDecodeError, UnicodeDecodeError) as err:
        warnings.warn(f"stored roadmap {path} is unreadable ({err}); rebuilding it", RoadmapCacheWarning, stacklevel=2)
        path.unlink(missing_ok=True)
        return None


def save(directory: Path, key: str, roadmap: Roadmap) -> None:
    """Store a roadmap; a cache directory that cannot hold files at all is a CacheError, a
    failed write (disk full) only a warning: the roadmap is simply grown again next time."""
    folder = Path(directory) / "roadmaps"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise CacheError(
            f"cache directory {directory} cannot be used: {err.strerror} (use --cache-dir DIR or --no-cache)"
        ) from None
    arrays = {"nodes": roadmap.nodes, "edges": roadmap.edges, "weights": roadmap.weights}
    header = {
        "digest": hashlib.sha256(b"".join(a.tobytes() for a in arrays.values())).hexdigest(),
        "instantiations": {k: list(v) for k, v in roadmap.instantiations.items()},
        "starts": roadmap.starts,
        "fingerprint": roadmap.fingerprint,
    }
    buffer = io.BytesIO()
    contents = {"header": np.frombuffer(json.dumps(header).encode(), dtype=np.uint8), **arrays}
    np.savez(buffer, **contents)  # type: ignore[arg-type]  # numpy's stub mistakes ** for allow_pickle
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{key}.", suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            fh.write(buffer.getvalue())
        os.replace(tmp, folder / f"{key}.npz")
    except OSError as err:
        warnings.warn(f"roadmap not stored in {folder} ({err.strerror})", RoadmapCacheWarning, stacklevel=2)
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
