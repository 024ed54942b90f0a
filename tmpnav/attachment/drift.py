"""How far off the plan's clock two robots may run: the time window of the conflict rule.

An executed robot never starts a move before its planned start (tmpnav.execution.schedule), so
it is never early where a move begins; while it drives it falls behind by up to ``drift``
seconds per second driven (local steering, recoveries), and a planned wait before a move
absorbs that much of its lateness. :func:`lateness` bounds each robot's lateness at every
instant so; two robots' clocks then differ by at most the larger of their two bounds, and
by at most ``drift`` times the time since the start of a paired move while they make it
(they start it together). :func:`pair_windows` gives those windows for the independent
checker (:func:`tmpnav.belief.conflicts.find_conflicts`) and the detours' search.

The rate is the scenario's ``planner.clock_drift``; by default DEFAULT_CLOCK_DRIFT for robots
localised by AMCL and 0 otherwise (the paper's model: the plan's own clock). docs/models.md,
"Two robots off the plan's clock", gives the measurements behind it.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence

import numpy as np

from tmpnav.results import Schedule, TimedMove
from tmpnav.types import ScanModelKind, Scenario, TrajectoryStep

#: seconds a robot localised by AMCL may fall behind its planned clock per second it drives
#: (``tmpnav simulate --localiser amcl`` on building-4robots: docs/models.md)
DEFAULT_CLOCK_DRIFT = 0.1


def clock_drift(scenario: Scenario) -> float:
    """The scenario's drift rate: its ``planner.clock_drift``, else DEFAULT_CLOCK_DRIFT where its
    robots' localiser is AMCL (``models.range_sensor.localiser.model: amcl``), else 0."""
    if scenario.planner.clock_drift is not None:
        return scenario.planner.clock_drift
    sensor = scenario.models.range_sensor
    return DEFAULT_CLOCK_DRIFT if sensor is not None and sensor.localiser.kind is ScanModelKind.AMCL else 0.0


def lateness(schedule: Schedule, drift: float, times: np.ndarray) -> dict[str, np.ndarray]:
    """Each robot's bound on how late it runs (s) at each of ``times`` (s of the plan's clock):
    0 until its first move; a move starts late by what its robots' lateness leaves after
    the planned wait before it (a paired move by the later of its two robots), then grows by
    ``drift`` per second driven; a job's window absorbs lateness as a wait does."""
    late = {r: np.zeros(len(times)) for r in schedule.robots}
    carried = dict.fromkeys(schedule.robots, 0.0)  # lateness when the robot is free again
    free = dict.fromkeys(schedule.robots, 0.0)  # when it is free again, planned
    for _, group in itertools.groupby(schedule.moves, key=lambda m: m.step):
        moves = list(group)
        behind = max(0.0, *(free[m.robot] + carried[m.robot] - m.start for m in moves))
        for m in moves:
            driving = (times >= m.start) & (times <= m.end)
            late[m.robot][times > free[m.robot]] = carried[m.robot]  # standing, then waiting
            late[m.robot][driving] = behind + drift * (times[driving] - m.start)
            arrived = behind + drift * (m.end - m.start)
            late[m.robot][times > m.end] = arrived
            carried[m.robot], free[m.robot] = max(0.0, arrived - m.opens), m.done
    return late


def pair_windows(schedule: Schedule, drift: float, times: np.ndarray) -> dict[tuple[str, str], np.ndarray]:
    """(a, b) with a < b -> (len(times),) s: how far apart the two robots' clocks may be at
    each instant (module docstring); empty for ``drift`` 0."""
    if drift <= 0.0:
        return {}
    late = lateness(schedule, drift, times)
    windows = {}
    for a, b in itertools.combinations(sorted(schedule.robots), 2):
        window = np.maximum(late[a], late[b])
        for start, end in _together(schedule.timeline(a), schedule.timeline(b)):
            span = (times >= start) & (times <= end)
            window[span] = np.minimum(window[span], drift * (times[span] - start))
        windows[(a, b)] = window
    return windows


def trajectory_windows(
    trajectories: Mapping[str, Sequence[TrajectoryStep]], schedule: Schedule, drift: float
) -> dict[tuple[str, str], np.ndarray]:
    """:func:`pair_windows` on the time grid of ``trajectories`` (the longest robot's)."""
    longest = max(trajectories.values(), key=len, default=[])
    return pair_windows(schedule, drift, np.array([s.t for s in longest], dtype=float))


def _together(mine: Sequence[TimedMove], theirs: Sequence[TimedMove]) -> list[tuple[float, float]]:
    """(start, last arrival) of each paired move the two robots make together."""
    ends = {m.step: m for m in theirs}
    return [(m.start, max(m.end, ends[m.step].end)) for m in mine if m.step in ends]
