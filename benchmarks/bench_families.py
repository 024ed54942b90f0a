"""tmpnav on buildings it was not tuned on: generated families (benchmarks/families.py), fresh commands.

    .venv/bin/python benchmarks/bench_families.py [--seeds 10] [--sizes office:20:2,office:40:4,office:60:8:5] [-o DIR]

For every size (kind, rooms, robots) and seed, one fresh ``tmpnav plan`` of the generated scenario
with its default settings (a cold cache each): exit code, time, the objective, whether the
anytime search converged or stopped at its budget, how far the roadmap grew, and the peak
memory of the command and its worker processes as the proportional set size (PSS: a page shared
by n processes counts 1/n to each), sampled every 0.2 s. Writes runs.csv, a table of median and
p90 per size (summary.md) and families.png (time and objective against rooms and robots) into
benchmarks/families/ (or ``-o DIR``).
"""

from __future__ import annotations

import argparse
import csv
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
from families import KINDS, write  # benchmarks/ is the script's folder, first on sys.path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "families"
TMPNAV = [sys.executable, "-m", "tmpnav"]
SIZES = "office:20:2,office:40:4,office:60:8,warehouse:20:2,warehouse:40:4"


def _tree(pid: int) -> list[int]:
    """``pid`` and its descendants."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        try:
            children = Path(f"/proc/{p}/task/{p}/children").read_text().split()
        except OSError:
            continue
        todo += [int(c) for c in children]
    return out


def _pss(pid: int) -> int:
    """Proportional set size of one process (kB), 0 when it is gone."""
    try:
        for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
            if line.startswith("Pss:"):
                return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def run(scenario: Path, cache: Path) -> dict[str, object]:
    """One fresh command; its exit code, seconds, peak PSS (MB) and what its summary says."""
    start = time.perf_counter()
    proc = subprocess.Popen(
        [*TMPNAV, "plan", str(scenario), "--cache-dir", str(cache), "--format", "text"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    peak, done = [0], threading.Event()

    def sample() -> None:
        while not done.is_set():
            peak[0] = max(peak[0], sum(_pss(p) for p in _tree(proc.pid)))
            time.sleep(0.2)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    out, err = proc.communicate()
    seconds = time.perf_counter() - start
    done.set()
    sampler.join()
    objective = re.search(r"objective .*?: ([0-9.]+)", out)
    stopped = re.search(r"stopped: ([a-z ]+)", out)
    return {
        "exit": proc.returncode,
        "seconds": round(seconds, 2),
        "objective": float(objective.group(1)) if objective else float("nan"),
        "stopped": stopped.group(1).strip() if stopped else "exact",
        "peak_pss_mb": round(peak[0] / 1024, 1),
        "error": err.strip().splitlines()[-1] if proc.returncode else "",
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument(
        "--sizes", default=SIZES, help="kind:rooms:robots[:seeds], comma-separated (seeds: --seeds unless given)"
    )
    parser.add_argument("-o", "--output", type=Path, default=OUT, help="folder of the results (default: %(default)s)")
    parser.add_argument(
        "--localiser",
        choices=("beams", "amcl"),
        default=None,
        help="the lidar's localiser model (models.range_sensor.localiser.model; default: the scenario default)",
    )
    args = parser.parse_args()
    out = args.output
    out.mkdir(parents=True, exist_ok=True)
    fields = [s.split(":") for s in args.sizes.split(",")]
    seeds = {(f[0], int(f[1]), int(f[2])): int(f[3]) if len(f) > 3 else args.seeds for f in fields}
    sizes = list(seeds)
    rows: list[dict[str, object]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind, rooms, robots in sizes:
            for seed in range(seeds[(kind, rooms, robots)]):
                doc = KINDS[kind](rooms, robots, seed)
                if args.localiser and "range_sensor" in doc.get("models", {}):
                    doc["models"]["range_sensor"]["localiser"] = {"model": args.localiser}
                path = write(doc, Path(tmp) / f"{kind}-{rooms}-{robots}-{seed}.yaml")
                result = run(path, Path(tmp) / f"cache-{kind}-{rooms}-{robots}-{seed}")
                rows.append({"kind": kind, "rooms": rooms, "robots": robots, "seed": seed, **result})
                print(rows[-1], flush=True)
    with open(out / "runs.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        f"# `python benchmarks/bench_families.py --seeds {args.seeds} --sizes {args.sizes}"
        + (f" --localiser {args.localiser}" if args.localiser else "")
        + "`, "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        "",
        "| kind | rooms | robots | planned | time median [s] | time p90 [s] | converged | objective median | "
        "peak PSS median / max [MB] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for kind, rooms, robots in sizes:
        mine = [r for r in rows if (r["kind"], r["rooms"], r["robots"]) == (kind, rooms, robots)]
        ok = [r for r in mine if r["exit"] == 0]
        t = np.array([float(r["seconds"]) for r in ok]) if ok else np.array([np.nan])  # type: ignore[arg-type]
        obj = np.array([float(r["objective"]) for r in ok]) if ok else np.array([np.nan])  # type: ignore[arg-type]
        pss = np.array([float(r["peak_pss_mb"]) for r in ok]) if ok else np.array([np.nan])  # type: ignore[arg-type]
        # converged or proved optimal; a search stopped by its work or time budget did neither
        converged = sum(r["stopped"] in ("converged", "optimal", "solved", "exact", "nothing to do") for r in ok)
        lines.append(
            f"| {kind} | {rooms} | {robots} | {len(ok)}/{len(mine)} | {np.median(t):.1f} | "
            f"{np.percentile(t, 90):.1f} | {converged}/{len(ok)} | {np.median(obj):.1f} | "
            f"{np.median(pss):.0f} / {np.max(pss):.0f} |"
        )
    failures = [
        f"- {r['kind']} {r['rooms']}/{r['robots']} seed {r['seed']}: exit {r['exit']}: {r['error']}"
        for r in rows
        if r["exit"]
    ]
    (out / "summary.md").write_text("\n".join(lines + (["", *failures] if failures else [])) + "\n")
    _figure(rows, sizes, out)
    print("\n".join(lines))


def _figure(rows: list[dict[str, object]], sizes: list[tuple[str, int, int]], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_o) = plt.subplots(1, 2, figsize=(10, 3.8))
    for kind, marker in (("office", "o"), ("warehouse", "s")):
        mine = [s for s in sizes if s[0] == kind]
        for _, rooms, robots in mine:
            ok = [r for r in rows if (r["kind"], r["rooms"], r["robots"]) == (kind, rooms, robots) and r["exit"] == 0]
            t = [float(r["seconds"]) for r in ok]  # type: ignore[arg-type]
            o = [float(r["objective"]) for r in ok]  # type: ignore[arg-type]
            label = f"{kind} {rooms} rooms / {robots} robots"
            ax_t.scatter([rooms] * len(t), t, marker=marker, alpha=0.5, label=label)
            ax_o.scatter([rooms] * len(o), o, marker=marker, alpha=0.5, label=label)
    ax_t.set_xlabel("rooms (places)")
    ax_t.set_ylabel("fresh `tmpnav plan` [s]")
    ax_o.set_xlabel("rooms (places)")
    ax_o.set_ylabel("objective (cost + 1 per s of makespan)")
    ax_t.legend(fontsize=7)
    for ax in (ax_t, ax_o):
        ax.grid(True, lw=0.3)
    fig.suptitle("Generated families, one dot per seed (benchmarks/families.py)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out / "families.png", dpi=110)


if __name__ == "__main__":
    main()
