"""bench.csv and what is computed from it: medians per point, and the summary table.

A row is one phase (cold, warm, replan) of one run; every cell is text, as in the CSV file,
so a table read back from bench.csv (``tmpnav bench --replot``) is the table that was written.
"""

from __future__ import annotations

import csv
import io
import statistics
from dataclasses import dataclass
from pathlib import Path

from tmpnav.errors import InputError
from tmpnav.results import STAGES

Row = dict[str, str]
#: the stages timed per run: every pipeline stage but ``load``, and their total
BENCH_STAGES = (*STAGES[1:], "total")
COLUMNS = (
    "experiment",
    "encoding",
    "robots",
    "rooms",
    "session",
    "goals",
    "phase",
    "status",
    *(f"{s}_s" for s in BENCH_STAGES),
    "planner_cost",
    "resimulated_cost",
    "actions",
    "pair_actions",
    "joint_simulations",
    "joint_factorized",
    "table_cache_hit",
    "plan_cache_hit",
    "peak_rss_mb",
    "bound",
    "stopped",
    "makespan",
)
#: columns that bench.csv files written before them lack (read back as empty)
LATER_COLUMNS = ("bound_s", "peak_rss_mb", "bound", "stopped", "makespan")
#: a run's phases, in the order they run. cold: empty cache; warm: everything cached;
#: replan: costs cached, the task planner runs again
PHASES = ("cold", "warm", "replan")


@dataclass(frozen=True)
class PointStats:
    """The runs of one encoding and phase at one point: medians over the solved ones."""

    runs: int
    solved: int
    timeouts: int
    medians: dict[str, float | None]  # stage (``total`` included) -> median seconds; None: none solved
    q1: float | None  # quartiles of the total
    q3: float | None
    makespan: float | None = None  # median s until the plan's last robot is done; None: not recorded

    @property
    def total(self) -> float | None:
        return self.medians["total"]


Medians = dict[tuple[str, str, int], PointStats]  # (encoding, phase, point) -> stats


def to_csv(table: list[Row]) -> str:
    """The rows as bench.csv text."""
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(table)
    return buffer.getvalue()


def read_csv(path: Path) -> list[Row]:
    """The rows of a bench.csv written by :func:`to_csv` (for ``tmpnav bench --replot``)."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            table = list(reader)
            header = reader.fieldnames or []
    except OSError as err:
        raise InputError(f"--replot: cannot read {path}: {err.strerror}") from None
    missing = [c for c in COLUMNS if c not in header and c not in LATER_COLUMNS]
    for row in table:
        for c in LATER_COLUMNS:
            row.setdefault(c, "")
    if missing or not table:
        what = f"misses the columns {', '.join(missing)}" if missing else "has no rows"
        raise InputError(f"--replot: {path} is not a tmpnav bench.csv: it {what}")
    return table


def medians(table: list[Row], axis: str) -> Medians:
    """(encoding, phase, point) -> median total and stages over the solved sessions."""
    out: Medians = {}
    keys = sorted({(r["encoding"], r["phase"], int(r[axis])) for r in table})
    for enc, phase, point in keys:
        runs = [r for r in table if r["encoding"] == enc and r["phase"] == phase and int(r[axis]) == point]
        ok = [r for r in runs if r["status"].startswith("solved")]
        stages: dict[str, float | None] = {}
        for s in BENCH_STAGES:
            vals = [float(r[f"{s}_s"]) for r in ok if r[f"{s}_s"] != ""]
            stages[s] = statistics.median(vals) if vals else None
        totals = sorted(float(r["total_s"]) for r in ok)
        spans = [float(r["makespan"]) for r in ok if r.get("makespan", "") != ""]
        out[(enc, phase, point)] = PointStats(
            runs=len(runs),
            solved=len(ok),
            timeouts=sum(r["status"] == "timeout" for r in runs),
            medians=stages,
            q1=totals[len(totals) // 4] if totals else None,
            q3=totals[(3 * len(totals)) // 4] if totals else None,
            makespan=statistics.median(spans) if spans else None,
        )
    return out


def summary_markdown(table: list[Row], axis: str, default: str = "mixed", timeout: float | None = None) -> str:
    """A Markdown table of medians per point: planning times, and the plans' makespan (the robots
    moving at once; "-" for runs recorded before bench.csv had it), with the speed-up of
    ``default`` over the others (a column only when there are others: no column is ever empty).

    Where another encoding never finished, its speed-up is a lower bound: the time limit
    over ``default``'s median."""
    med = medians(table, axis)
    encodings = sorted({k[0] for k in med})
    points = sorted({k[2] for k in med})
    label = "rooms" if axis == "rooms" else "robots"
    compare = len(encodings) > 1
    head = (
        f"| {label} | encoding | cache | solved | median total (s) | roadmap | oracle | encode | planner "
        "| makespan (s) |"
    )
    lines = [head + (f" speed-up of {default} |" if compare else ""), "|---" * (10 + compare) + "|"]
    for point in points:
        for enc in encodings:
            for phase in PHASES:
                e = med.get((enc, phase, point))
                if e is not None:
                    mine = med[(default, phase, point)].total if (default, phase, point) in med else None
                    lines.append(_summary_row(point, enc, phase, e, default, mine, timeout, compare))
    return "\n".join(lines) + "\n"


def _summary_row(
    point: int,
    enc: str,
    phase: str,
    e: PointStats,
    default: str,
    mine: float | None,
    timeout: float | None,
    compare: bool = True,
) -> str:
    not_run = e.solved == 0 and phase != "cold"  # a cold run past the limit skips the others
    # a stage without a median: no run finished (timeout), or the solved runs skipped it (-)
    missing = "timeout" if e.solved == 0 else "-"
    cells = [_s(e.medians.get(s), missing) for s in ("total", "roadmap", "oracle", "encode", "planner")]
    cells.append(_s(e.makespan, missing))
    ratio = "-"
    if not_run:
        ratio, cells = "not run: the cold runs timed out", ["-"] * len(cells)
    elif enc == default and e.total:
        ratio = "1.0x (reference)"
    elif enc != default and mine and e.total:
        ratio = f"{e.total / mine:.1f}x"
    elif enc != default and mine and e.solved == 0:
        ratio = f"> {timeout / mine:.0f}x (timeout)" if timeout else "> timeout"
    row = f"| {point} | {enc} | {phase} | {e.solved}/{e.runs} | " + " | ".join(cells) + " |"
    return row + (f" {ratio} |" if compare else "")


def _s(v: float | None, missing: str = "timeout") -> str:
    return missing if v is None else f"{v:.2f}"
