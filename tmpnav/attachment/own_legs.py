"""Each robot's belief along its own legs, where the robots take in nothing of each other.

The team's clock (:mod:`tmpnav.attachment.clock`) runs the whole team in one joint EKF, because
robots that observe each other become correlated. Where no two robots of a team observe each
other (nav2's AMCL fusing its lidar alone, or mutual observations switched off: no
:class:`~tmpnav.world.visibility.MutualSensing` between any two) and their initial beliefs are
uncorrelated, the joint covariance stays block-diagonal, and robot i's belief is a function of
its own legs alone: its initial belief, then each move it drives (from the step it starts)
and the standing after it. The joint kernel's updates then touch only the observed robot's
block, with the same operations as a simulation of that robot alone (tmpnav.belief.kernel), so
a leg propagated on its own gives the joint run's beliefs to rounding (the compiled loops of a
3-state filter and of a 3n-state one round differently in the last bit).

:class:`OwnLegs` propagates each leg once (:class:`LegBelief`, the same compiled kernel with
n = 1) and keeps it by the robot's whole history of legs up to it (:meth:`OwnLegs.key`). Every
run of every plan that gives a robot the same legs up to then reads its belief from there: a
plan that changes one robot's route, or holds one robot back, runs that robot's new legs only,
where the joint EKF ran the whole team again (at 16 robots, 200 runs of the search's
candidates held a robot's first step and could not resume, benchmarks/fleet/split.txt).

A leg is computed in pieces at fixed rows, its drive in one kernel call and the standing after
it in blocks of :data:`TAIL` steps, so that what a run reads does not depend on which run
computed it first. A move's c_Sigma and collision bound are summed from its own start (the
joint run sums them from the run's start and takes differences: the two agree to rounding).
"""

from __future__ import annotations

import hashlib
import itertools
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import TYPE_CHECKING
from weakref import WeakKeyDictionary

import numpy as np

from tmpnav.belief.conflicts import position_sigma
from tmpnav.belief.risk import running_bound
from tmpnav.belief.sequences import (
    EKFConstants,
    MotionArrays,
    SequenceBatch,
    SequenceResults,
    Sequences,
    StartGroups,
    propagate_sequences,
)
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.nominal import NominalMotion, scan_seed
from tmpnav.types import TrajectoryStep

if TYPE_CHECKING:
    from tmpnav.attachment.clock_state import Leg

#: steps of one block of a leg's standing after its drive (where standing changes the belief)
TAIL = 128
#: legs kept (the least recently used dropped first): a 16-robot plan of 100 rooms has about
#: 120; a leg of 300 steps with its record takes about 100 kB
MAX_LEGS = 4096
#: leg histories kept as keys (the least recently used dropped first; a key dropped is made anew
#: when asked for again, a new number: never another history's)
MAX_KEYS = 65536


@dataclass(eq=False)
class LegBelief:
    """One robot's belief along one leg, from its start (row 0) on: rows 0..``drive`` the move
    (none for a robot standing before its first move), then the standing after it.

    ``static``: standing changes nothing (no landmarks fused, a localiser that updates only on
    the move), so rows past the drive are its last row."""

    robot: int
    leg: Leg
    drive: int
    static: bool
    means: np.ndarray  # (rows computed, 3)
    covs: np.ndarray  # (rows computed, 3, 3)
    csig: np.ndarray  # (drive + 1,) the move's running c_Sigma
    risk: np.ndarray  # (drive + 1,) the move's running collision bound
    nodes: dict[int, int]  # row -> the roadmap node reached there
    record: list[TrajectoryStep] = field(default_factory=list)  # rows 1.. as far as asked
    _sigma: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)  # position_sigma(covs), as of covs

    def row(self, r: int) -> int:
        """The row of the arrays that holds row ``r`` (computed)."""
        return min(r, self.drive) if self.static else r

    def track(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
        """Rows lo..hi-1 (computed) as positions (n, 2) m and position stds (n,) m
        (tmpnav.attachment.record.Rows): what :meth:`OwnLegs.records` holds of them."""
        rows = np.arange(lo, hi)
        if self.static:
            rows = np.minimum(rows, self.drive)
        if self._sigma.shape[0] != self.covs.shape[0]:  # the leg's standing grew: its rows' stds again
            self._sigma = position_sigma(self.covs)
        return self.means[rows, :2], self._sigma[rows]


class OwnLegs:
    """The legs of one team's robots, propagated one robot at a time (the module docstring)."""

    def __init__(self, lib: MotionLibrary, ekf: EKFConstants, radii: tuple[float, ...]):
        self.lib, self.ekf, self.radii = lib, ekf, radii
        self.dt = lib.scenario.models.dt
        self._fov = lib.scenario.models.landmark_sensor.fov
        #: standing changes nothing: no landmark updates, and a scan counts by the share of the
        #: update thresholds a step drives (kernel.scan_weight: 0 standing); the prediction with
        #: u = 0 adds nothing
        self.static = (not ekf.fuse_others or ekf.landmarks.shape[0] == 0) and (
            not ekf.scans or float(ekf.scan_thresholds[0]) > 0.0
        )
        self._keys: OrderedDict[tuple[object, ...], int] = OrderedDict()
        self._legs: OrderedDict[tuple[int, bool], LegBelief] = OrderedDict()
        self.computed = 0  # legs propagated (for the benchmarks)

    # ------------------------------------------------------------------ keys

    def key(
        self, robot: int, before: int, leg_start: int, motion: NominalMotion | None, pose: np.ndarray, seed: int
    ) -> int:
        """The number of robot ``robot``'s history of legs ending with a leg that starts at
        ``leg_start``, drives ``motion`` (None: stands at ``pose``) with the noise of ``seed``,
        after the history numbered ``before`` (-1: none)."""
        what = pose.tobytes() if motion is None else _digest(motion)
        k = (robot, before, leg_start, seed, what)
        found = self._keys.get(k)
        if found is None:
            found = self._keys[k] = next(_NUMBERS)
            if len(self._keys) > MAX_KEYS:
                self._keys.popitem(last=False)
        else:
            self._keys.move_to_end(k)
        return found

    # ------------------------------------------------------------------ beliefs

    def belief(
        self, robot: int, legs: tuple[Leg, ...], priced: bool, rows: int, start: tuple[np.ndarray, np.ndarray]
    ) -> LegBelief:
        """The belief along robot ``robot``'s last leg of ``legs`` (its legs so far), computed to
        at least row ``rows``; ``start``: the robot's initial belief (mean (3,), cov (3, 3)).
        ``priced``: with its moves' collision bound."""
        leg = legs[-1]
        key = (leg.key, priced)
        found = self._legs.get(key)
        if found is None:
            if len(legs) == 1:
                mean, cov = start
            else:
                before = self.belief(robot, legs[:-1], priced, leg.start - legs[-2].start, start)
                r = before.row(leg.start - legs[-2].start)
                mean, cov = before.means[r], before.covs[r]
            found = self._legs[key] = self._propagate(robot, leg, priced, mean, cov)
            if len(self._legs) > MAX_LEGS:
                self._legs.popitem(last=False)
        else:
            self._legs.move_to_end(key)
        if not found.static:
            while found.means.shape[0] <= rows:
                self._stand(found)
        return found

    def records(self, b: LegBelief, lo: int, hi: int) -> list[TrajectoryStep]:
        """The record's steps of rows lo..hi-1 (lo >= 1) of ``b`` (computed)."""
        have = len(b.record)  # rows 1..have
        if have < hi - 1:
            start = b.leg.start
            first, last = b.row(have + 1), b.row(hi - 1)
            means = [tuple(m) for m in b.means[first : last + 1].tolist()]
            covs = [(tuple(c[0]), tuple(c[1]), tuple(c[2])) for c in b.covs[first : last + 1].tolist()]
            for r in range(have + 1, hi):  # rows past a static leg's drive share its last row's values
                j = b.row(r) - first
                t = round(float((start + r) * self.dt), 9)
                b.record.append(TrajectoryStep(t, means[j], covs[j], b.nodes.get(r)))
        return b.record[lo - 1 : hi - 1]

    def _propagate(self, robot: int, leg: Leg, priced: bool, mean: np.ndarray, cov: np.ndarray) -> LegBelief:
        """A leg's drive from its start belief, in one kernel call (rows 0..drive)."""
        self.computed += 1
        m = leg.motion
        if m is None:
            return LegBelief(
                robot, leg, 0, self.static, mean[None].copy(), cov[None].copy(), np.zeros(1), np.zeros(1), {}
            )
        T = m.n_steps
        k = np.arange(T + 1)
        reach = self.lib.reach(m, k) if priced else np.full((T + 1, 1), np.inf)
        out = self._run(mean, cov, m.controls, m.poses, m.lm_visible, reach, m.scan_keys, leg.noise_seed, 0)
        assert out.c_sigma_history is not None
        drove = np.ones(T + 1, dtype=bool)
        drove[0] = False  # a move starts standing (its first step adds min(p_1, p_0 + X_1))
        risk = running_bound(out.step_risk[:, 0], drove) if priced else np.zeros(T + 1)
        nodes: dict[int, int] = {}
        for node, s in zip(m.path, m.node_steps.tolist(), strict=False):
            if 0 < s <= T:
                nodes[s] = int(node)
        return LegBelief(
            robot,
            leg,
            T,
            self.static,
            out.last_means.copy(),
            out.last_covs.copy(),
            out.c_sigma_history[0, :, 0].copy(),
            risk,
            nodes,
        )

    def _stand(self, b: LegBelief) -> None:
        """The next :data:`TAIL` rows of ``b``'s standing (rows past its drive)."""
        s0 = b.means.shape[0] - 1
        leg, m = b.leg, b.leg.motion
        if m is None:
            pose = leg.pose
            vis = self.lib.visibility.visible(pose[None], self._fov, min_range=self.radii[b.robot])[0]
            key = None if self.lib.scans is None else self.lib.scans.keys(pose)
        else:
            pose, vis = m.poses[-1], m.lm_visible[-1]
            key = None if m.scan_keys is None else m.scan_keys[-1]
        poses = np.repeat(np.asarray(pose, dtype=float)[None], TAIL + 1, axis=0)
        visible = np.repeat(np.asarray(vis)[None], TAIL + 1, axis=0)
        keys = None if key is None else np.full(TAIL + 1, key, dtype=np.int64)
        reach = np.full((TAIL + 1, 1), np.inf)
        out = self._run(b.means[s0], b.covs[s0], np.zeros((TAIL, 2)), poses, visible, reach, keys, leg.noise_seed, s0)
        b.means = np.concatenate([b.means, out.last_means[1:]])
        b.covs = np.concatenate([b.covs, out.last_covs[1:]])

    def _run(
        self,
        mean: np.ndarray,
        cov: np.ndarray,
        controls: np.ndarray,
        poses: np.ndarray,
        visible: np.ndarray,
        reach: np.ndarray,
        keys: np.ndarray | None,
        seed: int,
        k0: int,
    ) -> SequenceResults:
        """One robot through ``controls`` from (``mean``, ``cov``): rows k0..k0+T of its leg,
        the leg's noise streams read from row k0."""
        T, L = controls.shape[0], self.ekf.landmarks.shape[0]
        lib, scans = self.lib, self.lib.scans
        rows = np.arange(k0, k0 + T + 1)
        noise = lib.noise.rows(seed, k0 + T + 1, (L, 2))[rows]
        scan_noise = np.zeros((T + 1, 3))
        if scans is not None and not self.ekf.max_likelihood:
            scan_noise = lib.noise.rows(scan_seed(seed), k0 + T + 1, (3,))[rows]
        scan_rows = None
        if scans is not None:
            ks = np.full(T + 1, -1, dtype=np.int64) if keys is None else np.asarray(keys, dtype=np.int64)
            scan_rows = (scans.rows(ks), scans.table)
        batch = SequenceBatch(
            n=1,
            ekf=self.ekf,
            motions=MotionArrays.of(
                [controls], [poses], [visible], np.zeros(1, dtype=np.int64), L, [reach], scans=scan_rows
            ),
            landmark_noise=noise[None],
            groups=StartGroups(mean[None].copy(), cov[None].copy(), np.zeros((1, T + 1, 1, 1, 2))),
            sequences=Sequences.one(1, T),
            mutual_visible=np.zeros((T + 1, 1, 1), dtype=bool),
            c_sigma_history=True,
            scan_noise=scan_noise[None],
        )
        return propagate_sequences(batch)


#: each motion's digest (its path, controller, controls and poses), while the motion lives
_DIGESTS: WeakKeyDictionary[NominalMotion, bytes] = WeakKeyDictionary()


def _digest(motion: NominalMotion) -> bytes:
    """128 bits that tell one motion from another: two motions along the same path can differ
    (a detour is driven along the path itself, a shortest path along its shortened form)."""
    found = _DIGESTS.get(motion)
    if found is None:
        h = hashlib.blake2b(digest_size=16)
        h.update(repr((motion.robot, motion.path, motion.controller)).encode())
        h.update(np.ascontiguousarray(motion.controls).tobytes())
        h.update(np.ascontiguousarray(motion.poses).tobytes())
        found = _DIGESTS[motion] = h.digest()
    return found


#: the numbers of leg histories, never one twice in a process
_NUMBERS = itertools.count(1)
