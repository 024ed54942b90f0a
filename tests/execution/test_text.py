"""What ``tmpnav simulate`` prints, on results built by hand: a NEES that reads as the filter is,
and no filler line (issue 57: "4037.94 against the filter's own", "r3 nan", "0.0% lower")."""

from __future__ import annotations

import re

import numpy as np

from tmpnav.execution import ExecutionResult, error_summary
from tmpnav.execution.consistency import Nees
from tmpnav.results import Schedule, TimedMove

SESSIONS = 3


def _result(errors: dict[tuple[int, str], float], own_nees: np.ndarray, moving: tuple[str, ...]) -> ExecutionResult:
    """Robots r1-r3, of which ``moving`` make one move each; ``errors`` (config, robot) -> the
    error at every point; every robot's filter NEES at every step ``own_nees``."""
    robots = ["r1", "r2", "r3"]
    moves = tuple(
        TimedMove(k, r, "A", "B", None, 0.0, 0.0, 10.0) for k, r in enumerate(robots) if r in moving
    )  # fmt: skip
    schedule = Schedule(tuple(robots), moves)
    configs = (1, 2)
    points = {r: 3 if r in moving else 1 for r in robots}
    rng = np.random.default_rng(0)
    drawn = {
        r: rng.chisquare(2, (SESSIONS, points[r])) if r in moving else np.full((SESSIONS, 1), np.nan) for r in robots
    }
    planned_nees = {(c, r): drawn[r] for c in configs for r in robots}  # the configurations agree
    zero = np.zeros(SESSIONS, dtype=int)
    return ExecutionResult(
        robots=robots,
        nodes={r: list(range(points[r])) for r in robots},
        errors={(c, r): np.full((SESSIONS, points[r]), errors[(c, r)]) for c in configs for r in robots},
        truncated_sessions=0,
        times={(c, r): np.zeros((SESSIONS, points[r])) for c in configs for r in robots},
        planned_times={r: [0.0] * points[r] for r in robots},
        schedules={c: [schedule] * SESSIONS for c in configs},
        planned=schedule,
        wall_hits={(c, r): zero for c in configs for r in robots},
        contacts={(c, r): zero for c in configs for r in robots},
        planned_nees=planned_nees,
        filter_nees={(c, r): own_nees for c in configs for r in robots},
        beams={(c, r): (0, 0) for c in configs for r in robots},
        move_hits={},
        move_contacts={},
        bounds={},
    )


def _consistent_but_one_lost_step() -> np.ndarray:
    """A consistent filter's NEES over 2,000 steps (chi-square, 2 degrees of freedom), but one step
    where it had lost track: an error of metres against a covariance of centimetres."""
    values = np.random.default_rng(1).chisquare(2, 2000)
    values[700] = 8.0e6
    return values


def test_the_nees_reads_as_the_filter_is_not_as_its_worst_step() -> None:
    """The mean of these steps is about 4,000 (one step outweighs the 1,999 others): the summary
    reports the median and the share beyond 3 sigma, which read as the consistent filter it is."""
    lost = _consistent_but_one_lost_step()
    assert lost.mean() > 4000
    n = Nees.of(lost)
    assert abs(n.median - 1.386) < 0.15 and n.beyond < 0.02 and n.steps == 2000
    same = {(c, r): 0.1 for c in (1, 2) for r in ("r1", "r2", "r3")}
    text = "\n".join(error_summary(_result(same, lost, ("r1", "r2", "r3")), SESSIONS))
    line = next(x for x in text.splitlines() if x.startswith("position NEES"))
    assert "median and share beyond 3 sigma (1.4 and 1.1% when the errors agree" in line
    own = re.search(r"against the filter's own at every step ([\d.]+), ([\d.]+)%", line)
    assert own is not None and float(own[1]) < 2.0 and float(own[2]) < 2.0, line
    assert "4000" not in text and "4001" not in text


def test_a_robot_without_moves_and_equal_configurations_print_no_filler() -> None:
    """r3 makes no move: no error, no NEES of its own to report (it printed "r3 nan"); the
    configurations agree for every robot (a lidar pins them): no "0% lower" line per robot."""
    same = {(1, "r1"): 0.058, (2, "r1"): 0.058, (1, "r2"): 0.086, (2, "r2"): 0.086, (1, "r3"): 0.1, (2, "r3"): 0.1}
    text = "\n".join(error_summary(_result(same, np.random.default_rng(2).chisquare(2, 500), ("r1", "r2")), SESSIONS))
    assert "nan" not in text and "n/a" not in text, text
    assert not re.search(r"\b0(\.0)?% (lower|higher)", text), text
    assert "worst-case position error (largest average error over the path's nodes), the same with and without" in text
    assert "r1 5.8 cm, r2 8.6 cm, r3 no moves" in text
    assert "landmark-starved" not in text  # no robot gains from mutual observations
    assert "r3 none (no moves)" in text  # the NEES line says why r3 has none
    assert "position NEES with and without mutual observations alike" in text


def test_configurations_that_differ_are_compared_robot_by_robot() -> None:
    errors = {(1, "r1"): 0.21, (2, "r1"): 0.41, (1, "r2"): 0.15, (2, "r2"): 0.15, (1, "r3"): 0.1, (2, "r3"): 0.1}
    lines = error_summary(_result(errors, np.random.default_rng(3).chisquare(2, 500), ("r1", "r2")), SESSIONS)
    assert "  r1: with mutual observations 0.21 m, without 0.41 m, 48.8% lower" in lines
    assert "  r2: 0.15 m with and without mutual observations" in lines
    assert "  r3 no moves" in lines
    assert "landmark-starved robot (largest error without mutual observations): r1, 48.8% lower with mutual" in (
        "\n".join(lines)
    )
