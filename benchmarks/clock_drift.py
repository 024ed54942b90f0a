"""How late executed robots run against the plan's clock: from ``tmpnav simulate -o DIR``'s
sessions.csv (when each robot was done, per execution) and each robot's planned done time, the
lateness when done per second of the plan, pooled over the robots whose plan lasts more than
``--min-plan`` seconds, with its quantiles; and each robot's lateness in the executions with a
contact. docs/models.md ("Two robots off the plan's clock") gives the figures of
``amcl/safety/building-4robots.local.rpp.seed200.sessions.csv``:

    .venv/bin/python benchmarks/clock_drift.py amcl/safety/building-4robots.local.rpp.seed200.sessions.csv \\
        r1=165.5 r2=231.0 r3=34.0 r4=214.0
"""

from __future__ import annotations

import argparse
import csv
from collections import defaultdict
from pathlib import Path

QUANTILES = (0.5, 0.75, 0.9, 0.95, 0.975, 1.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sessions", type=Path, help="sessions.csv of tmpnav simulate -o DIR")
    parser.add_argument("planned", nargs="+", help="ROBOT=SECONDS: when the plan has each robot done")
    parser.add_argument("--min-plan", type=float, default=100.0, help="pool robots whose plan lasts longer (s)")
    parser.add_argument("--config", default="1", help="the configuration's rows (1: with mutual observations)")
    args = parser.parse_args()
    planned = {robot: float(s) for robot, s in (p.split("=", 1) for p in args.planned)}
    ratios, late = [], defaultdict(list)
    contacts: dict[str, list[str]] = defaultdict(list)
    for row in csv.DictReader(args.sessions.open()):
        robot = row["robot"]
        if row["config"] != args.config or robot not in planned:
            continue
        behind = float(row["done_s"]) - planned[robot]
        late[robot].append(behind)
        if planned[robot] > args.min_plan:
            ratios.append(behind / planned[robot])
        if int(row["contacts"] or 0):
            contacts[row["session"]].append(f"{robot} {behind:+.1f} s")
    ratios.sort()
    print(f"lateness when done per second of plan, {len(ratios)} robot-executions (plans over {args.min_plan:g} s):")
    for q in QUANTILES:
        print(f"  {q:>5.1%}: {ratios[min(len(ratios) - 1, int(q * len(ratios)))]:.3f}")
    for robot, values in sorted(late.items()):
        values.sort()
        print(f"{robot}: planned done {planned[robot]:g} s; late median {values[len(values) // 2]:+.1f} s, "
              f"largest {values[-1]:+.1f} s")  # fmt: skip
    for session, who in sorted(contacts.items(), key=lambda x: int(x[0])):
        print(f"execution {session} with a contact: {', '.join(who)} when done")


if __name__ == "__main__":
    main()
