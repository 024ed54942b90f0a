"""The plan's clock against nav2's Regulated Pure Pursuit: each move's planned duration next to
the one executed by ``tmpnav simulate --follower rpp`` (and by the waypoint follower that turns on
the spot as the plan does), median over the sessions; seconds per metre of driving; the makespan.

    .venv/bin/python benchmarks/bench_rpp.py [--sessions 20] [--only building-4robots ...]
        [--controller rpp|turn-then-drive] [--followers waypoint rpp auto] [--workers 1]

Writes ``rpp/NAME.csv`` (one row per move and follower; ``rpp/NAME.CONTROLLER.csv`` with
``--controller``, which plans a copy of the scenario with ``models.controller`` set) and prints
one line per scenario and follower (benchmarks/README.md, "The plan's clock against nav2's RPP").
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
import yaml

from tmpnav.execution import execute
from tmpnav.execution.localisers import Localisation
from tmpnav.execution.moves import queues
from tmpnav.pipeline import plan

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SCENARIOS = ("building-4robots", "building-20", "depot-jobs", "office-ros")


def with_controller(source: Path, controller: str, folder: Path) -> Path:
    """A copy of ``source`` in ``folder`` with ``models.controller`` set and its map paths absolute."""
    doc = yaml.safe_load(source.read_text())
    for key in ("ros", "image"):
        found = doc.get("map", {}).get(key)
        if isinstance(found, str) and not Path(found).is_absolute():
            doc["map"][key] = str((source.parent / found).resolve())
    doc.setdefault("models", {})["controller"] = controller
    target = folder / source.name
    target.write_text(yaml.safe_dump(doc, sort_keys=False))
    return target


def measure(
    name: str,
    sessions: int,
    controller: str | None = None,
    folder: Path | None = None,
    followers: tuple[str, ...] = ("waypoint", "rpp"),
    workers: int | None = None,
) -> list[str]:
    source = ROOT / "configs" / f"{name}.yaml"
    report = plan(with_controller(source, controller, folder) if controller and folder else source)
    paths = {(m.robot, m.step): m for q in queues(report).values() for m in q}
    planned = {(m.robot, m.step): m for m in report.schedule.moves}
    rows, lines = [], []
    for follower in followers:
        result = execute(report, sessions, 0, workers, Localisation(follower=follower))
        config = min(result.schedules)
        runs = result.schedules[config]
        ratios, per_metre, planned_per_metre = [], [], []
        for key, p in planned.items():
            move = paths.get(key)
            if move is None or len(move.points) < 2:
                continue
            length = float(np.sum(np.hypot(*np.diff(np.asarray(move.points), axis=0).T)))
            done = [m.end - m.start for s in runs for m in s.moves if (m.robot, m.step) == key]
            if not done or length <= 0.0 or p.end - p.start <= 0.0:
                continue
            executed = float(np.median(done))
            ratios.append(executed / (p.end - p.start))
            per_metre.append(executed / length)
            planned_per_metre.append((p.end - p.start) / length)
            rows.append(f"{follower},{key[0]},{key[1] + 1},{length:.2f},{p.end - p.start:.1f},{executed:.1f}")
        makespan = float(np.mean([s.makespan for s in runs]))
        hit, touched = np.zeros(sessions, dtype=bool), np.zeros(sessions, dtype=bool)
        for (c, _), v in result.wall_hits.items():
            hit |= (np.asarray(v) > 0) if c == config else False
        for (c, _), v in result.contacts.items():
            touched |= (np.asarray(v) > 0) if c == config else False
        hits = int(hit.sum())
        over = [
            (key, int(np.count_nonzero(v)), result.bounds.get((key[1], key[2]), 0.0))
            for key, v in result.move_hits.items()
            if key[0] == config and key[2] >= 0
        ]
        # a move over its bound: its hit rate's 95% lower Clopper-Pearson limit above the planned bound
        from scipy.stats import beta

        beyond = sum(1 for _, k, b in over if k > 0 and beta.ppf(0.025, k, sessions - k + 1) > b)
        planned_makespan = report.schedule.makespan
        label = f" ({controller})" if controller else ""
        within = float(np.mean(np.abs(np.array(ratios) - 1.0) <= 0.10))
        lines.append(
            f"{name}{label} {follower}: {len(ratios)} moves; executed/planned duration median {np.median(ratios):.2f} "
            f"(within 10%: {within:.0%}); executed {np.median(per_metre):.2f} s/m against planned "
            f"{np.median(planned_per_metre):.2f} s/m; "
            f"makespan planned {planned_makespan:.1f} s, executed {makespan:.1f} s "
            f"({makespan / planned_makespan - 1:+.1%}); sessions with a wall hit {hits}/{sessions}, "
            f"with a contact {int(touched.sum())}/{sessions}; moves whose hit rate lies above their bound "
            f"{beyond}/{len(over)}"
        )
    out = HERE / "rpp"
    out.mkdir(exist_ok=True)
    (out / (f"{name}.{controller}.csv" if controller else f"{name}.csv")).write_text(
        "follower,robot,step,length_m,planned_s,executed_median_s\n" + "\n".join(rows) + "\n"
    )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=20)
    parser.add_argument("--only", nargs="*", default=None)
    parser.add_argument("--controller", choices=("rpp", "turn-then-drive"), default=None)
    parser.add_argument("--followers", nargs="+", choices=("waypoint", "rpp", "auto"), default=["waypoint", "rpp"])
    parser.add_argument("--workers", type=int, default=None, help="processes (default: one per core)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.only or SCENARIOS:
            for line in measure(name, args.sessions, args.controller, Path(tmp), tuple(args.followers), args.workers):
                print(line, flush=True)


if __name__ == "__main__":
    main()
