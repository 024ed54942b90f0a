"""One benchmark run in its own process: ``python -m tmpnav.bench.worker`` reads a JSON job
on stdin and prints one JSON line with the stage timings of a cold, a warm and a re-planned run.

Before measuring, the worker plans a tiny shipped scenario (``configs/two-rooms.yaml``) twice,
with the exact search and with the default's anytime search, so that imports, compiled
kernels, the first JVM start and ENHSP's first searches are not counted: the timings are
those of a planning service that is already running, as in the paper's figures. The cold
run uses an empty cache directory (oracle and roadmap), the warm run the same directory
again (roadmap, cost table and task plan come from the cache), and the re-planned run the
same with ``--replan`` (cost table from the cache, the task planner runs again). When the
cold run fails (a timeout), the others are not tried and record the same failure.

The time limit holds for a whole run, whatever stage it is in (roadmap, oracle, encoding,
ENHSP): a watchdog prints the result so far, with this run and the ones after it as
timeouts, and ends the worker; the bench then kills what the run left (its oracle worker
processes, a JVM).
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import threading
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

from tmpnav import shipped
from tmpnav.bench.table import PHASES
from tmpnav.errors import TmpnavError
from tmpnav.lifetime import scratch_folder
from tmpnav.pipeline import PlanOptions, plan
from tmpnav.results import PlanReport
from tmpnav.scenario import load
from tmpnav.task import enhsp_jvm
from tmpnav.types import Goals, PlanStatus

SOLVED = {s.value for s in PlanStatus}
WARM_UP = "two-rooms.yaml"  # a shipped scenario
#: seconds the warm-up waits for ENHSP's searches to be ready
WARM_SECONDS = 30.0


def warm_up() -> None:
    """Plan a tiny scenario twice, so that imports, compiled kernels, the first JVM start and
    ENHSP's first searches are paid: its swap with the exact search, in this process, then
    its three rooms with the anytime search as a bench run plans (worker processes for the
    oracle, OR-Tools' routes, the bound's linear programs, ENHSP's sub-problems in the JVM).
    Before the second plan, a cold 10-room run spent about a second more than a second cold
    run in the same process: 0.3 s importing scipy.optimize for the bound (its LP solver
    then), the rest in ENHSP's first searches and the oracle. A different world from every
    benchmarked one: no motion, roadmap or cost computed here serves a measured run."""
    path = shipped.configs_dir() / WARM_UP
    plan(path, PlanOptions.of(use_cache=False, executor="serial"))
    rooms = tuple(room.name for room in load(path).rooms)
    plan(path, PlanOptions.of(use_cache=False, search="anytime", goals=Goals(visit=rooms, per_robot=())))
    enhsp_jvm.settle(WARM_SECONDS)  # its second search was still being made ready in the background


class Watchdog:
    """Ends the worker when a run passes the time limit, printing what was measured so far."""

    def __init__(self, out: dict[str, Any], limit: float | None, cache: str):
        self.out, self.limit, self.cache = out, limit, cache
        self.lock = threading.Lock()
        self.timer: threading.Timer | None = None

    def start(self, phase: str) -> None:
        if self.limit:
            self.timer = threading.Timer(self.limit, self._expire, args=(phase,))
            self.timer.daemon = True
            self.timer.start()

    def stop(self, phase: str, result: dict[str, Any]) -> None:
        """Record a finished run, unless the watchdog has already given it up."""
        with self.lock:
            if self.timer is not None:
                self.timer.cancel()
            self.out[phase] = result

    def _expire(self, phase: str) -> None:
        with self.lock:
            if phase in self.out:  # it finished just in time
                return
            result = dict(self.out)
            for later in PHASES:
                result.setdefault(later, {"status": "timeout", "wall": self.limit if later == phase else 0.0})
            print(json.dumps(result), flush=True)
            shutil.rmtree(self.cache, ignore_errors=True)
            os._exit(0)  # the bench kills the rest of the process group (oracle pool, JVM)


def run(job: dict[str, Any]) -> dict[str, Any]:
    goals = Goals(visit=tuple(job["rooms"]), per_robot=())
    out: dict[str, Any] = {}
    with scratch_folder("bench-") as cache:
        watchdog = Watchdog(out, job.get("planner_timeout"), cache)
        for phase in PHASES:
            if phase != "cold" and out["cold"].get("status") not in SOLVED:
                out[phase] = dict(out["cold"], wall=0.0)
                continue
            encoding, costs, search = variant(job["encoding"])
            options = PlanOptions.of(
                encoding=encoding,
                costs=costs,
                search=search,
                time_budget=job.get("time_budget"),
                planner=job.get("planner"),
                timeout=job.get("planner_timeout"),
                goals=goals,
                cache_dir=Path(cache),
                workers=job.get("workers"),
                replan=phase == "replan",
            )
            start = time.perf_counter()
            watchdog.start(phase)
            memory = PeakMemory()
            try:
                report = plan(job["scenario"], options)
            except TmpnavError as err:
                watchdog.stop(
                    phase, {"status": type(err).__name__, "error": str(err), "wall": time.perf_counter() - start}
                )
                continue
            finally:
                memory.stop()
            watchdog.stop(phase, {**measured(report), "peak_rss_mb": memory.peak_mb})
    return out


def variant(text: str) -> tuple[str, str | None, str | None]:
    """``ENCODING[:COSTS[:SEARCH]]`` (``mixed``, ``mixed:table``, ``mixed:carried:anytime``)."""
    parts = text.split(":")
    return parts[0], (parts[1] or None) if len(parts) > 1 else None, (parts[2] or None) if len(parts) > 2 else None


class PeakMemory:
    """The largest resident memory of this process and all its descendants together (oracle
    workers, ENHSP's JVMs), sampled every 0.2 s from /proc (Linux; elsewhere nothing)."""

    def __init__(self) -> None:
        self.peak = 0
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    @property
    def peak_mb(self) -> float | None:
        return self.peak / 2**20 if self.peak else None

    def stop(self) -> None:
        self._done.set()
        self._thread.join()
        self._sample()

    def _run(self) -> None:
        while not self._done.wait(0.2):
            self._sample()

    def _sample(self) -> None:
        self.peak = max(self.peak, sum(_rss(pid) for pid in _tree(os.getpid())))


def _tree(pid: int) -> list[int]:
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        try:
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as fh:
                    todo.extend(int(c) for c in fh.read().split())
        except OSError:
            continue
    return out


def _rss(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError):
        pass
    return 0


def measured(report: PlanReport) -> dict[str, Any]:
    """What a run reports to the bench: status, stage times, costs, makespan, counters."""
    bound, search = report.task.bound, report.task.search
    return {
        "bound": None if bound is None else bound.value,
        "stopped": None if search is None else f"{search.mode}/{search.costs}/{search.stopped}",
        "status": report.status.value,
        "times": report.times.seconds,
        "planner_cost": report.planner_cost,
        "resimulated_cost": report.resimulated_cost,
        "makespan": report.schedule.makespan,  # s: the re-simulated plan, the robots moving at once
        "actions": len(report.actions),
        "task": asdict(report.task.counts),
        "oracle": report.oracle.as_dict(),
        "plan_cache_hit": report.cache.plan_hit,
    }


def main() -> None:
    from tmpnav.lifetime import Terminated, end_as_terminated, guard

    guard()  # the run's JVMs end with it, when the bench kills it at its time limit too
    try:
        job = json.loads(sys.stdin.read())
        warm_up()
        print(json.dumps(run(job)), flush=True)
    except Terminated:
        end_as_terminated()


if __name__ == "__main__":
    main()
