"""Motions as the compiled kernel reads them, and the runs of the kernel the oracle makes.

A :class:`MotionSet` is every motion one robot may drive from one start state, sorted in
lexicographic order of their controls: neighbours share the longest prefixes. A
:class:`MotionTable` lays many motions end to end (:class:`tmpnav.belief.sequences.MotionArrays`)
and runs simulations of them through the belief stage (:meth:`MotionTable.propagate`).
:func:`trajectory` is the one simulation with its whole history that the re-simulation of a
plan needs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from tmpnav.belief.sequences import (
    EKFConstants,
    MotionArrays,
    SequenceBatch,
    SequenceResults,
    Sequences,
    StartGroups,
    propagate_sequences,
)
from tmpnav.belief.trie import common_prefix_matrix
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.nominal import NominalMotion, scan_seed
from tmpnav.oracle.requests import StartState
from tmpnav.types import ObservationMode


@dataclass
class MotionSet:
    """The motions of one robot from one start state, in lexicographic order of controls.

    Neighbours in this order share the longest prefixes; ``prefix[a, b]`` is the number of
    leading steps motions a and b have in common. ``by_goal`` maps a goal node to its
    motion's position.
    """

    robot: str
    start: StartState
    motions: list[NominalMotion]
    by_goal: dict[int, int]
    prefix: np.ndarray
    steps: np.ndarray  # (k,) T of each motion
    c_u: np.ndarray  # (k,) control usage of each motion
    goal_xy: np.ndarray  # (k, 2) nominal final position

    @staticmethod
    def build(robot: str, start: StartState, motions: dict[int, NominalMotion], dt: float) -> MotionSet:
        ordered = sorted(motions.items(), key=lambda kv: order_key(kv[1].controls))
        ms = [m for _, m in ordered]
        T = np.array([m.n_steps for m in ms], dtype=np.int64)
        off = np.concatenate([[0], np.cumsum(T)[:-1]]).astype(np.int64)
        ctrl = np.concatenate([m.controls for m in ms]).reshape(-1, 2)
        prefix = common_prefix_matrix(ctrl, off, T, np.arange(len(ms), dtype=np.int64))
        return MotionSet(
            robot,
            start,
            ms,
            {g: k for k, (g, _) in enumerate(ordered)},
            prefix,
            T,
            np.array([m.c_u(dt) for m in ms]),
            np.array([m.poses[-1, :2] for m in ms]),
        )

    def goals_in(self, lib: MotionLibrary, room: str) -> list[int]:
        """Positions of the motions to the room's instantiations, in the roadmap's order."""
        return [self.by_goal[g] for g in lib.roadmap.instantiations[room] if g in self.by_goal]


def order_key(controls: np.ndarray) -> bytes:
    """Bytes that sort as the controls (T, 2) do in lexicographic order of their floats (as
    tuples of them would), a shorter sequence first where it is the other's prefix: each float
    mapped to an unsigned integer of the same order (sign bit set on a positive one, every bit
    flipped on a negative one; -0.0 counted as 0.0), written big-endian. Sorting a fleet's motion
    sets by tuples of their controls took a tenth of its oracle workers' time."""
    bits = (np.ascontiguousarray(controls, dtype=float).ravel() + 0.0).view(np.uint64)
    keyed = np.where(bits >> np.uint64(63), ~bits, bits | np.uint64(1 << 63))
    return keyed.astype(">u8").tobytes()


SetKey = tuple[str, StartState]


def motion_sets(lib: MotionLibrary, wanted: dict[SetKey, set[int]]) -> dict[SetKey, MotionSet]:
    """The motion set of each (robot, start state) to the goal nodes wanted from it; a
    start that reaches none of them has no set.

    A set's motions and their order depend on the robot, its start node and heading and the
    goals, not on its belief: the order and the arrays of a set built before from the same
    node and heading to the same goals are taken with the new start (``lib.sets``; a
    sub-problem asks for the sets of its singles again for its pairs, and the next
    sub-problem for many of the same). The motions themselves are the library's."""
    sets = {}
    memo, dt = lib.sets, lib.scenario.models.dt
    for (robot, start), goals in wanted.items():
        key = (robot, start.node, start.heading, frozenset(goals))
        layout = memo.get(key)
        if layout is not None:
            memo.move_to_end(key)
            order, prefix, steps, c_u, goal_xy = layout
            motions = [m for g in order if (m := lib.motion(robot, start.node, start.heading, g)) is not None]
            if len(motions) == len(order):
                by_goal = {g: k for k, g in enumerate(order)}
                sets[(robot, start)] = MotionSet(robot, start, motions, by_goal, prefix, steps, c_u, goal_xy)
                continue
        found = {g: lib.motion(robot, start.node, start.heading, g) for g in sorted(goals)}
        valid = {g: m for g, m in found.items() if m is not None}
        if not valid:
            continue
        built = sets[(robot, start)] = MotionSet.build(robot, start, valid, dt)
        order = tuple(sorted(built.by_goal, key=built.by_goal.__getitem__))
        memo[key] = (order, built.prefix, built.steps, built.c_u, built.goal_xy)
        while len(memo) > MAX_SETS:
            memo.popitem(last=False)
    return sets


#: motion sets remembered per library (the least recently used dropped first)
MAX_SETS = 4096


def chain_restarts(
    P1: np.ndarray, a: np.ndarray, horizon: np.ndarray, P2: np.ndarray | None = None, b: np.ndarray | None = None
) -> np.ndarray:
    """Steps each simulation shares with the previous one (0 for the first), for one robot
    moving along motions ``a`` of a set with prefix matrix P1 (and a second along ``b``)."""
    start = np.zeros(a.shape[0], dtype=np.int64)
    if a.shape[0] > 1:
        shared = P1[a[:-1], a[1:]]
        if P2 is not None and b is not None:
            shared = np.minimum(shared, P2[b[:-1], b[1:]])
        start[1:] = np.minimum(shared, horizon[:-1])
    return start


class GroupStart(NamedTuple):
    """The initial joint belief of a group of simulations and its mutual-noise seed."""

    mean0: np.ndarray
    cov0: np.ndarray
    seed: int


class MotionTable:
    """Motions laid out for the compiled kernel (concatenated arrays with offsets).

    ``priced``: the collision bound is wanted (a threshold on it, ``max_risk``, chooses among
    the instantiations); without one the table has no sector reach, and the kernel's bound
    is 0 at every step at no cost: on the 10-room corridor the bound was three quarters of
    the kernel's time (1.07 s of 1.42 s), for numbers no one read."""

    def __init__(self, motions: list[NominalMotion], lib: MotionLibrary, priced: bool = True):
        landmarks, dt = lib.world.landmark_xy.shape[0], lib.scenario.models.dt
        self.offset: dict[int, int] = {}
        self.motions = motions
        self.c_u = np.array([m.c_u(dt) for m in motions])
        streams: dict[int, int] = {}
        stream = np.array([streams.setdefault(m.noise_seed, len(streams)) for m in motions], dtype=np.int64)
        self.seeds = list(streams)  # one landmark-noise stream per robot and start node
        self.arrays = MotionArrays.of(
            [m.controls for m in motions],
            [m.poses for m in motions],
            [m.lm_visible for m in motions],
            stream,
            landmarks,
            lib.reach_layout(motions) if priced else None,
            scan_layout(motions, lib),
        )

    @staticmethod
    def of_sets(sets: list[MotionSet], lib: MotionLibrary, priced: bool = True) -> MotionTable:
        table = MotionTable([m for ms in sets for m in ms.motions], lib, priced)
        k = 0
        for ms in sets:
            table.offset[id(ms)] = k
            k += len(ms.motions)
        return table

    def ids(self, ms: MotionSet, local: np.ndarray) -> np.ndarray:
        """Table rows of the motions at positions ``local`` of set ``ms``."""
        return self.offset[id(ms)] + local

    def goal_xy(self, ids: np.ndarray) -> np.ndarray:
        """Nominal final position (..., 2) of the motions ``ids`` (any shape)."""
        a = self.arrays
        return a.poses[a.offset[ids] + ids + a.steps[ids], :2]

    def propagate(
        self,
        lib: MotionLibrary,
        n: int,
        groups: list[GroupStart],
        sequences: Sequences,
        mutual_visible: np.ndarray,
        mutual_noise: np.ndarray | None = None,
        c_sigma_history: bool = False,
    ) -> SequenceResults:
        """Run ``sequences`` of n robots over this table's motions in one kernel call.

        Landmark noise is drawn per stream (robot and start node), mutual noise per group
        from its seed unless ``mutual_noise`` (G, T+1, n, n, 2) is given.
        """
        models = lib.scenario.models
        landmarks = np.ascontiguousarray(lib.world.landmark_xy)
        T = int(sequences.horizon.max(initial=0))
        if mutual_noise is None:
            mutual_noise = lib.noise.draws([g.seed for g in groups], (T + 1, n, n, 2))
        batch = SequenceBatch(
            n=n,
            ekf=EKFConstants.of(models, landmarks),
            motions=self.arrays,
            landmark_noise=lib.noise.draws(self.seeds, (T + 1, landmarks.shape[0], 2)),
            scan_noise=scan_draws(lib, self.seeds, T),
            groups=StartGroups(np.stack([g.mean0 for g in groups]), np.stack([g.cov0 for g in groups]), mutual_noise),
            sequences=sequences,
            mutual_visible=mutual_visible,
            c_sigma_history=c_sigma_history,
        )
        return propagate_sequences(batch)


def scan_layout(motions: list[NominalMotion], lib: MotionLibrary) -> tuple[np.ndarray, np.ndarray] | None:
    """The scan rows of ``motions``' poses laid end to end, and the table they index (None
    without a range sensor)."""
    if lib.scans is None:
        return None
    rows = lib.scan_rows_all(motions)
    return rows, lib.scans.table  # the table after the rows were added to it


def scan_draws(lib: MotionLibrary, seeds: list[int], T: int) -> np.ndarray:
    """The range scans' draws (S, T+1, 3) of the landmark-noise streams ``seeds``; zeros where no
    scan is simulated with noise (no range sensor, or maximum-likelihood observations)."""
    models = lib.scenario.models
    if lib.scans is None or models.observations is ObservationMode.MAX_LIKELIHOOD:
        return np.zeros((max(len(seeds), 1), T + 1, 3))
    return lib.noise.draws([scan_seed(s) for s in seeds], (T + 1, 3))


def row_offsets(horizon: np.ndarray) -> np.ndarray:
    """First row of each simulation in a stack of per-step rows (steps 0..horizon)."""
    return np.concatenate([[0], np.cumsum(horizon + 1)[:-1]]).astype(np.int64)
