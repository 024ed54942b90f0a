"""The oracle on a real Ray cluster started on this machine (issue 59): the speed-up from one worker
to two, and what the measured serial fraction extrapolates to.

    python benchmarks/bench_ray.py --scenario configs/building-20.yaml -o benchmarks/ray

A cluster is started as a fleet would start one: ``ray start --head`` with one CPU, then a second
node process with one CPU joining it (``ray start --address``). The scenario is planned cold (a
cache directory of its own each run: roadmap and every move cost computed) three ways:

1. ``--executor ray`` on the head alone (one worker);
2. ``--executor ray`` after the second node joined (two workers);
3. ``--executor processes`` with two local worker processes (the default).

Each run's plan.json must be the same but for its timings and cache folder. From the oracle
stage's wall time with one and two workers, S2 = T1 / T2, and Amdahl's law S(n) = 1 / (f + (1 - f)
/ n) gives the serial fraction f = 2 / S2 - 1 of the stage; the same for the whole command. The
extrapolations to 16 and 64 workers assume the parallel part keeps scaling and the serial part
stays (one machine's cores, no network). Ray's own start is not counted (the cluster runs
already), nor what a worker does once per site: its first task imports tmpnav and loads its
compiled kernels (about 40 s here), and the first block of a site builds the site's motion
library (the map's visibility and scan tables: seconds), which the worker keeps for the site's
next runs. Each cluster plans a scenario once first, in a cache folder of its own, untimed
(``--warm-up``: the scenario itself by default, so that the timed runs are those of a cluster
that has seen the site, as a fleet's cluster would; a small scenario where planning the site
twice would take too long, so that only the workers' start is left out).
``--plan-args`` are given to every ``tmpnav plan`` (a large site: ``--routing-time 600`` so that
OR-Tools' count of solutions, not the machine's speed, ends its first routes).
Writes ``<name>.txt``; the machine should be otherwise idle (the load is recorded).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tmpnav.report.plan_json import without_timings  # noqa: E402

RAY = Path(sys.executable).parent / "ray"
ENV = dict(os.environ, PYTHONPATH=str(ROOT), RAY_USAGE_STATS_ENABLED="0")


def ray(*args: str) -> None:
    done = subprocess.run([str(RAY), *args], env=ENV, capture_output=True, text=True, timeout=600)
    if done.returncode != 0:
        raise SystemExit(f"ray {' '.join(args)} failed: {done.stderr[-2000:]}")


def plan(scenario: str, tmp: Path, name: str, more: list[str]) -> dict[str, Any]:
    out = tmp / name
    began = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "tmpnav", "plan", scenario, "-q", "-o", str(out), "--cache-dir", str(tmp / f"c-{name}"),
         *more],
        cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=3600,
    )  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"{name}: {done.stderr[-2000:]}")
    doc: dict[str, Any] = json.loads((out / "plan.json").read_text())
    doc["command_s"] = time.perf_counter() - began
    return doc


def amdahl(speedup: float) -> tuple[float, float, float]:
    """The serial fraction f from the speed-up on two workers, and S(16), S(64)."""
    f = min(max(2.0 / speedup - 1.0, 0.0), 1.0)
    return f, 1.0 / (f + (1.0 - f) / 16), 1.0 / (f + (1.0 - f) / 64)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="configs/building-20.yaml")
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--warm-up", help="the scenario each cluster plans first, untimed (default: --scenario)")
    parser.add_argument("--plan-args", default="", help="more arguments of every tmpnav plan, one string")
    args = parser.parse_args()
    more = args.plan_args.split()
    warm = args.warm_up or args.scenario
    temp = tempfile.mkdtemp(prefix="tmpnav-ray-")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"127.0.0.1:{port}"
    common = ("--node-ip-address=127.0.0.1", "--num-cpus=1", "--disable-usage-stats")
    load, began = os.getloadavg()[0], time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    docs: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        try:
            on_ray = ["--executor", "ray", "--ray-address", address, *more]
            ray("start", "--head", f"--port={port}", "--include-dashboard=false", f"--temp-dir={temp}", *common)
            plan(warm, Path(tmp), "warm1", on_ray)
            docs["ray, 1 worker"] = plan(args.scenario, Path(tmp), "ray1", on_ray)
            ray("start", f"--address={address}", *common)
            plan(warm, Path(tmp), "warm2", on_ray)
            docs["ray, 2 workers"] = plan(args.scenario, Path(tmp), "ray2", on_ray)
        finally:
            subprocess.run([str(RAY), "stop", "--force"], env=ENV, capture_output=True, timeout=300)
            shutil.rmtree(temp, ignore_errors=True)
        docs["local processes, 2 workers"] = plan(args.scenario, Path(tmp), "local", ["--workers", "2", *more])
    plans = []
    for doc in docs.values():
        plain = without_timings({k: v for k, v in doc.items() if k != "command_s"})
        plain["cache"].pop("directory", None)
        plans.append(plain)
    same = all(p == plans[0] for p in plans)
    lines = [
        f"{args.scenario}: the oracle on a two-node Ray cluster ({platform.node()}, {os.cpu_count()} cores, "
        f"load {load:.1f} at the start, {began}; "
        f"warm-up {warm}; plan arguments: {' '.join(more) or 'none'})",
        f"  the same plan.json (timings and cache folder aside) all three ways: {'yes' if same else 'NO'}",
        "  run | oracle stage s | tmpnav total s | whole command s | move costs computed",
    ]
    for name, doc in docs.items():
        t = doc["timings"]
        lines.append(
            f"  {name} | {t['oracle']:.1f} | {t['total']:.1f} | {doc['command_s']:.1f} | {doc['cache']['misses']}"
        )
    one, two = docs["ray, 1 worker"], docs["ray, 2 workers"]
    for what, key in (("oracle stage", "oracle"), ("tmpnav total", "total")):
        s2 = one["timings"][key] / two["timings"][key]
        f, s16, s64 = amdahl(s2)
        lines.append(
            f"  {what}: speed-up 1 -> 2 workers {s2:.2f}; serial fraction {f:.2f}; extrapolated "
            f"{s16:.1f}x on 16 workers, {s64:.1f}x on 64"
        )
    args.output.mkdir(parents=True, exist_ok=True)
    (args.output / f"{Path(args.scenario).stem}.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
