"""The same task planned with table costs and with carried beliefs: executed cost and uncertainty.

    python benchmarks/bench_carried.py -o benchmarks/full/carried [--scenario configs/sparse-warehouse.yaml]

For each scenario the task is planned three times, ``--costs table --search exact`` (the exact
plan of the canonical cost table, tmpnav's earlier default), ``--costs carried`` (the default)
and the default with ``--time-budget 60`` (the anytime search run to convergence), each from
an empty cache. Each plan is re-simulated with the beliefs carried step by step (its
executed cost) and executed ``--sessions`` times with simulated noise (``tmpnav simulate``:
the worst-case position error per robot). Writes carried.json, summary.md and carried.png:
each robot's position uncertainty sqrt(var x + var y) along the plans, and the planner's
against the executed cost of each.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tmpnav.execution import execute  # noqa: E402
from tmpnav.pipeline import PlanOptions, plan  # noqa: E402
from tmpnav.results import PlanReport  # noqa: E402

#: the exact plan of the table, the default, and the default with a budget long enough for the
#: anytime search to converge (the default budget is 10 s at these sizes)
MODES = {
    "table": {"costs": "table", "search": "exact"},
    "carried": {"costs": "carried"},
    "carried-60s": {"costs": "carried", "time_budget": 60.0},
}
STYLES = {"table": ":", "carried": "-", "carried-60s": "--"}


def run(scenario: str, sessions: int) -> dict:
    out: dict = {"scenario": scenario, "plans": {}}
    for name, choice in MODES.items():
        with tempfile.TemporaryDirectory() as cache:
            start = time.perf_counter()
            report = plan(ROOT / scenario, PlanOptions.of(cache_dir=Path(cache), **choice))
            seconds = time.perf_counter() - start
        result = execute(report, sessions, seed=0)
        out["plans"][name] = {
            "report": report,
            "seconds": seconds,
            "planner_cost": report.planner_cost,
            "resimulated_cost": report.resimulated_cost,
            "steps": [[list(m) for m in a.moves] for a in report.actions],
            "worst_error_m": {r: result.worst(1, r) for r in result.robots},
            "max_pos_std_m": {r: float(np.max(_pos_std(report, r))) for r in report.trajectories},
        }
    return out


def _pos_std(report: PlanReport, robot: str) -> np.ndarray:
    covs = np.array([s.cov for s in report.trajectories[robot]])
    return np.sqrt(np.clip(covs[:, 0, 0] + covs[:, 1, 1], 0, None))


def figure(runs: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(runs), 2, figsize=(12, 4.2 * len(runs)), squeeze=False)
    for row, r in zip(axes, runs, strict=True):
        ax = row[0]
        colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
        for name, style in STYLES.items():
            report = r["plans"][name]["report"]
            for k, robot in enumerate(report.trajectories):
                t = [s.t for s in report.trajectories[robot]]
                ax.plot(
                    t, _pos_std(report, robot), style, color=colours[k % len(colours)], label=f"{robot}, {_label(name)}"
                )
        ax.set_xlabel("time along the plan (s)")
        ax.set_ylabel("position std sqrt(var x + var y) (m)")
        ax.set_title(f"{r['scenario']}: uncertainty as executed")
        ax.legend(fontsize=8, ncol=2)
        ax = row[1]
        names = list(MODES)
        planner = [r["plans"][n]["planner_cost"] for n in names]
        executed = [r["plans"][n]["resimulated_cost"] for n in names]
        x = np.arange(len(names))
        ax.bar(x - 0.2, planner, 0.4, label="cost as the planner saw it")
        ax.bar(x + 0.2, executed, 0.4, label="cost as executed (re-simulated)")
        for i in range(len(names)):
            ax.text(x[i] - 0.2, planner[i], f"{planner[i]:.0f}", ha="center", va="bottom", fontsize=8)
            ax.text(x[i] + 0.2, executed[i], f"{executed[i]:.0f}", ha="center", va="bottom", fontsize=8)
        ax.set_xticks(x, [_label(n).replace(" --time", "\n--time") for n in names])
        ax.set_ylabel("plan cost")
        ax.set_title("planner's cost against executed cost")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def _label(name: str) -> str:
    choice = MODES[name]
    budget = f" --time-budget {choice['time_budget']:.0f}" if "time_budget" in choice else ""
    return f"--costs {choice['costs']}{budget}"


def summary(runs: list[dict], sessions: int) -> str:
    lines = [
        "| scenario | costs | planner cost | executed cost | executed vs planner | worst position error (m), "
        f"{sessions} sessions | largest position std (m) | planning time (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        for name, p in r["plans"].items():
            diff = 100 * (p["resimulated_cost"] - p["planner_cost"]) / p["planner_cost"]
            worst = ", ".join(f"{k} {v:.2f}" for k, v in p["worst_error_m"].items())
            std = ", ".join(f"{k} {v:.2f}" for k, v in p["max_pos_std_m"].items())
            lines.append(
                f"| {r['scenario']} | {_label(name)} | {p['planner_cost']:.1f} | {p['resimulated_cost']:.1f} | "
                f"{diff:+.1f}% | {worst} | {std} | {p['seconds']:.1f} |"
            )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--scenario", action="append", default=None)
    parser.add_argument("--sessions", type=int, default=25)
    args = parser.parse_args()
    scenarios = args.scenario or ["configs/sparse-warehouse.yaml", "configs/corridor-2robots.yaml"]
    runs = [run(s, args.sessions) for s in scenarios]
    args.output.mkdir(parents=True, exist_ok=True)
    figure(runs, args.output / "carried.png")
    text = summary(runs, args.sessions)
    (args.output / "summary.md").write_text(text)
    plain = [
        {**r, "plans": {n: {k: v for k, v in p.items() if k != "report"} for n, p in r["plans"].items()}} for r in runs
    ]
    (args.output / "carried.json").write_text(json.dumps(plain, indent=1) + "\n")
    print(text)


if __name__ == "__main__":
    main()
