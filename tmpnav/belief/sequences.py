"""The belief stage's entry point for the oracle: a batch of simulations in, results out.

A :class:`SequenceBatch` holds C simulations of n robots each: which motions the robots
drive, from which initial belief, with which simulated observation noise, and who sees
whom at every step. :func:`propagate_sequences` runs them through the compiled EKF of
:mod:`tmpnav.belief.kernel` (the production path; its reference is the filterpy EKF of
:mod:`tmpnav.belief.ekf`) and returns a :class:`SequenceResults`.

Arrays are laid out for the kernel: motions end to end (:class:`MotionArrays`), one row
per simulation (:class:`Sequences`). The named tuples are passed to the kernel as they
are, so their fields are its arguments.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from tmpnav.belief.kernel import run_sequences
from tmpnav.types import Models, ObservationMode, ScanModelKind
from tmpnav.world.reach import encoded


class EKFConstants(NamedTuple):
    """The filter's constants: time step (s), motion noise, sensor noise, landmarks."""

    dt: float
    alphas: np.ndarray  # (4,) a1..a4 of the control noise W(u), paper eq. (4)
    Q_landmark: np.ndarray  # (2, 2) landmark observation noise (m², rad²)
    chol_landmark: np.ndarray  # (2, 2) its lower Cholesky factor
    Q_mutual: np.ndarray  # (2, 2) mutual observation noise (m², rad²)
    chol_mutual: np.ndarray  # (2, 2) its lower Cholesky factor
    max_likelihood: bool  # simulate z = h(mean) (no innovation) instead of h(pose) + noise
    landmarks: np.ndarray  # (L, 2) landmark positions (m)
    scans: bool  # the robots carry a range sensor (MotionArrays.scan_row, SequenceBatch.scan_noise)
    #: (2,) the localiser's update thresholds (m, rad): a step's scan counts by the share of them the
    #: step drives or turns, at most 1 (0, 0: every step's scan counts whole; ScanModel.update_rate)
    scan_thresholds: np.ndarray
    #: landmarks and mutual observations update the beliefs (False: a localiser of the lidar alone,
    #: nav2's AMCL; ScanModel.fuses_others)
    fuse_others: bool
    #: the collision bound's error relative to the walls the robot sees (ScanModel.local_walls): its
    #: variance per axis (m²; 0: the bound prices the belief itself) and the correlation of two
    #: consecutive steps' errors, exp(-dt / local_time)
    local_var: float
    local_rho: float
    #: wall hits per metre driven that the collision bound adds to the Gaussian error's
    #: (ScanModel.hazard, docs/models.md "Localisation failures"; 0: none)
    hazard: float
    #: 1: a step translates along the heading at its middle (Models.midpoint, RPP's steps that turn
    #: while they drive); 0: along the heading it starts with (the Euler step, the paper's)
    midpoint: float

    @staticmethod
    def of(models: Models, landmarks: np.ndarray) -> EKFConstants:
        """The constants of a scenario's models, with the world's landmarks (L, 2)."""
        Q_lm, Q_mu = models.landmark_sensor.Q, models.mutual_sensor.Q
        local_var, local_rho = local_walls(models)
        return EKFConstants(
            dt=models.dt,
            alphas=np.array(models.belief_noise, dtype=float),
            Q_landmark=Q_lm,
            chol_landmark=np.linalg.cholesky(Q_lm),
            Q_mutual=Q_mu,
            chol_mutual=np.linalg.cholesky(Q_mu),
            max_likelihood=models.observations is ObservationMode.MAX_LIKELIHOOD,
            landmarks=np.ascontiguousarray(landmarks, dtype=float).reshape(-1, 2),
            scans=models.range_sensor is not None,
            scan_thresholds=scan_thresholds(models),
            fuse_others=models.others_fused,
            local_var=local_var,
            local_rho=local_rho,
            hazard=hazard(models),
            midpoint=1.0 if models.midpoint else 0.0,
        )


def local_walls(models: Models) -> tuple[float, float]:
    """(variance per axis, correlation of consecutive steps) of the error the collision bound prices
    where the robots keep clear of the walls their lidar sees (ScanModel.local_walls); (0, 0) where
    it prices their beliefs."""
    sensor = models.range_sensor
    if sensor is None or not sensor.localiser.local_walls:
        return 0.0, 0.0
    return sensor.localiser.local_std**2, math.exp(-models.dt / sensor.localiser.local_time)


def hazard(models: Models) -> float:
    """:attr:`EKFConstants.hazard` of a scenario's models: its localiser's failures per metre driven."""
    sensor = models.range_sensor
    return 0.0 if sensor is None else sensor.localiser.hazard


def scan_thresholds(models: Models) -> np.ndarray:
    """:attr:`EKFConstants.scan_thresholds` of a scenario's models."""
    sensor = models.range_sensor
    if sensor is None or sensor.localiser.kind is ScanModelKind.BEAMS:
        return np.zeros(2)
    return np.array([sensor.localiser.update_min_d, sensor.localiser.update_min_a], dtype=float)


class MotionArrays(NamedTuple):
    """M nominal motions laid end to end.

    Motion m has ``steps[m]`` = T_m controls (v m/s, omega rad/s), rows ``offset[m]`` to
    ``offset[m] + T_m - 1`` of ``controls``, and T_m + 1 nominal poses (m, m, rad) and
    landmark-visibility rows, rows ``offset[m] + m`` to ``offset[m] + m + T_m`` of
    ``poses`` and ``lm_visible`` (L columns). After its last step a robot waits (u = 0)
    at its last pose and keeps observing from there. ``noise_stream[m]`` is the row of
    :attr:`SequenceBatch.landmark_noise` its simulated landmark observations use (and of
    :attr:`SequenceBatch.scan_noise`, its range scans'). A pose's range scan updates with
    the factor ``scan_table[scan_row[row]]`` (3, 3) of its information (tmpnav.world.lidar;
    row 0 of the table is zero: no scan).
    """

    offset: np.ndarray  # (M,) int64
    steps: np.ndarray  # (M,) int64
    controls: np.ndarray  # (sum T_m, 2)
    poses: np.ndarray  # (sum T_m + 1, 3)
    lm_visible: np.ndarray  # (sum T_m + 1, L) bool
    noise_stream: np.ndarray  # (M,) int64
    reach: np.ndarray  # (R, K) uint16/uint32: sector reaches (tmpnav.world.reach) as codes into reach_values
    reach_values: np.ndarray  # (V,) m: the reaches the codes stand for; a pose's are reach_values[reach[row]]
    reach_row: np.ndarray  # (sum T_m + 1,) int64: the row of ``reach`` of each nominal pose
    scan_row: np.ndarray  # (sum T_m + 1,) int64: the row of scan_table of each nominal pose's scan
    scan_table: np.ndarray  # (R, 3, 3): factors G of scan information, J = Gᵀ G; row 0 zero

    @staticmethod
    def of(
        controls: Sequence[np.ndarray],
        poses: Sequence[np.ndarray],
        lm_visible: Sequence[np.ndarray],
        noise_stream: np.ndarray,
        landmarks: int,
        reach: Sequence[np.ndarray] | np.ndarray | tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
        scans: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> MotionArrays:
        """Lay out motions given as per-motion arrays (T_m, 2), (T_m + 1, 3), (T_m + 1, L)
        and (T_m + 1, K) sector reach, or the reach already laid end to end (sum (T_m + 1), K),
        or a table of reaches as codes (R, K), the values they index (V,) and the row of each
        pose laid end to end (sum (T_m + 1),) as a tuple (:class:`~tmpnav.world.reach.SectorReach`;
        none given: no collision bound, one sector of infinite reach); ``scans``: the
        scan rows laid end to end (sum (T_m + 1),) and their table (R, 3, 3) (none given: no scans)."""
        steps = np.array([c.shape[0] for c in controls], dtype=np.int64)
        rows = int((steps + 1).sum())
        reach_row = np.arange(rows, dtype=np.int64)
        if reach is None:  # one sector of infinite reach: the kernel's bound is 0 at once
            codes, values = np.zeros((1, 1), dtype=np.uint16), np.full(1, np.inf)
            reach_row = np.zeros(rows, dtype=np.int64)
        elif isinstance(reach, tuple):
            codes, values, reach_row = reach[0], np.asarray(reach[1], dtype=float), np.asarray(reach[2], dtype=np.int64)
        elif isinstance(reach, np.ndarray):
            codes, values = encoded(np.asarray(reach, dtype=float).reshape(rows, -1))
        else:
            codes, values = encoded(np.concatenate(list(reach)).astype(float).reshape(rows, -1))
        return MotionArrays(
            offset=np.concatenate([[0], np.cumsum(steps)[:-1]]).astype(np.int64),
            steps=steps,
            controls=np.concatenate(list(controls)).reshape(-1, 2),
            poses=np.concatenate(list(poses)),
            lm_visible=np.ascontiguousarray(
                np.concatenate(list(lm_visible)).reshape(int((steps + 1).sum()), landmarks)
            ),
            noise_stream=np.asarray(noise_stream, dtype=np.int64),
            reach=np.ascontiguousarray(codes),
            reach_values=values,
            reach_row=reach_row,
            scan_row=np.zeros(rows, dtype=np.int64) if scans is None else np.asarray(scans[0], dtype=np.int64),
            scan_table=np.zeros((1, 3, 3)) if scans is None else np.asarray(scans[1], dtype=float),
        )


class StartGroups(NamedTuple):
    """G initial joint beliefs, each with the draws of its mutual observations."""

    mean0: np.ndarray  # (G, 3n)
    cov0: np.ndarray  # (G, 3n, 3n)
    mutual_noise: np.ndarray  # (G, T+1, n, n, 2) standard-normal draws: robot i observes j at step t


class Sequences(NamedTuple):
    """C simulations of n robots, in the order they run (trie order, :mod:`tmpnav.belief.trie`).

    Simulation c moves robot i along motion ``motions[c, i]`` from the belief of group
    ``group[c]`` and runs to step ``horizon[c]``. With ``restart[c]`` = d > 0 it starts
    from the state simulation c - 1 had after step d (they share their first d steps,
    noise and visibility included); d = 0 starts from the group's initial belief.
    Mutual visibility at step t is row ``mutual_offset[c] + t`` of
    :attr:`SequenceBatch.mutual_visible`.
    """

    group: np.ndarray  # (C,) int64
    motions: np.ndarray  # (C, n) int64
    restart: np.ndarray  # (C,) int64
    horizon: np.ndarray  # (C,) int64
    mutual_offset: np.ndarray  # (C,) int64

    @staticmethod
    def one(n: int, horizon: int) -> Sequences:
        """A single simulation: robot i moves along motion i from group 0's belief for
        ``horizon`` steps, mutual visibility from row 0."""
        return Sequences(
            group=np.zeros(1, dtype=np.int64),
            motions=np.arange(n, dtype=np.int64)[None],
            restart=np.zeros(1, dtype=np.int64),
            horizon=np.array([horizon], dtype=np.int64),
            mutual_offset=np.zeros(1, dtype=np.int64),
        )


@dataclass(frozen=True, eq=False)
class SequenceBatch:
    """Everything one kernel call needs (see the module docstring and each part's).

    ``landmark_noise`` (S, T+1, L, 2): standard-normal draws of the landmark observations
    per noise stream, step and landmark; ``mutual_visible`` (rows, n, n) bool: robot i sees
    robot j; ``c_sigma_history``: also return the running c_Sigma after every step;
    ``scan_noise`` (S, T+1, 3): the draws of the range scans' three pseudo-measurements per
    noise stream and step (read only when the robots carry a range sensor).
    """

    n: int
    ekf: EKFConstants
    motions: MotionArrays
    landmark_noise: np.ndarray
    groups: StartGroups
    sequences: Sequences
    mutual_visible: np.ndarray
    c_sigma_history: bool = False
    scan_noise: np.ndarray = field(default_factory=lambda: np.zeros((1, 1, 3)))

    @property
    def horizon(self) -> int:
        """The last step of the longest simulation."""
        return int(self.sequences.horizon.max(initial=0))

    def check(self) -> None:
        """Raise ValueError naming the first array that does not fit the others (the
        compiled kernel does not check its indices)."""
        n, C, T = self.n, self.sequences.group.shape[0], self.horizon
        M = self.motions.steps.shape[0]
        seq = self.sequences
        expected: dict[str, tuple[np.ndarray, tuple[int | None, ...]]] = {
            "sequences.motions": (seq.motions, (C, n)),
            "sequences.restart": (seq.restart, (C,)),
            "sequences.horizon": (seq.horizon, (C,)),
            "sequences.mutual_offset": (seq.mutual_offset, (C,)),
            "groups.cov0": (self.groups.cov0, (self.groups.mean0.shape[0], 3 * n, 3 * n)),
            "groups.mutual_noise": (self.groups.mutual_noise, (self.groups.mean0.shape[0], None, n, n, 2)),
            "landmark_noise": (self.landmark_noise, (None, None, self.ekf.landmarks.shape[0], 2)),
            "mutual_visible": (self.mutual_visible, (None, n, n)),
        }
        for name, (value, shape) in expected.items():
            if value.ndim != len(shape) or any(
                s is not None and s != v for s, v in zip(shape, value.shape, strict=True)
            ):
                raise ValueError(f"{name} has shape {value.shape}, expected {shape} (None: any)")
        if C and (seq.motions.min() < 0 or seq.motions.max() >= M):
            raise ValueError(f"sequences.motions must index the {M} motions")
        if C and (seq.group.min() < 0 or seq.group.max() >= self.groups.mean0.shape[0]):
            raise ValueError("sequences.group must index the start groups")
        if self.groups.mutual_noise.shape[1] <= T or self.landmark_noise.shape[1] <= T:
            raise ValueError(f"the noise draws must cover steps 0..{T}")
        rows = self.motions.reach_row
        if rows.size and (rows.min() < 0 or rows.max() >= self.motions.reach.shape[0]):
            raise ValueError("motions.reach_row must index motions.reach")
        if self.ekf.scans:
            streams = int(self.motions.noise_stream.max(initial=-1)) + 1
            if self.scan_noise.ndim != 3 or self.scan_noise.shape[0] < streams or self.scan_noise.shape[1] <= T:
                raise ValueError(f"scan_noise has shape {self.scan_noise.shape}, expected ({streams}, >{T}, 3)")
            rows = self.motions.scan_row
            if rows.size and (rows.min() < 0 or rows.max() >= self.motions.scan_table.shape[0]):
                raise ValueError("motions.scan_row must index motions.scan_table")
        if C and int((seq.mutual_offset + seq.horizon).max()) >= self.mutual_visible.shape[0]:
            raise ValueError("mutual_visible must have a row for every step of every simulation")


@dataclass(frozen=True, eq=False)
class SequenceResults:
    """What the simulations of a batch end with, one row per simulation.

    ``mean`` (C, 3n), ``cov`` (C, 3n, 3n): the joint belief after the last step;
    ``c_sigma`` (C, n): c_Sigma of each robot (docs/models.md, "Motion cost");
    ``arrival_xy`` (C, n, 2): each robot's mean position after its own last step;
    ``mutual_steps`` (C,): steps with at least one mutual observation;
    ``risk`` (C, n): each robot's collision bound over its driving steps (first passage,
    tmpnav.belief.risk.move_bound), not capped at 1; 0 where the motions carry no sector reach;
    ``c_sigma_history`` (C, T+1, n): the running c_Sigma after every step, if asked for;
    ``last_means`` (T+1, 3n), ``last_covs`` (T+1, 3n, 3n): the history of the last
    simulation (its whole trajectory if it started from its group's initial belief);
    ``step_risk`` (T+1, n, 2): its p_t and X_t of every robot and step (risk.step_bound and
    risk.crossing_bound; 0 where a robot stands or no bound is wanted, p_0 at row 0), from
    which :func:`tmpnav.belief.risk.running_bound` sums a bound over any driving steps.
    """

    mean: np.ndarray
    cov: np.ndarray
    c_sigma: np.ndarray
    arrival_xy: np.ndarray
    mutual_steps: np.ndarray
    c_sigma_history: np.ndarray | None
    risk: np.ndarray
    last_means: np.ndarray
    last_covs: np.ndarray
    step_risk: np.ndarray


class _KernelOutputs(NamedTuple):
    mean: np.ndarray
    cov: np.ndarray
    c_sigma: np.ndarray
    arrival_xy: np.ndarray
    mutual_steps: np.ndarray
    c_sigma_history: np.ndarray
    risk: np.ndarray


def propagate_sequences(batch: SequenceBatch) -> SequenceResults:
    """Run every simulation of ``batch`` through the compiled EKF (paper eqs. (8), (9), (11)-(15))."""
    batch.check()
    n, C, T = batch.n, batch.sequences.group.shape[0], batch.horizon
    out = _KernelOutputs(
        np.empty((C, 3 * n)),
        np.empty((C, 3 * n, 3 * n)),
        np.empty((C, n)),
        np.empty((C, n, 2)),
        np.empty(C, dtype=np.int64),
        np.zeros((C, T + 1, n)) if batch.c_sigma_history else np.zeros((0, 1, n)),
        np.empty((C, n)),
    )
    last_means, last_covs, step_risk = run_sequences(
        n,
        batch.ekf,
        batch.motions,
        batch.landmark_noise,
        np.ascontiguousarray(batch.scan_noise, dtype=float),
        batch.groups,
        batch.sequences,
        batch.mutual_visible,
        out,
    )
    return SequenceResults(
        mean=out.mean,
        cov=out.cov,
        c_sigma=out.c_sigma,
        arrival_xy=out.arrival_xy,
        mutual_steps=out.mutual_steps,
        c_sigma_history=out.c_sigma_history if batch.c_sigma_history else None,
        risk=out.risk,
        last_means=last_means,
        last_covs=last_covs,
        step_risk=step_risk,
    )


def standard_normal_draws(seeds: Sequence[int], shape: tuple[int, ...]) -> np.ndarray:
    """(len(seeds), *shape) standard-normal draws, one independent stream per seed.

    A stream's draws are filled in C order, so a stream drawn for more steps starts with
    the draws of a shorter one: a simulation's noise does not depend on its batch.
    """
    return np.stack([np.random.default_rng(s).standard_normal(shape) for s in seeds])


class NoiseStreams:
    """Standard-normal streams by seed, kept once drawn, up to ``limit`` bytes (the least
    recently used dropped first): the oracle and the team's clock ask for the same streams
    again and again (20-room building: 0.47 s of 5 s of the oracle drew them anew).

    The limit is per process (the run's and each oracle worker's). 16 MB holds every stream of
    the 20-room building (7.4 MB in one process). At 128 MB the 40-room office's peak memory
    (all processes, resident) rose from 1.73 to 1.93 GB, the main process and both workers
    each holding a full set, for no measured gain in speed there (the search stops at its
    budget either way).

    Drawn in C order, a stream drawn longer starts with the draws of a shorter one
    (:func:`standard_normal_draws`), so a stream is drawn again, twice as long, only when
    more rows are needed, and what it gives is bit for bit what :func:`standard_normal_draws`
    gives."""

    def __init__(self, limit: int = 16 * 2**20):
        self.limit = limit
        self._have: OrderedDict[tuple[int, tuple[int, ...]], np.ndarray] = OrderedDict()
        self._bytes = 0

    def rows(self, seed: int, rows: int, tail: tuple[int, ...]) -> np.ndarray:
        """At least the first ``rows`` rows of the stream of ``seed``, each of shape ``tail``."""
        key = (seed, tail)
        have = self._have.get(key)
        if have is not None and have.shape[0] >= rows:
            self._have.move_to_end(key)
            return have
        size = max(rows, 64 if have is None else 2 * have.shape[0])
        fresh = np.random.default_rng(seed).standard_normal((size, *tail))
        if have is not None:
            self._bytes -= self._have.pop(key).nbytes
        self._have[key] = fresh
        self._bytes += fresh.nbytes
        while self._bytes > self.limit and len(self._have) > 1:
            self._bytes -= self._have.popitem(last=False)[1].nbytes
        return fresh

    def draws(self, seeds: Sequence[int], shape: tuple[int, ...]) -> np.ndarray:
        """:func:`standard_normal_draws` of ``seeds`` and ``shape``, from the kept streams."""
        return np.stack([self.rows(s, shape[0], shape[1:])[: shape[0]] for s in seeds])
