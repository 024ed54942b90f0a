"""The collision bound: against Monte Carlo on the test paths, its cost in the kernel, and the
chance constraint on the shipped configurations (docs/models.md, "Collision bound";
docs/planning.md, "Chance constraint").

    .venv/bin/python benchmarks/bench_risk.py paths [--samples N] > benchmarks/risk/paths.txt
    .venv/bin/python benchmarks/bench_risk.py kernel [--repeat N]
    .venv/bin/python benchmarks/bench_risk.py plans [--max-risk 0.05] [CONFIG ...]

``paths``: the test paths of tests/belief/risk_paths.py at several noise levels; per case the
bound (first passage, sub-cell reach), the bound before them (the union of the per-step bounds
over the steps, Boole's inequality, with whole cells' reach; for the passing robots' contact,
the union of the per-instant rule pair_risk.pair_bound), the sampled rate of trajectories that hit
a wall (touch) with its 95% Clopper-Pearson interval, and the two over the rate. ``kernel``: microseconds
per control step of the compiled EKF along the door path (one robot) and the passing (two
robots) with and without the bound, 500 simulations from scratch per call, the best of
``--repeat`` calls. ``plans``: per configuration the run's time, the quantiles of its moves'
bounds, the largest move and the plan's bound, each robot's largest position std, the cost and
the makespan; with ``--max-risk``, the plan within it or the least threshold tmpnav names
(exit code 9's message).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the test paths live with the tests

from tests.belief import risk_paths  # noqa: E402
from tmpnav.belief.intervals import clopper_pearson  # noqa: E402
from tmpnav.belief.sequences import propagate_sequences  # noqa: E402
from tmpnav.errors import RiskError  # noqa: E402
from tmpnav.pipeline import PlanOptions, plan  # noqa: E402

CONFIGS = ("corridor", "two-rooms", "office-rooms", "warehouse-2robots", "sparse-warehouse", "building-4robots")
KERNEL_COPIES = 500
#: (path, noise) measured by ``paths``: the cases of tests/belief/test_monte_carlo.py
PATHS = (
    ("straight", 0.25),
    ("straight", 0.5),
    ("straight", 1.0),
    ("corner", 0.25),
    ("corner", 0.5),
    ("corner", 1.0),
    ("door", 0.5),
    ("door", 1.0),
    ("door", 2.0),
    ("passing", 1.0),
    ("passing", 2.0),
    ("open-straight", 0.035),
    ("open-straight", 0.06),
    ("open-straight", 0.09),
    ("open-corner", 0.05),
    ("open-corner", 0.1),
    ("open-inner", 0.045),
    ("open-inner", 0.07),
)


def paths(samples: int) -> None:
    """The bound (first passage) and the union of the per-step bounds against sampled rates."""
    head = ("path", "noise", "trajectories", "what", "bound", "before", "sampled rate (95% CI)")
    print("| " + " | ".join(head) + " | bound / rate | before / rate |")
    print("|---" * (len(head) + 2) + "|")
    for name, noise in PATHS:
        d = risk_paths.drive(risk_paths.path(name, offset=0.56), noise)
        n = 5 * samples if name == "passing" else samples
        for how in ("walk", "unicycle") if name.startswith("open-") else ("walk",):
            for m in risk_paths.measure(d, n, how):
                lo, hi = clopper_pearson(m.hits, m.n)
                ratio = f"{m.bound / m.rate:.2f}" if m.hits else "-"
                before = f"{m.before / m.rate:.1f}" if m.hits else "-"
                print(
                    f"| {name} | {noise:g} | {how} {m.n:,} | {m.what} | {m.bound:.4g} | {m.before:.4g} | "
                    f"{m.rate:.4g} ({lo:.4g}-{hi:.4g}) | {ratio} | {before} |"
                )


def kernel(repeat: int) -> None:
    """Microseconds per control step (one simulation's step of all its robots)."""
    for name in ("door", "passing"):
        d = risk_paths.drive(risk_paths.path(name), 1.0)
        steps = KERNEL_COPIES * (d.covs.shape[0] - 1)
        timed = {}
        for bound in (False, True):
            batch = risk_paths.kernel_batch(d, 1.0, KERNEL_COPIES, bound)
            propagate_sequences(batch)  # compiled, or loaded from numba's cache
            best = float("inf")
            for _ in range(repeat):
                start = time.perf_counter()
                propagate_sequences(batch)
                best = min(best, time.perf_counter() - start)
            timed[bound] = 1e6 * best / steps
        print(
            f"{name} ({d.poses.shape[0]} robot(s), {d.covs.shape[0] - 1} steps, {d.landmarks.shape[0]} landmarks): "
            f"{timed[False]:.2f} us per step without the bound, {timed[True]:.2f} us with it"
        )


def plans(configs: list[str], max_risk: float | None) -> None:
    """The shipped configurations' plans and their bounds."""
    root = ROOT / "configs"
    with tempfile.TemporaryDirectory() as cache:
        for name in configs:
            start = time.perf_counter()
            try:
                r = plan(root / f"{name}.yaml", PlanOptions.of(cache_dir=Path(cache), max_risk=max_risk))
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="what", required=True)
    m = sub.add_parser("paths")
    m.add_argument("--samples", type=int, default=20_000, help="trajectories a case (5 times as many passing)")
    k = sub.add_parser("kernel")
    k.add_argument("--repeat", type=int, default=5)
    p = sub.add_parser("plans")
    p.add_argument("configs", nargs="*", default=CONFIGS)
    p.add_argument("--max-risk", type=float, default=None)
    args = parser.parse_args()
    if args.what == "paths":
        paths(args.samples)
    elif args.what == "kernel":
        kernel(args.repeat)
    else:
        plans(list(args.configs), args.max_risk)


if __name__ == "__main__":
    main()
