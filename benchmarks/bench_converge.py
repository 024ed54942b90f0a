"""Does the anytime search stop when it is done, and how far can its plan be from the best?

    .venv/bin/python benchmarks/bench_converge.py [--case corridor-10] [--repeat N] [--verbose]

Plans each case cold (no cache; the roadmap grown, every cost simulated, ENHSP run) with the
default choices (carried costs, auto search: the anytime search at these sizes, weighted
objective), after the bench worker's warm-up (tmpnav/bench/worker.py: a tiny scenario
planned twice), so that imports, compiled kernels, the first JVM start and ENHSP's first
searches are not counted. Prints
one line per run: rooms, robots, seconds, how the search stopped, the plan's objective, the
certified lower bound, the gap and the sub-problems ENHSP solved; ``--verbose`` adds the
search's progress lines. Timings on a 2-core machine shared with other jobs are noisy.
"""

from __future__ import annotations

import argparse
import itertools
import random
import sys
import time
from dataclasses import dataclass, replace

from tmpnav import shipped
from tmpnav.bench.worker import warm_up
from tmpnav.pipeline import PlanOptions, Reporters, plan
from tmpnav.report.schedule import objective_values
from tmpnav.results import PlanReport
from tmpnav.scenario import load
from tmpnav.types import Goals


@dataclass(frozen=True)
class Case:
    name: str
    scenario: str  # a shipped scenario
    rooms: int | None  # rooms drawn (None: the scenario's goals)
    seed: int = 0


CASES = {
    "corridor-10": Case("corridor-10", "corridor-2robots.yaml", 10),
    "building-20": Case("building-20", "building-20.yaml", None),
    "building-40": Case("building-40", "building-4robots.yaml", 40),
}


def _goals(case: Case) -> Goals | None:
    """The case's rooms: every room of the scenario, or ``rooms`` of them drawn with the seed
    (sorted, as the bench draws them)."""
    if case.rooms is None:
        return None
    names = [room.name for room in load(shipped.configs_dir() / case.scenario).rooms]
    if case.rooms >= len(names):
        return Goals(visit=tuple(names), per_robot=())
    drawn = random.Random(case.seed).sample(names, case.rooms)
    return Goals(visit=tuple(sorted(drawn, key=names.index)), per_robot=())


def trace_batches() -> None:
    """Print every batch of sub-problems the search tries: its size, seconds, and whether it improved."""
    from tmpnav.task import search

    try_batch = search.AnytimeSearch._settle

    def traced(self: search.AnytimeSearch, plan: object, batch: object, keep_equal: bool = False) -> bool:
        t0, before = time.perf_counter(), dict(self.times.seconds)
        out = try_batch(self, plan, batch, keep_equal)  # type: ignore[arg-type]
        spent = {k: v - before.get(k, 0.0) for k, v in self.times.seconds.items() if v - before.get(k, 0.0) > 0.01}
        parts = ", ".join(f"{k} {v:.2f}" for k, v in spent.items())
        sizes = ", ".join(f"{len(s.hood.robots)}r/{len(s.hood.rooms)}x" for s in batch.subs)
        label = self.model.costs
        counts = f"{self.stats.subproblems} solved, {self.stats.reused} reused"
        print(
            f"    batch [{label}] {sizes}: {time.perf_counter() - t0:.2f} s ({parts}), improved {out}; {counts}",
            file=sys.stderr,
        )
        return out

    search.AnytimeSearch._settle = traced  # type: ignore[method-assign]


def run_case(case: Case, verbose: bool, budget: float | None = None) -> str:
    def progress(t: float, best: float, bound: float | None, what: str) -> None:
        if verbose:
            print(f"    {t:7.2f} s  best {best:10.3f}  {what}", file=sys.stderr)

    # PlanOptions.of's "search_progress" lands on the search override of the same name: set it here
    base = PlanOptions.of(use_cache=False, goals=_goals(case), time_budget=budget)
    options = replace(base, reporters=Reporters(search=progress))
    start = time.perf_counter()
    report = plan(shipped.configs_dir() / case.scenario, options)
    seconds = time.perf_counter() - start
    search, bound = report.task.search, report.task.bound
    rooms = len(report.scenario.goals.all_rooms) if case.rooms is None else case.rooms
    stopped = search.stopped if search is not None else "-"
    subproblems = search.subproblems if search is not None else 0
    value = f"{bound.value:.2f}" if bound is not None else "-"
    gap = f"{100 * bound.gap:.1f}%" if bound is not None else "-"
    cost = objective_values(report).planner_value or 0.0
    parts = _parts(report)
    return (
        f"{case.name:12s} {rooms:5d} {len(report.scenario.robots):6d} {seconds:8.2f} {stopped:>12s} "
        f"{cost:10.2f} {value:>10s} {gap:>7s} {subproblems:5d}   {parts}"
    )


def _parts(report: PlanReport) -> str:
    """The objective's parts as re-simulated: M_Sigma c_Sigma (trace(Sigma) dt over the steps
    where a robot's mean moved: an estimate that counts turning steps too), the rest of the
    summed cost (M_u c_u + M_G c_G), and M_T times the makespan."""
    values, w = objective_values(report), report.scenario.cost
    dt = report.scenario.models.dt
    sigma = 0.0
    for steps in report.trajectories.values():
        for a, b in itertools.pairwise(steps):
            if a.mean != b.mean:
                sigma += sum(b.cov[k][k] for k in range(3)) * dt
    rest = report.resimulated_cost - w.M_Sigma * sigma
    span = values.value - report.resimulated_cost
    return f"sigma {w.M_Sigma * sigma:.1f}, driving+goal {rest:.1f}, time {span:.1f}"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", action="append", choices=sorted(CASES), help="default: every case")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--verbose", action="store_true")
    parser.add_argument("--budget", type=float, help="the anytime search's budget (default: the scenario's)")
    args = parser.parse_args(argv)
    if args.verbose:
        trace_batches()
    warm_up()
    print(
        f"{'case':12s} {'rooms':>5s} {'robots':>6s} {'time [s]':>8s} {'stopped':>12s} "
        f"{'objective':>10s} {'bound':>10s} {'gap':>7s} {'subs':>5s}"
    )
    for name in args.case or list(CASES):
        for _ in range(args.repeat):
            print(run_case(CASES[name], args.verbose, args.budget), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
