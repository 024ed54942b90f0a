"""Roadmaps kept in the cache directory, so that a warm run does not grow them again.

A roadmap is stored as a ``.npz`` file (numpy arrays and a JSON header, read with
``allow_pickle=False``) named by the SHA-256 of everything it depends on: the world, the
largest robot radius, the robot starts, the roadmap parameters, OMPL's version and this
package's roadmap code. Files are written all or nothing (:mod:`tmpnav.atomic`). Reading
checks everything: the archive, the checksum over the arrays and the header, the arrays'
shapes, every node index. A file that fails any check (truncated by a full disk,
emptied, overwritten) is set aside with one warning and the roadmap is grown again.
"""

from __future__ import annotations

import hashlib
import io
import json
import warnings
import zipfile
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from tmpnav.atomic import write_file
from tmpnav.cachedir import CacheDir, set_aside
from tmpnav.errors import CacheError
from tmpnav.roadmap.graph import grown_edges, grown_safe_weights, keep_safe_weights
from tmpnav.types import RangeSensor, Roadmap, RoadmapParams, RobotSpec
from tmpnav.world import World
from tmpnav.world.scan_information import Localisability, localisability

CODE = Path(__file__).with_name("prm.py")
FORMAT = "roadmap-file/2"  # the checksum covers the header too; part of the key, so older files are not read
#: what reading a damaged .npz file can raise (numpy reports a truncated archive as EOFError or BadZipFile)
DAMAGE = (OSError, EOFError, zipfile.BadZipFile, ValueError, KeyError, TypeError, IndexError, UnicodeDecodeError)


class RoadmapCacheWarning(UserWarning):
    """A stored roadmap was unreadable and is being grown again."""


def roadmap_key(world: World, robots: tuple[RobotSpec, ...], params: RoadmapParams) -> str:
    """The content address of the roadmap of this world, team and parameters."""
    try:
        ompl_version = version("ompl")
    except PackageNotFoundError:
        ompl_version = "unknown"
    parts = (
        FORMAT,
        world.fingerprint,
        max(r.radius for r in robots),
        [(r.name, r.pose.x, r.pose.y) for r in robots],
        repr(params),
        ompl_version,
        hashlib.sha256(CODE.read_bytes()).hexdigest(),
    )
    return hashlib.sha256(repr(parts).encode()).hexdigest()


class RoadmapStore:
    """The roadmaps of one cache directory; ``warnings`` lists the damaged files set aside."""

    def __init__(self, cache: CacheDir):
        self.cache = cache
        self.warnings: list[str] = []

    def load(self, key: str) -> Roadmap | None:
        """The stored roadmap, or None when there is none or it was damaged (then set aside)."""
        path = self.cache.roadmap(key)
        if not path.exists():
            return None
        try:
            return read(path)
        except DAMAGE as err:
            moved = set_aside(path)
            where = f"; moved it to {moved.name}" if moved is not None else ""
            self.warn(f"stored roadmap {path} is unreadable ({type(err).__name__}: {err}){where}; growing it again")
            return None

    def save(self, key: str, roadmap: Roadmap) -> None:
        """Store a roadmap. A cache directory that cannot hold files at all is a CacheError; a
        failed write (a full disk) only a warning: the roadmap is grown again next time."""
        self.cache.ensure(self.cache.roadmaps)
        path = self.cache.roadmap(key)
        try:
            write_file(path, serialize(roadmap))
        except OSError as err:
            self.warn(f"roadmap not stored in {path.parent} ({err.strerror or err})")

    def warn(self, message: str) -> None:
        """Record a cache problem and warn of it once (RoadmapCacheWarning)."""
        self.warnings.append(message)
        warnings.warn(message, RoadmapCacheWarning, stacklevel=3)


def _digest(arrays: dict[str, np.ndarray], header: dict[str, object]) -> str:
    """SHA-256 of the arrays and of the header's other fields (JSON, sorted keys)."""
    h = hashlib.sha256(b"".join(a.tobytes() for a in arrays.values()))
    h.update(json.dumps({k: v for k, v in header.items() if k != "digest"}, sort_keys=True).encode())
    return h.hexdigest()


def serialize(roadmap: Roadmap) -> bytes:
    """The .npz file of a roadmap."""
    arrays = {"nodes": roadmap.nodes, "edges": roadmap.edges, "weights": roadmap.weights}
    header: dict[str, object] = {
        "instantiations": {k: list(v) for k, v in roadmap.instantiations.items()},
        "starts": roadmap.starts,
        "fingerprint": roadmap.fingerprint,
    }
    return _npz(arrays, header)


def _npz(arrays: dict[str, np.ndarray], header: dict[str, object]) -> bytes:
    """An .npz file of ``arrays`` and a JSON ``header`` that carries their checksum (``digest``)."""
    header["digest"] = _digest(arrays, header)
    buffer = io.BytesIO()
    contents = {"header": np.frombuffer(json.dumps(header).encode(), dtype=np.uint8), **arrays}
    np.savez(buffer, **contents)  # type: ignore[arg-type]  # numpy's stub mistakes ** for allow_pickle
    return buffer.getvalue()


def read(path: Path) -> Roadmap:
    """A stored roadmap, every part checked; raises one of ``DAMAGE`` when anything is off."""
    with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as data:  # our handle: closed even on a bad zip
        header = json.loads(bytes(data["header"]).decode())
        arrays = {k: data[k] for k in ("nodes", "edges", "weights")}
    if not isinstance(header, dict) or _digest(arrays, header) != header["digest"]:
        raise ValueError("checksum mismatch")
    nodes, edges, weights = arrays["nodes"], arrays["edges"], arrays["weights"]
    n = nodes.shape[0]
    if nodes.ndim != 2 or nodes.shape[1] != 2 or edges.ndim != 2 or edges.shape[1] != 2:
        raise ValueError("arrays of the wrong shape")
    if weights.shape != (edges.shape[0],) or (edges.size and (edges.min() < 0 or edges.max() >= n)):
        raise ValueError("edges that do not fit the nodes")
    instantiations = {str(k): tuple(int(i) for i in v) for k, v in header["instantiations"].items()}
    starts = {str(k): int(v) for k, v in header["starts"].items()}
    if any(not 0 <= i < n for ids in instantiations.values() for i in ids) or any(
        not 0 <= i < n for i in starts.values()
    ):
        raise ValueError("node indices out of range")
    return Roadmap(nodes, edges, weights, instantiations, starts, str(header["fingerprint"]))


SCANS_FORMAT = "scans-file/1"
#: the code that computes scan information: the ray casting and the table
LIDAR_CODE = tuple(Path(__file__).resolve().parents[1] / "world" / name for name in ("lidar.py", "scan_information.py"))


def _lidar_code() -> str:
    """The digest of :data:`LIDAR_CODE`."""
    digest = hashlib.sha256()
    for path in LIDAR_CODE:
        digest.update(path.read_bytes())
    return digest.hexdigest()


def scans_key(world: World, sensor: RangeSensor) -> str:
    """The content address of a range sensor's scan information in a world (the map and the sensor,
    and the code that computes it)."""
    parts = (SCANS_FORMAT, world.fingerprint, repr(sensor), _lidar_code())
    return hashlib.sha256(repr(parts).encode()).hexdigest()


class ScanStore:
    """A range sensor's scan information (tmpnav.world.scan_information.ScanInformation) kept beside the
    roadmaps, keyed by the map and the sensor: what one run computed, the next reads. Like a
    roadmap, a damaged file is set aside with one warning and computed again."""

    def __init__(self, cache: CacheDir, store: RoadmapStore):
        self.cache, self.store = cache, store  # the store's warnings are the run's cache warnings

    def load(self, world: World, sensor: RangeSensor) -> int:
        """Preload ``world.scans(sensor)`` with the stored table; how many keys it held."""
        path = self.cache.scans(scans_key(world, sensor))
        if not path.exists():
            return 0
        try:
            keys, factors = read_scans(path)
        except DAMAGE as err:
            moved = set_aside(path)
            where = f"; moved it to {moved.name}" if moved is not None else ""
            self.store.warn(f"stored scan table {path} is unreadable ({type(err).__name__}: {err}){where}")
            return 0
        world.scans(sensor).preload(keys, factors)
        return int(keys.size)

    def save(self, world: World, sensor: RangeSensor) -> None:
        """Store the table when this run computed keys the stored one lacked (a failed write: a warning)."""
        scans = world.scans(sensor)
        if scans.computed == 0:
            return
        self.cache.ensure(self.cache.roadmaps)
        path = self.cache.scans(scans_key(world, sensor))
        try:
            write_file(path, serialize_scans(*scans.contents()))
        except OSError as err:
            self.store.warn(f"scan table not stored in {path.parent} ({err.strerror or err})")


def serialize_scans(keys: np.ndarray, factors: np.ndarray) -> bytes:
    """The .npz file of a scan table: its keys (K,) and factors (K, 3, 3), with their checksum."""
    arrays = {"keys": np.asarray(keys, dtype=np.int64), "factors": np.asarray(factors, dtype=float)}
    header: dict[str, object] = {"format": SCANS_FORMAT}
    return _npz(arrays, header)


def read_scans(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A stored scan table, checked; raises one of ``DAMAGE`` when anything is off."""
    with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as data:
        header = json.loads(bytes(data["header"]).decode())
        arrays = {k: data[k] for k in ("keys", "factors")}
    if not isinstance(header, dict) or _digest(arrays, header) != header["digest"]:
        raise ValueError("checksum mismatch")
    keys, factors = arrays["keys"], arrays["factors"]
    if keys.ndim != 1 or factors.shape != (keys.size, 3, 3) or keys.dtype != np.int64:
        raise ValueError("arrays of the wrong shape")
    if keys.size and (keys.min() < 0 or np.any(np.diff(keys) <= 0) or not np.isfinite(factors).all()):
        raise ValueError("keys out of order or factors not finite")
    return keys, factors


LOCALISABILITY_FORMAT = "localisability-file/1"


def localisability_key(
    world: World, sensor: RangeSensor, view: tuple[float, float, float, float] | None, points: int
) -> str:
    """The content address of a localisability map (tmpnav.world.scan_information.localisability): the map,
    the sensor, the view, the points and the code that computes it."""
    view_text = None if view is None else tuple(repr(float(v)) for v in view)
    code = _lidar_code()
    parts = (LOCALISABILITY_FORMAT, world.fingerprint, repr(sensor), view_text, points, code)
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def stored_localisability(
    cache: CacheDir | None,
    world: World,
    sensor: RangeSensor,
    view: tuple[float, float, float, float] | None,
    points: int,
) -> Localisability:
    """``localisability(world.grid, world.signed_distance, sensor, view, points)``, read from
    ``cache`` when an earlier figure of this map and view computed it (every plan.png of a map
    with a range sensor draws it: 0.5 s of ray casting for a warehouse), else computed and
    stored. Without a cache, computed. A damaged file is set aside and computed again."""
    if cache is None:
        return localisability(world.grid, world.signed_distance, sensor, view, points)
    path = cache.localisability(localisability_key(world, sensor, view, points))
    if path.exists():
        try:
            return read_localisability(path)
        except DAMAGE:
            set_aside(path)
    found = localisability(world.grid, world.signed_distance, sensor, view, points)
    try:
        cache.ensure(cache.roadmaps)
        write_file(path, serialize_localisability(found))
    except (OSError, CacheError):
        pass  # a figure is drawn all the same; the next one computes the map again
    return found


def serialize_localisability(found: Localisability) -> bytes:
    """The .npz file of a localisability map: its points (xs, ys) and sigma, with their checksum."""
    arrays = {"xs": found.xs, "ys": found.ys, "sigma": found.sigma}
    header: dict[str, object] = {"format": LOCALISABILITY_FORMAT}
    return _npz(arrays, header)


def read_localisability(path: Path) -> Localisability:
    """A stored localisability map, checked; raises one of ``DAMAGE`` when anything is off."""
    with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as data:
        header = json.loads(bytes(data["header"]).decode())
        arrays = {k: data[k] for k in ("xs", "ys", "sigma")}
    if not isinstance(header, dict) or _digest(arrays, header) != header["digest"]:
        raise ValueError("checksum mismatch")
    xs, ys, sigma = arrays["xs"], arrays["ys"], arrays["sigma"]
    if xs.ndim != 1 or ys.ndim != 1 or sigma.shape != (ys.size, xs.size):
        raise ValueError("arrays of the wrong shape")
    return Localisability(xs, ys, sigma)


SAFE_FORMAT = "safe-weights-file/1"
GRAPH_CODE = Path(__file__).with_name("graph.py")


def safe_weights_key(roadmap: Roadmap, world: World, radius: float, clearance: float) -> str:
    """The content address of a grown roadmap's safe edge weights (tmpnav.roadmap.graph.safe_weights):
    the roadmap as grown, the map, the robot radius, the clearance and the code that computes them."""
    code = hashlib.sha256(GRAPH_CODE.read_bytes()).hexdigest()
    parts = (SAFE_FORMAT, roadmap.grown, world.fingerprint, repr(float(radius)), repr(float(clearance)), code)
    return hashlib.sha256(repr(parts).encode()).hexdigest()


class SafeWeightStore:
    """A grown roadmap's safe edge weights kept beside it: every process that plans on the roadmap
    (a warm replan above all) reads them instead of sampling the clearance along every edge again
    (a third of a second on building-4robots). Like a roadmap, a damaged file is set aside with one
    warning and the weights computed again."""

    def __init__(self, cache: CacheDir, store: RoadmapStore):
        self.cache, self.store = cache, store  # the store's warnings are the run's cache warnings

    def ensure(self, roadmap: Roadmap, world: World, radius: float, clearance: float) -> None:
        """Make the process know the grown roadmap's safe weights (graph.keep_safe_weights): read
        them, or compute and store them."""
        if not roadmap.grown:
            return  # a roadmap built by hand: nothing to know it by
        path = self.cache.safe_weights(safe_weights_key(roadmap, world, radius, clearance))
        if path.exists():
            try:
                keep_safe_weights(roadmap, world, radius, clearance, read_safe_weights(path, roadmap))
                return
            except DAMAGE as err:
                moved = set_aside(path)
                where = f"; moved it to {moved.name}" if moved is not None else ""
                self.store.warn(f"stored safe weights {path} are unreadable ({type(err).__name__}: {err}){where}")
        weights = grown_safe_weights(roadmap, world, radius, clearance)
        self.cache.ensure(self.cache.roadmaps)
        try:
            write_file(path, _npz({"weights": np.asarray(weights, dtype=float)}, {"format": SAFE_FORMAT}))
        except OSError as err:
            self.store.warn(f"safe weights not stored in {path.parent} ({err.strerror or err})")


def read_safe_weights(path: Path, roadmap: Roadmap) -> np.ndarray:
    """Stored safe weights of ``roadmap``'s grown edges, checked against it; raises one of ``DAMAGE``
    when anything is off."""
    with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as data:
        header = json.loads(bytes(data["header"]).decode())
        arrays = {"weights": data["weights"]}
    if not isinstance(header, dict) or _digest(arrays, header) != header["digest"]:
        raise ValueError("checksum mismatch")
    weights = arrays["weights"]
    lengths = roadmap.weights[grown_edges(roadmap)]
    if weights.shape != lengths.shape or weights.dtype != np.float64:
        raise ValueError("weights of the wrong shape")
    if not np.isfinite(weights).all() or np.any(weights < lengths):
        raise ValueError("weights not finite or below the edges' lengths")
    weights.setflags(write=False)
    return weights
