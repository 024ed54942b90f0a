"""Do the plan's beliefs agree with the localiser that executes it? Per robot and move, per driving step.

At every control step a robot drives, the simulator records its localiser's actual position
error e (true minus estimated position), the localiser's own position covariance L and the
plan's predicted position covariance P at the same step of the move (its control steps
counted from the move's start, the last one held when the execution runs longer). From
these, per robot and move and for the whole plan (docs/amcl.md, "Consistency"):

* the RMS error per axis sqrt(mean |e|² / 2) and the localiser's reported std per axis
  sqrt(tr L / 2) (median over the steps);
* the plan's predicted std per axis sqrt(tr P / 2) (median);
* the NEES eᵀ P⁻¹ e of the actual error against the plan (median; 2 on average and 1.39 in
  the median for a consistent 2-D Gaussian);
* the share of steps beyond 3 predicted sigma: eᵀ P⁻¹ e > 9 (1.1% for a consistent filter).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: the NEES of a consistent 2-D Gaussian error: its median (chi-square of 2 degrees of freedom, 2 ln 2)
#: and the share of steps beyond 3 sigma (exp(-9/2))
CONSISTENT_MEDIAN = 2.0 * math.log(2.0)
CONSISTENT_BEYOND = math.exp(-(3.0**2) / 2.0)
#: a row per driving step: e_x, e_y (m), L_xx, L_xy, L_yy, P_xx, P_xy, P_yy (m²)
COLUMNS = 8
#: the Mahalanobis distance beyond which a step counts as outside the plan's belief
SIGMAS = 3.0


@dataclass
class ConsistencyTrace:
    """One session's driving steps, by (robot, plan step of the move)."""

    rows: dict[tuple[str, int], list[tuple[float, ...]]] = field(default_factory=dict)

    def record(self, robot: str, step: int, error: np.ndarray, own: np.ndarray, planned: np.ndarray | None) -> None:
        """A driving step: the position ``error`` (2,), the localiser's covariance ``own`` (2, 2) and the
        plan's ``planned`` (2, 2) (None: the plan has none here, the step is not recorded)."""
        if planned is None:
            return
        self.rows.setdefault((robot, step), []).append(
            (
                float(error[0]),
                float(error[1]),
                float(own[0, 0]),
                float(own[0, 1]),
                float(own[1, 1]),
                float(planned[0, 0]),
                float(planned[0, 1]),
                float(planned[1, 1]),
            )
        )


@dataclass(frozen=True)
class Nees:
    """The position NEES eᵀ Σ⁻¹ e of a set of steps, summed up robustly: its median (1.39 for
    a consistent filter, :data:`CONSISTENT_MEDIAN`) and the share of steps beyond 3 sigma (1.1%,
    :data:`CONSISTENT_BEYOND`). Not the mean (2 for a consistent filter): a filter that has
    lost track (a landmark-only robot metres off with a covariance of decimetres) gives a few
    steps of NEES 10⁴-10⁶ that outweigh every other step of the run (docs/models.md, "NEES")."""

    steps: int  # steps with a NEES (a step whose covariance is singular counts, as beyond 3 sigma)
    median: float  # nan for no step
    beyond: float  # share of the steps beyond 3 sigma; nan for no step

    @staticmethod
    def of(values: np.ndarray) -> Nees:
        """The summary of NEES ``values`` (any shape; nan: no covariance there, left out; inf:
        a singular covariance)."""
        v = np.asarray(values, dtype=float).ravel()
        v = v[~np.isnan(v)]
        if not v.size:
            return Nees(0, math.nan, math.nan)
        return Nees(int(v.size), float(np.median(v)), float(np.mean(v > SIGMAS**2)))


def planned_nees(rows: np.ndarray) -> np.ndarray:
    """(N,) each driving step's NEES eᵀ P⁻¹ e of the actual error against the plan's covariance
    (inf where P is singular); rows (N, COLUMNS)."""
    e, a, b, c = rows[:, :2], rows[:, 5], rows[:, 6], rows[:, 7]
    det = a * c - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(det > 0, (c * e[:, 0] ** 2 - 2 * b * e[:, 0] * e[:, 1] + a * e[:, 1] ** 2) / det, np.inf)


@dataclass(frozen=True)
class Agreement:
    """The figures of the module docstring over a set of driving steps."""

    steps: int
    rms_error: float  # m per axis
    own_std: float  # m per axis, median
    planned_std: float  # m per axis, median
    nees: float  # median
    beyond: float  # share of steps beyond 3 predicted sigma

    @staticmethod
    def of(rows: np.ndarray) -> Agreement:
        """The figures of ``rows`` (N, COLUMNS); nan for none."""
        if rows.size == 0:
            return Agreement(0, math.nan, math.nan, math.nan, math.nan, math.nan)
        e, a, c = rows[:, :2], rows[:, 5], rows[:, 7]
        nees = planned_nees(rows)
        return Agreement(
            steps=int(rows.shape[0]),
            rms_error=float(np.sqrt(np.mean(np.sum(e * e, axis=1)) / 2.0)),
            own_std=float(np.median(np.sqrt(np.maximum(rows[:, 2] + rows[:, 4], 0.0) / 2.0))),
            planned_std=float(np.median(np.sqrt(np.maximum(a + c, 0.0) / 2.0))),
            nees=float(np.median(nees)),
            beyond=float(np.mean(nees > SIGMAS**2)),
        )

    @property
    def inflation(self) -> float:
        """The plan's predicted std over the actual RMS error (1: as large as it should be)."""
        return self.planned_std / self.rms_error if self.rms_error > 0 else math.nan


def gather(traces: list[ConsistencyTrace]) -> dict[tuple[str, int], np.ndarray]:
    """(robot, plan step) -> every session's driving-step rows (N, COLUMNS), in plan order."""
    out: dict[tuple[str, int], list[tuple[float, ...]]] = {}
    for t in traces:
        for key, rows in t.rows.items():
            out.setdefault(key, []).extend(rows)
    return {k: np.array(out[k], dtype=float).reshape(-1, COLUMNS) for k in sorted(out, key=lambda k: (k[1], k[0]))}


def overall(rows: dict[tuple[str, int], np.ndarray], robot: str | None = None) -> Agreement:
    """The figures over every move (of ``robot``, or of the whole team for None)."""
    picked = [r for (name, _), r in rows.items() if robot is None or name == robot]
    return Agreement.of(np.concatenate(picked) if picked else np.zeros((0, COLUMNS)))


def csv_text(rows: dict[tuple[str, int], np.ndarray]) -> str:
    """consistency.csv: one line per robot and move, with its figures."""
    lines = ["robot,step,driving_steps,rms_error_m,localiser_std_m,planned_std_m,median_nees,beyond_3_sigma"]
    for (robot, step), r in rows.items():
        a = Agreement.of(r)
        lines.append(
            f"{robot},{step + 1},{a.steps},{a.rms_error:.4f},{a.own_std:.4f},{a.planned_std:.4f},"
            f"{a.nees:.2f},{a.beyond:.4f}"
        )
    return "\n".join(lines) + "\n"


def summary_lines(rows: dict[tuple[str, int], np.ndarray], localiser: str) -> list[str]:
    """The terminal's lines: who localised, then per robot and for the team the figures of the
    module docstring (per move in consistency.csv)."""
    from tmpnav.numbers import length, nees, percent

    if not rows:
        return [localiser, "consistency with the plan: no driving step with a planned covariance"]
    out = [
        localiser,
        "the plan's beliefs against the executing localiser, over the driving steps (consistency.csv per move):",
        f"{'robot':6} {'steps':>6} {'rms error':>10} {'localiser std':>14} {'planned std':>12} "
        f"{'median NEES':>12} {'beyond 3 sigma':>15}",
    ]
    robots = list(dict.fromkeys(name for name, _ in rows))
    for name in [*robots, None]:
        a = overall(rows, name)
        out.append(
            f"{name or 'team':6} {a.steps:>6} {length(a.rms_error):>10} {length(a.own_std):>14} "
            f"{length(a.planned_std):>12} {nees(a.nees):>12} {percent(a.beyond):>15}"
        )
    out.append(
        "(per axis: rms error sqrt(mean |e|²/2), stds sqrt(tr/2); NEES of the actual error against the plan's "
        "covariance: 1.4 in the median and 1.1% beyond 3 sigma for a consistent belief)"
    )
    return out
