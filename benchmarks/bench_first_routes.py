"""How many solutions OR-Tools' first routes need: the anytime search's first plan at several
solution limits, on the generated families (benchmarks/families.py).

    .venv/bin/python benchmarks/bench_first_routes.py [--sizes office:40:4:10,office:60:8:4] [--limits 500,500/100]

For each generated building (kind, rooms, robots, seed): its single-move table as the search
computes it (canonical beliefs), then OR-Tools' routes (guided local search, the search's
first solution strategy and objective) stopped after each number of solutions, and each
routes' plan costed with carried beliefs, as the search judges it before keeping robots apart.
A limit N/K stops after N solutions or K in a row that did not improve the objective. On every
generated office the anytime search finds no improvement over this first plan, so its cost is
the run's. Writes benchmarks/routing/first_routes.txt (one row per building and limit: OR-Tools'
seconds, its objective on the table, the plan's objective with carried beliefs, the solutions
found, the one that last improved the objective and the most in a row that did not improve it
before one that did). ``--scenario`` adds a shipped config (its own goals).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from families import KINDS, write  # noqa: E402

from tmpnav.attachment.canonical import CanonicalCosts  # noqa: E402
from tmpnav.attachment.carried import CarriedCosts  # noqa: E402
from tmpnav.pipeline import PlanOptions, prepare  # noqa: E402
from tmpnav.planning.run import span_weight_of  # noqa: E402
from tmpnav.results import StageTimes  # noqa: E402
from tmpnav.task.first_routes import ROUTING_CAP  # noqa: E402
from tmpnav.task.plans import with_origins  # noqa: E402
from tmpnav.task.routing import solve_routes  # noqa: E402

OUT = ROOT / "benchmarks" / "routing"


def building(kind: str, rooms: int, robots: int, seed: int, limits: list[str], folder: Path) -> list[str]:
    path = write(KINDS[kind](rooms, robots, seed), folder / f"{kind}-{rooms}-{robots}-{seed}.yaml")
    return routes_of(path, f"{kind},{rooms},{robots},{seed}", limits, folder)


def routes_of(path: Path, name: str, limits: list[str], folder: Path) -> list[str]:
    prep = prepare(path, PlanOptions.of(cache_dir=folder / "cache"), StageTimes())
    rows = []
    try:
        sc = prep.scenario
        canonical = CanonicalCosts(prep.oracle, prep.world, sc.planner.pair_min_gain)
        carried = CarriedCosts(prep.oracle, canonical)
        singles = canonical.singles(sc.goals)
        weight = span_weight_of(sc)
        for limit in limits:
            most, _, still = limit.partition("/")
            start = time.perf_counter()
            routes = solve_routes(
                singles,
                sc.goals,
                ROUTING_CAP,
                solution_limit=int(most),
                span_weight=weight,
                stagnation=int(still) if still else None,
            )
            seconds = time.perf_counter() - start
            steps = with_origins([((m[0], m[2]),) for m in routes.moves(singles)], singles.start_location)
            value = carried.plan_cost(steps).value(weight)
            rows.append(
                f"{name},{limit},{seconds:.2f},{routes.cost:.3f},{value:.3f},"
                f"{routes.solutions},{routes.last_improvement},{routes.plateau},{routes.status}"
            )
            print(rows[-1], flush=True)
    finally:
        prep.oracle.close()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="office:40:4:10,office:60:8:4", help="kind:rooms:robots:seeds,...")
    parser.add_argument("--limits", default="500,500/100", help="solutions[/stagnation],...")
    parser.add_argument("--scenario", action="append", default=[], help="a shipped config too")
    args = parser.parse_args()
    limits = args.limits.split(",")
    columns = "seconds,table_objective,carried_objective,solutions,last_improvement,plateau,status"
    rows = [f"kind,rooms,robots,seed,limit,{columns}"]
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes.split(","):
            kind, rooms, robots, seeds = size.split(":")
            for seed in range(int(seeds)):
                rows += building(kind, int(rooms), int(robots), seed, limits, Path(tmp))
        for scenario in args.scenario:
            rows += routes_of(ROOT / scenario, f"{Path(scenario).stem},-,-,-", limits, Path(tmp))
    OUT.mkdir(parents=True, exist_ok=True)
    stamp = f"# {' '.join(sys.argv[1:]) or 'defaults'}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}\n"
    (OUT / "first_routes.txt").write_text(stamp + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
