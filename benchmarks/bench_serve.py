"""tmpnav serve through HTTP (issue 58): warm revision latency, and a load of many clients.

    python benchmarks/bench_serve.py latency --scenario configs/building-20.yaml --events 20 -o benchmarks/serve
    python benchmarks/bench_serve.py load --scenario configs/two-rooms.yaml --clients 20 --plans 5 --seconds 90 \
        -o benchmarks/serve

Both start the real ``tmpnav serve`` (a process of its own, on loopback, a free port) on the
cache directory given (default: tmpnav's), make the first plan(s), then post team states.

``latency``: one client posts ``--events`` states, each against the plan's latest revision: the
team at a random time of that revision's schedule (seeded), where the plan has them, the first
robot's pose and covariance given as AMCL's 36 numbers. Each latency is the wall time of the
POST (HTTP, JSON, the revision planned and stored). Writes ``<name>-latency.csv`` and ``.txt``.

``load``: ``--clients`` threads post states to ``--plans`` plans (client i to plan i mod plans)
for ``--seconds``: each reads the plan's latest revision and posts a state against it; a 409
(stale: another client's revision came first) is counted and the client goes on from the latest.
At the end every plan's revisions are checked against the answers: each 201 answer's revision is
stored once (none lost), no revision number was answered twice (none applied twice). Writes
``<name>-load.txt``.
"""

from __future__ import annotations

import argparse
import collections
import csv
import platform
import random
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.serve.server import Server  # noqa: E402
from tmpnav.cachedir import default_cache_dir  # noqa: E402
from tmpnav.client import Client, ServiceError  # noqa: E402


def amcl(cov: list[list[float]]) -> list[float]:
    """A 3x3 (x, y, yaw) covariance as the 36 numbers of a ROS PoseWithCovariance."""
    out = [0.0] * 36
    for i, a in enumerate((0, 1, 5)):
        for j, b in enumerate((0, 1, 5)):
            out[6 * a + b] = cov[i][j]
    for k in (2, 3, 4):
        out[7 * k] = 1e6  # z, roll, pitch: unknown, as AMCL publishes them
    return out


def state_of(doc: dict[str, Any], rng: random.Random, within: tuple[float, float] = (0.0, 0.5)) -> dict[str, Any]:
    """The team at a random time of the plan (by default its first half), the first robot's
    belief from AMCL."""
    t = rng.uniform(within[0] * doc["schedule"]["makespan"], within[1] * doc["schedule"]["makespan"])
    state: dict[str, Any] = {"time": round(t, 2)}
    robot, steps = next(iter(doc["trajectories"].items()))
    step = steps[min(len(steps) - 1, int(t / doc["dt"]))]
    state["robots"] = {robot: {"pose": step["mean"], "covariance": amcl(step["cov"])}}
    return state


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q * (len(ordered) - 1)))]


def latency(client: Any, events: int, seed: int, shift: bool = False) -> list[dict[str, Any]]:
    """Chained (default): each state revises the revision before it. ``shift``: each state revises
    a new plan of the whole shift (remembered by the cache, so it is made at once) at a random
    time in 5-85% of its makespan, as the first replan of a shift under way."""
    rng = random.Random(seed)
    plan = client.plan()
    rows = []
    for event in range(events):
        if shift and event:
            plan = client.plan()
        doc = client.document(plan["id"])
        state = state_of(doc, rng, (0.05, 0.85) if shift else (0.0, 0.5))
        start = time.perf_counter()
        try:
            info = client.post_state(plan["id"], plan["revision"], state)
            outcome, plan = "revision", info
        except ServiceError as err:  # the team at a time the plan cannot go on from (all done)
            outcome = f"{err.status} {err.problem['detail'][:80]}"
        rows.append(
            {
                "event": event,
                "time": state["time"],
                "seconds": round(time.perf_counter() - start, 3),
                "outcome": outcome,
                "revision": plan["revision"],
                "cost": plan.get("cost", ""),
                "makespan": plan.get("makespan", ""),
            }
        )
        print(rows[-1], flush=True)
    return rows


class Direct:
    """The service's own calls in this process, without HTTP: the same site, store and jobs (for
    the latency of HTTP itself, side by side with the service's)."""

    def __init__(self, scenario: str, cache: Path):
        from tmpnav.serve.service import Service

        self.service = Service.start(scenario, cache)

    def _wait(self, job: Any) -> dict[str, Any]:
        job.done.wait()
        if job.status != "done":
            raise ServiceError(job.problem["status"], job.problem)
        result: dict[str, Any] = job.result
        return result

    def plan(self) -> dict[str, Any]:
        return self._wait(self.service.plan(None, None))

    def document(self, plan: str) -> dict[str, Any]:
        return self.service.document(plan, None)

    def post_state(self, plan: str, revision: int, state: dict[str, Any]) -> dict[str, Any]:
        return self._wait(self.service.revise(plan, revision, state, None))


def load(client: Client, clients: int, plans: int, seconds: float, seed: int, renew: float = 0.5) -> str:
    """Client i posts team states to plan slot i mod ``plans``, each against the slot's latest
    revision. A slot whose latest revision leaves less than ``renew`` of its first plan's
    makespan gets a new plan of the shift (the cache remembers it: made at once): chained
    revisions shrink the work left, and a nearly finished plan revises in no time."""
    ids = [client.plan()["id"] for _ in range(plans)]
    every = list(ids)
    first: dict[str, float] = {}
    answered: dict[str, list[int]] = collections.defaultdict(list)
    latencies: list[float] = []
    counts: collections.Counter[str] = collections.Counter()
    lock = threading.Lock()
    end = time.monotonic() + seconds

    def run(i: int) -> None:
        rng, slot = random.Random(seed + i), i % plans
        while time.monotonic() < end:
            plan = ids[slot]
            doc = client.document(plan)
            number = doc["revision"]["number"] if "revision" in doc else 0
            makespan = float(doc["schedule"]["makespan"])
            with lock:
                first.setdefault(plan, makespan)
                if ids[slot] == plan and makespan < renew * first[plan]:
                    ids[slot] = client.plan()["id"]
                    every.append(ids[slot])
                    counts["new plan"] += 1
                    continue
            start = time.perf_counter()
            try:
                info = client.post_state(plan, number, state_of(doc, rng))
                outcome = "201"
            except ServiceError as err:
                info, outcome = None, str(err.status)
            took = time.perf_counter() - start
            with lock:
                counts[outcome] += 1
                latencies.append(took)
                if info is not None:
                    answered[plan].append(info["revision"])

    threads = [threading.Thread(target=run, args=(i,)) for i in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    lost = twice = 0
    stored = client.plans()
    for plan in every:
        latest = next(p["revision"] for p in stored if p["id"] == plan)
        numbers = answered[plan]
        twice += len(numbers) - len(set(numbers))
        lost += len(set(range(1, latest + 1)) - set(numbers))  # stored revisions no client was answered
        lost += len(set(numbers) - set(range(1, latest + 1)))  # answered revisions not stored
    return (
        f"{clients} clients, {plans} plans at a time ({len(every)} in all), {seconds:g} s: "
        f"{sum(v for k, v in counts.items() if k != 'new plan')} posts, "
        f"answers {dict(sorted(counts.items()))}\n"
        f"latency p50 {percentile(latencies, 0.5):.3f} s, p90 {percentile(latencies, 0.9):.3f} s, "
        f"p99 {percentile(latencies, 0.99):.3f} s, max {max(latencies):.3f} s\n"
        f"revisions stored {sum(len(v) for v in answered.values())}; lost {lost}; applied twice {twice}\n"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mode", choices=["latency", "load"])
    parser.add_argument("--scenario", default="configs/building-20.yaml")
    parser.add_argument("--events", type=int, default=20)
    parser.add_argument("--clients", type=int, default=20)
    parser.add_argument("--plans", type=int, default=5)
    parser.add_argument("--seconds", type=float, default=90.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--cache-dir", type=Path, default=None)
    parser.add_argument("--direct", action="store_true", help="latency: the service's calls in this process, no HTTP")
    parser.add_argument("--shift", action="store_true", help="latency: each state revises a new plan of the shift")
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "benchmarks" / "serve")
    args = parser.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    name = Path(args.scenario).stem
    if args.direct:
        rows = latency(Direct(args.scenario, args.cache_dir or default_cache_dir()), args.events, args.seed, args.shift)
        took = [r["seconds"] for r in rows if r["outcome"] == "revision"]
        text = (
            f"# {args.scenario}, in process (no HTTP): {len(took)} of {len(rows)} revisions: median "
            f"{statistics.median(took):.3f} s, p90 {percentile(took, 0.9):.3f} s, max {max(took):.3f} s\n"
        )
        (args.output / f"{name}-direct.txt").write_text(text)
        print(text, end="")
        return
    server = Server(args.scenario, args.cache_dir or default_cache_dir(), logs=Path(tempfile.gettempdir()))
    try:
        client = Client(server.url)
        header = f"# {platform.node()} {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} {args.scenario}\n"
        if args.mode == "latency":
            rows = latency(client, args.events, args.seed, args.shift)
            suffix = "-shift" if args.shift else ""
            with (args.output / f"{name}-latency{suffix}.csv").open("w", newline="") as out:
                writer = csv.DictWriter(out, fieldnames=list(rows[0]))
                writer.writeheader()
                writer.writerows(rows)
            took = [r["seconds"] for r in rows if r["outcome"] == "revision"]
            text = (
                f"{header}{len(took)} of {len(rows)} revisions through HTTP: median "
                f"{statistics.median(took):.3f} s, p90 {percentile(took, 0.9):.3f} s, max {max(took):.3f} s\n"
            )
        else:
            text = header + load(client, args.clients, args.plans, args.seconds, args.seed)
        suffix = "-shift" if args.mode == "latency" and args.shift else ""
        (args.output / f"{name}-{args.mode}{suffix}.txt").write_text(text)
        print(text, end="")
    finally:
        server.stop()


if __name__ == "__main__":
    main()
