"""Where a fresh, warm tmpnav command spends its fixed cost (issues 56 and 57).

    python benchmarks/startup.py [--runs 3] [--base DIR] [--corridor] [-o benchmarks/startup]

Two parts, each in fresh interpreters (as a command runs):

- the pieces: the CPU time of importing each heavy library the plan command imports
  (numpy, SciPy's csgraph and ndimage, numba, matplotlib's figure and Agg canvas; each on
  top of the ones before), numba's first kernel read from its cache (its typing context),
  and drawing plan.png and schedule.png of the warm corridor plan;
- the commands: ``tmpnav plan configs/corridor.yaml`` on a warm cache, and ``tmpnav replan``
  of the shift and of building-4robots (benchmarks/replan_time/) with ``--export nav2``,
  each ``--runs`` times after a warm-up run; wall time and CPU time (the process and the
  children it waits for: ENHSP's JVM, ended at exit, is not counted). With ``--base DIR``
  (another checkout of tmpnav, for example ``git archive <commit> | tar -x -C DIR``) the same
  commands of DIR run alternately with this checkout's, on one cache, so that both see the
  same load.

``--corridor`` times only ``tmpnav plan configs/corridor.yaml`` with ``-o DIR`` and without
(corridor.txt), as issue 57 states its target.

The machine's load average is printed with the figures: on a shared machine the wall times
wait for the others, so the CPU time is the better figure of what a command costs.
Bytecode is compiled first (``compileall``, as an install does): with
``PYTHONDONTWRITEBYTECODE`` set, tmpnav's own modules would otherwise be compiled from source
by every command (0.7 s).
"""

from __future__ import annotations

import argparse
import compileall
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: each line imports on top of the lines before it; the CPU time of a line is its own
IMPORTS = (
    ("python and numpy", "import numpy"),
    ("scipy.sparse.csgraph", "import scipy.sparse.csgraph"),
    ("scipy.ndimage", "import scipy.ndimage"),
    ("numba", "import numba"),
    ("matplotlib (figure, Agg)", "import matplotlib.figure, matplotlib.backends.backend_agg"),
    ("matplotlib.pyplot", "import matplotlib.pyplot"),
)

FIRST_KERNEL = r"""
import time
import numpy as np
from tmpnav.world import geometry  # numba imported, the kernels declared
t = time.process_time()
geometry.wrap_angle_scalar(4.0)  # read from numba's cache: its typing context is made first
print(f"{time.process_time() - t:.3f}")
"""

FIGURES = r"""
import sys, time
from pathlib import Path
T = time.process_time
from tmpnav import pipeline
report = pipeline.plan(sys.argv[1], pipeline.PlanOptions.of(cache_dir=Path(sys.argv[2])))
t = T()
from tmpnav.report import figures as fg
from tmpnav.report.plan_plot import plan_figure
from tmpnav.report.schedule_plot import schedule_figure
imported = T() - t
out = Path(sys.argv[3])
t = T(); fg.render(plan_figure(report), out / "plan.png"); plan = T() - t
t = T(); fg.render(schedule_figure(report), out / "schedule.png"); schedule = T() - t
print(f"{imported:.3f} {plan:.3f} {schedule:.3f}")
"""


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run(root: Path, args: list[str | Path], cwd: Path | None = None) -> tuple[float, float, str]:
    """Run ``python ARGS`` with ``root``'s tmpnav first on the path: wall, CPU (with the children
    it waited for), stdout."""
    env = dict(os.environ, PYTHONPATH=str(root))
    cpu, began = children_cpu(), time.perf_counter()
    done = subprocess.run(
        [sys.executable, *map(str, args)], capture_output=True, text=True, cwd=cwd or root, env=env, timeout=1800
    )
    wall = time.perf_counter() - began
    if done.returncode != 0:
        sys.exit(f"{args}: exit {done.returncode}\n{done.stderr[-2000:]}")
    return wall, children_cpu() - cpu, done.stdout


def load() -> str:
    return "load average " + " ".join(f"{x:.1f}" for x in os.getloadavg())


def pieces(root: Path, runs: int, tmp: Path) -> list[str]:
    """The CPU time of each heavy import, of numba's first cached kernel, and of the two figures."""
    lines = [f"pieces (CPU s, median of {runs} fresh processes; {load()})"]
    before = ""
    for name, statement in IMPORTS:
        own = []
        for _ in range(runs):
            code = f"import time; {before}; t = time.process_time(); {statement}; print(time.process_time() - t)"
            code = code.replace("; ;", ";")
            own.append(float(run(root, ["-c", code])[2]))
        before += f"; {statement}" if before else statement
        lines.append(f"  import {name:<26} {statistics.median(own):5.2f}")
    first = [float(run(root, ["-c", FIRST_KERNEL])[2]) for _ in range(runs)]
    lines.append(f"  numba's first cached kernel        {statistics.median(first):5.2f}")
    cache = tmp / "pieces-cache"
    run(root, ["-m", "tmpnav", "plan", ROOT / "configs" / "corridor.yaml", "-q", "--cache-dir", cache, "-o", tmp / "p"])
    figures: list[str | Path] = ["-c", FIGURES, ROOT / "configs" / "corridor.yaml", cache, tmp / "p"]
    drawn = [run(root, figures)[2].split() for _ in range(runs)]
    for k, name in enumerate(("import the figure modules", "corridor plan.png", "corridor schedule.png")):
        lines.append(f"  {name:<33} {statistics.median(float(d[k]) for d in drawn):5.2f}")
    return lines


def commands(tmp: Path, cache: Path, name: str, prefix: list[str | Path]) -> dict[str, list[str | Path]]:
    """The three commands on ``cache``, each with its own output folder (under ``name``)."""
    replans = ROOT / "benchmarks" / "replan_time"
    scenarios = {
        "plan corridor": (ROOT / "configs" / "corridor.yaml", None),
        "replan shift": (ROOT / "tests" / "replan" / "data" / "shift.yaml", replans / "shift.state.yaml"),
        "replan building-4robots": (
            ROOT / "configs" / "building-4robots.yaml",
            replans / "building-4robots.state.yaml",
        ),
    }
    found: dict[str, list[str | Path]] = {}
    for label, (scenario, state) in scenarios.items():
        out = tmp / name / label.replace(" ", "-")
        if state is None:
            found[label] = [*prefix, "plan", scenario, "-q", "--cache-dir", cache, "-o", out]
        else:
            first = tmp / name / f"{label.replace(' ', '-')}-first"
            found[f"{label} (first plan)"] = [*prefix, "plan", scenario, "-q", "--cache-dir", cache, "-o", first]
            plan = ("--plan", first / "plan.json", "--state", state)
            found[label] = [*prefix, "replan", scenario, *plan, "-q", "--cache-dir", cache, "-o", out]
            found[label] += ["--export", "nav2"]
    return found


def timed_commands(roots: dict[str, Path], runs: int, tmp: Path, cache: Path) -> list[str]:
    """Each command warmed up once, then run ``runs`` times, the roots alternating, on one
    cache (the roots' keys agree where their planning code does)."""
    per_root = {name: commands(tmp, cache, name, ["-m", "tmpnav"]) for name in roots}
    figures: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for label in per_root[next(iter(roots))]:
        for name, root in roots.items():
            wall, _, _ = run(root, per_root[name][label])
            print(f"{name}: {label}: warm-up {wall:.1f} s", flush=True)
        if "first plan" in label:
            continue
        for _ in range(runs):
            for name, root in roots.items():
                wall, cpu, _ = run(root, per_root[name][label])
                figures.setdefault((name, label), []).append((wall, cpu))
    lines = [f"commands on a warm cache ({runs} runs each, alternating; {load()} at the end)"]
    for (name, label), got in figures.items():
        walls = ", ".join(f"{w:.2f}" for w, _ in got)
        cpus = ", ".join(f"{c:.2f}" for _, c in got)
        wall, cpu = statistics.median(w for w, _ in got), statistics.median(c for _, c in got)
        median = f"median wall {wall:5.2f} s, CPU {cpu:5.2f} s"
        lines.append(f"  {name:<6} {label:<24} {median}  (wall {walls}; CPU {cpus})")
    return lines


def corridor(roots: dict[str, Path], runs: int, tmp: Path, cache: Path) -> list[str]:
    """``tmpnav plan configs/corridor.yaml -o DIR`` (plan.json, the two figures, the PDDL) and the
    same without ``-o`` (no files) on a warm cache, as issue 57 times them: each warmed up once,
    then ``runs`` times, the roots and the two commands alternating; the load average before each
    run."""
    scenario = ROOT / "configs" / "corridor.yaml"
    variants: dict[str, list[str | Path]] = {"-o DIR": ["-o", tmp / "out"], "no files": []}
    for root in roots.values():  # warm-ups
        for extra in variants.values():
            run(root, ["-m", "tmpnav", "plan", scenario, "--cache-dir", cache, *extra])
    got: dict[tuple[str, str], list[tuple[float, float, float]]] = {}
    for _ in range(runs):
        for name, root in roots.items():
            for label, extra in variants.items():
                before = os.getloadavg()[0]
                wall, cpu, _ = run(root, ["-m", "tmpnav", "plan", scenario, "--cache-dir", cache, *extra])
                got.setdefault((name, label), []).append((wall, cpu, before))
                print(f"{name}: plan corridor {label}: {wall:.2f} s (load {before:.2f})", flush=True)
    lines = [f"the warm corridor plan ({runs} runs each, alternating; wall s (CPU s, 1-min load before the run))"]
    for (name, label), times in got.items():
        each = ", ".join(f"{w:.2f} ({c:.2f}, {b:.1f})" for w, c, b in times)
        walls = [w for w, _, _ in times]
        span = f"{min(walls):.2f}-{max(walls):.2f} s, median {statistics.median(walls):.2f} s"
        lines.append(f"  {name:<6} {label:<9} {span}  ({each})")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--base", type=Path, default=None, help="another checkout to compare with")
    parser.add_argument("--skip-pieces", action="store_true")
    parser.add_argument("--corridor", action="store_true", help="only the warm corridor plan, with -o DIR and without")
    parser.add_argument("--cache-dir", type=Path, default=None, help="a cache to reuse (default: a new one)")
    parser.add_argument("-o", "--output", type=Path, default=None)
    args = parser.parse_args()
    roots = {"this": ROOT} | ({"base": args.base.resolve()} if args.base else {})
    for root in roots.values():
        compileall.compile_dir(root / "tmpnav", quiet=1)
    lines = [f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} cores"]
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        if args.corridor:
            lines += corridor(roots, args.runs, tmp, args.cache_dir or tmp / "cache")
            return report(lines, args.output, "corridor.txt")
        if not args.skip_pieces:
            for name, root in roots.items():
                lines += [f"[{name}] {line}" for line in pieces(root, args.runs, tmp / name)]
                print("\n".join(lines), flush=True)
        lines += timed_commands(roots, args.runs, tmp, args.cache_dir or tmp / "cache")
    report(lines, args.output, "startup.txt")


def report(lines: list[str], folder: Path | None, name: str) -> None:
    """Print the lines, and write them to ``folder/name`` when a folder is given."""
    text = "\n".join(lines)
    print(text)
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(text + "\n")


if __name__ == "__main__":
    main()
