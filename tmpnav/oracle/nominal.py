"""A nominal motion: what a robot does and sees when it drives a roadmap path, as a value.

A :class:`NominalMotion` is the path's node indices, the controls along it, the nominal poses
they produce, the landmarks visible from each pose and, with a range sensor, the cell and
heading of each pose's scan, with the seed of its noise stream (:func:`stable_seed`).
The oracle's motion library (tmpnav.oracle.motions) makes them and keeps them.
"""

from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from tmpnav.world.scan_information import ScanInformation


@dataclass(frozen=True, eq=False)
class NominalMotion:
    """One robot driving one roadmap path: its controls, nominal poses and what it sees."""

    robot: str
    path: tuple[int, ...]  # roadmap node indices, start first
    controls: np.ndarray  # (T, 2)
    poses: np.ndarray  # (T+1, 3)
    node_steps: np.ndarray  # (P,) step at which each path node is reached
    lm_visible: np.ndarray  # (T+1, L)
    noise_seed: int
    cells: np.ndarray  # (T+1,) the sub-cell key of each pose (World.reach(radius).cells)
    scan_keys: np.ndarray | None = None  # (T+1,) each pose's scan (World.scans(sensor).keys); None: no scans
    #: how the robot drives it: "rpp" (nav2's Regulated Pure Pursuit) or "turn-then-drive"
    controller: str = "turn-then-drive"
    #: the poses' rows of a reach or scan table, by the table (MotionLibrary.reach_layout)
    rows: dict[object, np.ndarray] = field(default_factory=dict, repr=False)

    def scan_rows(self, scans: ScanInformation | None) -> np.ndarray:
        """(T+1,) the rows of ``scans.table`` (the library's scan table) of the poses' scans (0: no scan)."""
        if self.scan_keys is None or scans is None:
            return np.zeros(self.poses.shape[0], dtype=np.int64)
        return scans.rows(self.scan_keys)

    @property
    def n_steps(self) -> int:
        return int(self.controls.shape[0])

    @property
    def final_heading(self) -> float:
        return float(self.poses[-1, 2])

    def padded(self, T: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Controls, poses and visibility extended to T steps: the robot waits at its
        goal (u = 0) and keeps observing from there."""
        extra = T - self.n_steps
        return (
            np.concatenate([self.controls, np.zeros((extra, 2))]),
            np.concatenate([self.poses, np.repeat(self.poses[-1:], extra, axis=0)]),
            np.concatenate([self.lm_visible, np.repeat(self.lm_visible[-1:], extra, axis=0)]),
        )

    def c_u(self, dt: float) -> float:
        """Control usage c_u = sum_k (v_k² + omega_k²) dt (docs/models.md)."""
        return float(self._squares * dt)

    @functools.cached_property
    def _squares(self) -> np.float64:
        """sum_k (v_k² + omega_k²), once: the oracle lays out the same motions again and again."""
        return np.float64((self.controls**2).sum(-1).sum())


def footprint(m: NominalMotion | None) -> int:
    """The bytes of a motion's arrays: controls, poses, the landmarks seen (none for a broadcast
    row of unseen ones) and its cells and scan keys, twice: the rows of the reach and scan tables
    the library keeps for them (:meth:`MotionLibrary._rows`) take as many again."""
    if m is None:
        return 0
    seen = 0 if m.lm_visible.strides[0] == 0 else m.lm_visible.nbytes
    keys = m.cells.nbytes + (0 if m.scan_keys is None else m.scan_keys.nbytes)
    return m.controls.nbytes + m.poses.nbytes + seen + 2 * keys


def stable_seed(*parts: object) -> int:
    """A 63-bit seed from any printable parts (stable across processes and machines)."""
    digest = hashlib.sha256(repr(parts).encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


@functools.lru_cache(maxsize=65536)
def scan_seed(noise_seed: int) -> int:
    """The seed of the range scans' draws that go with the landmark-noise stream ``noise_seed``."""
    return stable_seed(noise_seed, "scans")
