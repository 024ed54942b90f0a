"""The whole team over a window of control steps in one joint EKF (:mod:`tmpnav.attachment.clock`).

Between two events of a run on the team's clock nothing starts: each robot drives the rest of
its current move, or stands. :meth:`JointWindow.advance` lays out every robot's controls, nominal
poses, visibility and draws over the window (from its legs) and runs them through the compiled
kernel as one simulation of the whole team, whose robots may observe each other
(:class:`~tmpnav.world.visibility.MutualSensing`). Where no robot takes in another, the clock
runs each robot along its own moves instead (:mod:`tmpnav.attachment.own_legs`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from tmpnav.attachment.clock_state import ClockState
from tmpnav.attachment.record import Trace
from tmpnav.attachment.team import Team
from tmpnav.belief.risk import running_bound
from tmpnav.belief.sequences import (
    EKFConstants,
    MotionArrays,
    SequenceBatch,
    Sequences,
    StartGroups,
    propagate_sequences,
)
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.nominal import scan_seed, stable_seed
from tmpnav.world.reach import SECTORS
from tmpnav.world.visibility import MutualSensing

if TYPE_CHECKING:
    from tmpnav.types import Scenario

#: steps of one block of the mutual-noise stream of a pair of robots outside paired moves
MUTUAL_BLOCK = 512


class JointWindow:
    """The team's joint EKF over windows of control steps (the module docstring)."""

    def __init__(
        self,
        lib: MotionLibrary,
        ekf: EKFConstants,
        names: tuple[str, ...],
        sensing: dict[tuple[int, int], MutualSensing],
        radii: tuple[float, ...],
    ):
        self.lib, self.ekf, self.names, self.sensing, self.radii = lib, ekf, names, sensing, radii
        self.scenario: Scenario = lib.scenario
        self.dt = self.scenario.models.dt

    def advance(
        self, state: ClockState, until: int, priced: bool, trace: Trace | None
    ) -> tuple[ClockState, np.ndarray, list[list[float]], list[np.ndarray]]:
        """The team from the clock's time to step ``until`` (one kernel call): the state then
        (its moves not yet closed), the team's means over the window (h + 1, 3n), each robot's
        running c_Sigma and collision bound over it (from the state's); ``trace`` extended."""
        a, h, n = state.t, until - state.t, len(self.names)
        windows = [self._window(state, i, a, until, priced) for i in range(n)]
        poses = [w[1] for w in windows]
        visible = self._visible(poses, h)
        scans = self.lib.scans
        batch = SequenceBatch(
            n=n,
            ekf=self.ekf,
            motions=MotionArrays.of(
                [w[0] for w in windows],
                poses,
                [w[2] for w in windows],
                np.arange(n),
                self.ekf.landmarks.shape[0],
                [w[4] for w in windows],
                scans=None if scans is None else (scans.rows(np.concatenate([w[6] for w in windows])), scans.table),
            ),
            landmark_noise=np.stack([w[3] for w in windows]),
            groups=StartGroups(
                state.team.mean[None], state.team.cov[None], self._mutual_noise(state, a, until, visible)[None]
            ),
            sequences=Sequences.one(n, h),
            mutual_visible=visible,
            c_sigma_history=True,
            scan_noise=np.stack([w[7] for w in windows]),
        )
        out = propagate_sequences(batch)
        assert out.c_sigma_history is not None
        running = [[state.csig[i] + float(c) for c in out.c_sigma_history[0, :, i]] for i in range(n)]
        zero = np.zeros(h + 1)
        risk = [
            state.risk[i] + (running_bound(out.step_risk[:, i], windows[i][5]) if priced else zero) for i in range(n)
        ]
        if trace is not None:
            trace.extend(state, a, out.last_means, out.last_covs)
        team = state.team
        nodes = tuple(state.where(i)[0] for i in range(n))
        headings = tuple(state.where(i)[1] for i in range(n))
        moved = Team(team.names, nodes, headings, out.last_means[h].copy(), out.last_covs[h].copy(), until * self.dt)
        csig, bound = tuple(running[i][h] for i in range(n)), tuple(float(risk[i][h]) for i in range(n))
        return replace(state, t=until, team=moved, csig=csig, risk=bound), out.last_means, running, risk

    def _window(self, state: ClockState, i: int, a: int, b: int, priced: bool) -> tuple[np.ndarray, ...]:
        """Robot i's controls (h, 2), nominal poses (h+1, 3), landmark visibility (h+1, L),
        landmark draws (h+1, L, 2), the sector reach of its footprint (h+1, K; infinite unless
        ``priced``: the collision bound is wanted), whether it drove into each row (h+1; row 0:
        from the step before the window), its
        scans' keys (h+1,; -1: none) and their draws (h+1, 3) over the steps a..b."""
        L = self.ekf.landmarks.shape[0]
        controls, poses = np.zeros((b - a, 2)), np.empty((b - a + 1, 3))
        reach, drove = np.full((b - a + 1, SECTORS if priced else 1), np.inf), np.zeros(b - a + 1, dtype=bool)
        vis, noise = np.empty((b - a + 1, L), dtype=bool), np.empty((b - a + 1, L, 2))
        scans, scan_noise = self.lib.scans, np.zeros((b - a + 1, 3))
        keys = np.full(b - a + 1, -1, dtype=np.int64)
        noisy = scans is not None and not self.ekf.max_likelihood
        legs = state.legs[i]
        for n, leg in enumerate(legs):
            end = legs[n + 1].start if n + 1 < len(legs) else b + 1
            lo, hi = max(leg.start, a), min(end, b + 1)
            if lo >= hi:
                continue
            k = np.arange(lo, hi) - leg.start  # steps since the leg began
            rows = slice(lo - a, hi - a)
            if leg.motion is None:
                poses[rows] = leg.pose
                vis[rows] = self.lib.visibility.visible(
                    leg.pose[None], self.scenario.models.landmark_sensor.fov, min_range=self.radii[i]
                )[0]
                if scans is not None:
                    keys[rows] = scans.keys(leg.pose)
            else:
                m = leg.motion
                last = np.minimum(k, m.n_steps)
                poses[rows], vis[rows] = m.poses[last], m.lm_visible[last]
                if m.scan_keys is not None:
                    keys[rows] = m.scan_keys[last]
                if priced:
                    reach[rows] = self.lib.reach(m, last)
                s = np.arange(lo, min(hi, b))  # the window's transitions s -> s + 1 in this leg
                drive = s - leg.start < m.n_steps
                controls[s[drive] - a] = m.controls[s[drive] - leg.start]
                drove[s[drive] - a + 1] = True
                if leg.start < a <= leg.start + m.n_steps:  # it drove into row 0 too: its move goes on
                    drove[0] = True
            noise[rows] = self.lib.noise.rows(leg.noise_seed, int(k[-1]) + 1, (L, 2))[k]
            if noisy:
                scan_noise[rows] = self.lib.noise.rows(scan_seed(leg.noise_seed), int(k[-1]) + 1, (3,))[k]
        return controls, poses, vis, noise, reach, drove, keys, scan_noise

    def _visible(self, poses: Sequence[np.ndarray], h: int) -> np.ndarray:
        """(h+1, n, n): whether robot i sees robot j at each step, its nominal poses ``poses[i]``
        (h+1, 3); the pairs of one sensing in one compiled call."""
        n = len(self.names)
        visible = np.zeros((h + 1, n, n), dtype=bool)
        by_sensing: dict[MutualSensing, list[tuple[int, int]]] = {}
        for pair, sensing in self.sensing.items():
            by_sensing.setdefault(sensing, []).append(pair)
        for sensing, pairs in by_sensing.items():
            observer = np.concatenate([poses[i] for i, _ in pairs])
            target = np.concatenate([poses[j] for _, j in pairs])
            seen = sensing.visible(self.lib.world, observer, target).reshape(len(pairs), h + 1)
            for (i, j), row in zip(pairs, seen, strict=True):
                visible[:, i, j] = row
        return visible

    def _mutual_noise(self, state: ClockState, a: int, b: int, visible: np.ndarray) -> np.ndarray:
        """(h+1, n, n, 2) draws of every ordered pair's observations over the steps a..b; zero
        for a pair that never sees the other then (``visible``: the kernel draws only where it does)."""
        n, h = len(self.names), b - a
        out = np.zeros((h + 1, n, n, 2))
        first = a // MUTUAL_BLOCK
        for i, j in self.sensing:
            if not visible[:, i, j].any():
                continue
            blocks = [self._pair_block(i, j, k) for k in range(first, b // MUTUAL_BLOCK + 1)]
            out[:, i, j] = np.concatenate(blocks)[a - first * MUTUAL_BLOCK : b - first * MUTUAL_BLOCK + 1]
        for p in state.pairings:
            lo, hi = max(p.start, a), min(p.start + p.steps, b)
            if lo > hi:
                continue
            draws = self.lib.noise.rows(p.seed, p.steps + 1, (2, 2, 2))
            (x, y), rows, k = p.robots, slice(lo - a, hi - a + 1), slice(lo - p.start, hi - p.start + 1)
            out[rows, x, y], out[rows, y, x] = draws[k, 0, 1], draws[k, 1, 0]
        return out

    def _pair_block(self, i: int, j: int, block: int) -> np.ndarray:
        """Block ``block`` of the draws of robot i observing robot j outside paired moves."""
        names = self.names
        seed = stable_seed(self.scenario.models.seed, "mutual", names[i], names[j], "clock", block)
        return self.lib.noise.rows(seed, MUTUAL_BLOCK, (2,))[:MUTUAL_BLOCK]

    # ------------------------------------------------------------------ the result
