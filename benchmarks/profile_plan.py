"""Profile one cold-cache plan under cProfile, the oracle in this process.

    python benchmarks/profile_plan.py SCENARIO.yaml OUT.prof [--top N]

Calls tmpnav.pipeline.plan rather than the command line, whose sys.exit would lose the
profile; the oracle's executor is serial so that its time is in the profile, not in workers.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import tempfile
import time

from tmpnav.pipeline import PlanOptions, plan


def main() -> None:
    """Plan the scenario from an empty cache under cProfile; print the top entries."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario")
    parser.add_argument("output", help="the profile's dump (pstats)")
    parser.add_argument("--top", type=int, default=40)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        profile = cProfile.Profile()
        start = time.perf_counter()
        profile.enable()
        plan(args.scenario, PlanOptions.of(cache_dir=cache, executor="serial"))
        profile.disable()
        print(f"wall {time.perf_counter() - start:.2f} s")
    profile.dump_stats(args.output)
    stats = pstats.Stats(args.output)
    stats.sort_stats("tottime").print_stats(args.top)
    stats.sort_stats("cumulative").print_stats(r"tmpnav/(oracle|world|belief|roadmap)", args.top)


if __name__ == "__main__":
    main()
