"""The chance constraint on the shipped configurations: each plan's collision bounds, without a
threshold and with one (docs/planning.md, "Chance constraint").

    .venv/bin/python benchmarks/bench_risk.py [--max-risk 0.05] [CONFIG ...]

Prints per configuration: the run's time, the quantiles of its moves' bounds, the largest move
and the plan's bound, each robot's largest position std, the cost and the makespan; with
``--max-risk``, the plan within it or the least threshold tmpnav names (exit code 9's message).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from tmpnav.errors import RiskError
from tmpnav.pipeline import PlanOptions, plan

CONFIGS = ("corridor", "two-rooms", "office-rooms", "warehouse-2robots", "sparse-warehouse", "building-4robots")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("configs", nargs="*", default=CONFIGS)
    parser.add_argument("--max-risk", type=float, default=None)
    args = parser.parse_args()
    root = Path(__file__).resolve().parent.parent / "configs"
    with tempfile.TemporaryDirectory() as cache:
        for name in args.configs:
            start = time.perf_counter()
            try:
                r = plan(root / f"{name}.yaml", PlanOptions.of(cache_dir=Path(cache), max_risk=args.max_risk))
            except RiskError as err:
                print(f"{name}: {time.perf_counter() - start:.1f} s, {err} (least {err.least:g})")
                continue
            risks = [p for a in r.actions for p in a.risk]
            q = np.quantile(risks, [0, 0.25, 0.5, 0.75, 1]) if risks else []
            std = ", ".join(f"{k} {v:.2f} m" for k, v in r.largest_std().items())
            print(
                f"{name}: {time.perf_counter() - start:.1f} s, {len(risks)} moves, bounds (min, quartiles, max) "
                f"{np.round(q, 3).tolist()}, plan {r.risk:.2g}; largest std {std}; "
                f"cost {r.resimulated_cost:.1f}, makespan {r.schedule.makespan:.1f} s"
            )


if __name__ == "__main__":
    main()
