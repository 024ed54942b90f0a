"""The runs of ``tmpnav bench``: which goals each run plans, and running each in its own process.

For each point (a number of rooms, or of robots) and session, the rooms to visit are drawn
at random from a seed; every encoding asked for plans the same goals in the same world,
one run after the other on this machine, each in its own process (:mod:`.worker`), cold
(empty cache), then warm (cost table and task plan from the cache), then re-planned
(cost table from the cache, the task planner runs again). A run that does not finish
within the time limit is killed and recorded as a timeout.
"""

from __future__ import annotations

import contextlib
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from tmpnav import shipped
from tmpnav.bench.table import BENCH_STAGES, PHASES, Row
from tmpnav.errors import InputError
from tmpnav.lifetime import remove_scratch

#: after this many timeouts at one point, an encoding's later sessions there are not run
GIVE_UP_AFTER = 2

#: one worker's answer: phase -> what it measured (status, times, costs, counters)
WorkerResult = dict[str, dict[str, object]]


def parse_counts(text: str, option: str) -> list[int]:
    """``2..4`` (every count from 2 to 4), ``2..10:2`` (every second one: 2, 4, ..., 10, as the
    paper), or a list ``2,4,6``. A range whose step passes over its end (``2..9:2``) is refused,
    so that the last point is always the one asked for."""
    try:
        if ".." in text:
            span, colon, step_text = text.partition(":")
            lo, hi = (int(v) for v in span.split(".."))
            step = int(step_text) if colon else 1
            if step < 1:
                raise ValueError
            values = list(range(lo, hi + 1, step))
        else:
            values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(
            f"{option} {text!r} is not a range A..B[:STEP] (STEP >= 1) or a list A,B,C of integers"
        ) from None
    if not values or min(values) < 1:
        raise InputError(f"{option} {text!r} must name positive integers")
    if ".." in text and values[-1] != hi:
        raise InputError(
            f"{option} {text!r}: steps of {step} from {lo} stop at {values[-1]}, not {hi}; "
            f"write {lo}..{values[-1]}:{step} or a list"
        )
    return values


def scenario_for(robots: int, override: Path | None) -> Path:
    """The world of a point: ``--scenario`` (``{robots}`` in it is replaced by the number of
    robots; a shipped config may be named configs/NAME.yaml), or the shipped
    configs/corridor-<N>robots.yaml."""
    if override is not None:
        path = shipped.resolve(Path(str(override).replace("{robots}", str(robots))))
        if not path.exists():
            raise InputError(f"--scenario {override}: {path} not found")
        return path
    path = shipped.configs_dir() / f"corridor-{robots}robots.yaml"
    if not path.exists():
        raise InputError(f"no benchmark scenario for {robots} robots ({path.name}); pass --scenario")
    return path


@dataclass(frozen=True)
class Job:
    """One run of the bench: an encoding planning drawn goals in one world."""

    experiment: str
    encoding: str
    robots: int
    rooms: int
    session: int
    goals: tuple[str, ...]
    scenario: Path


def make_jobs(
    experiment: str,
    robots: list[int],
    rooms: list[int],
    sessions: int,
    encodings: list[str],
    seed: int,
    scenario: Path | None,
    room_names: Callable[[Path], list[str]],
) -> list[Job]:
    """Every run of the experiment, goals drawn per (robots, rooms, session) from ``seed``."""
    out = []
    for n_robots in robots:
        path = scenario_for(n_robots, scenario)
        names = room_names(path)
        for n_rooms in rooms:
            if n_rooms > len(names):
                raise InputError(f"--rooms {n_rooms}: {path.name} has only {len(names)} rooms")
            for s in range(sessions):
                rnd = random.Random(f"{seed}/{n_robots}/{n_rooms}/{s}")
                goals = tuple(sorted(rnd.sample(names, n_rooms), key=lambda r: names.index(r)))
                for enc in encodings:
                    out.append(Job(experiment, enc, n_robots, n_rooms, s, goals, path))
    return out


def run_job(job: Job, timeout: float, workers: int | None, time_budget: float | None = None) -> WorkerResult:
    """Run one job's three phases in a worker process; a run past the limit is a timeout."""
    payload = {
        "scenario": str(job.scenario),
        "rooms": list(job.goals),
        "encoding": job.encoding,  # a variant: ENCODING[:COSTS[:SEARCH]]
        "planner_timeout": timeout,
        "workers": workers,
        "time_budget": time_budget,
    }
    # Its own session, so that a run killed at its time limit (or by Ctrl-C) takes its
    # oracle worker processes and its JVM with it. Its output goes to files, not pipes: a
    # worker that gives up (tmpnav.bench.worker's watchdog) exits at once, while the
    # processes it leaves would hold a pipe open until they are killed.
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(
            [sys.executable, "-m", "tmpnav.bench.worker"],
            stdin=subprocess.PIPE,
            stdout=out,
            stderr=err,
            text=True,
            env=dict(os.environ),
            start_new_session=True,
        )
        try:
            proc.communicate(json.dumps(payload), timeout=len(PHASES) * timeout + 60)
        except subprocess.TimeoutExpired:
            kill_group(proc)
            return {phase: {"status": "timeout"} for phase in PHASES}
        except BaseException:
            kill_group(proc)
            raise
        kill_group(proc)  # the run is over; nothing of it may outlive it
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    lines = [ln for ln in stdout.splitlines() if ln.startswith("{")]
    if proc.returncode != 0 or not lines:
        tail = (stderr.strip().splitlines() or ["no output"])[-1]
        return {phase: {"status": "error", "error": tail} for phase in PHASES}
    result: WorkerResult = json.loads(lines[-1])
    for phase in PHASES:
        if result[phase].get("status") == "PlannerTimeoutError":
            result[phase]["status"] = "timeout"
    return result


def kill_group(proc: subprocess.Popen[str]) -> None:
    """Kill a run's whole process group (the worker and its oracle pool), reap it, and remove
    the worker's temporary files (its cache; ENHSP's files of a search still under way)."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()
    remove_scratch(pid=proc.pid)


def rows(job: Job, result: WorkerResult) -> list[Row]:
    """The bench.csv rows of one job: one per phase."""
    out = []
    for phase in PHASES:
        r = result.get(phase, {"status": "missing"})
        times, oracle, task = (_mapping(r.get(k)) for k in ("times", "oracle", "task"))
        row = {
            "experiment": job.experiment,
            "encoding": job.encoding,
            "robots": job.robots,
            "rooms": job.rooms,
            "session": job.session,
            "goals": " ".join(job.goals),
            "phase": phase,
            "status": r.get("status"),
            **{f"{s}_s": _num(times.get(s)) for s in BENCH_STAGES},
            "planner_cost": _num(r.get("planner_cost")),
            "resimulated_cost": _num(r.get("resimulated_cost")),
            "actions": r.get("actions"),
            "pair_actions": task.get("pair_actions"),
            "joint_simulations": oracle.get("joint_simulations"),
            "joint_factorized": oracle.get("joint_factorized"),
            "table_cache_hit": oracle.get("table_cache_hit"),
            "plan_cache_hit": r.get("plan_cache_hit"),
            "peak_rss_mb": _num(r.get("peak_rss_mb")),
            "bound": _num(r.get("bound")),
            "stopped": r.get("stopped"),
            "makespan": _num(r.get("makespan")),
        }
        out.append({k: "" if v is None else str(v) for k, v in row.items()})
    return out


def _mapping(value: object) -> dict[str, object]:
    return value if isinstance(value, dict) else {}


def _num(v: object) -> str:
    return f"{float(v):.6g}" if isinstance(v, int | float) else ""


def run_jobs(
    job_list: list[Job],
    timeout: float,
    workers: int | None,
    progress: Callable[[str], None] | None = None,
    time_budget: float | None = None,
) -> list[Row]:
    """Run the jobs one after the other (timings on a shared machine would not mean much
    otherwise). A point where an encoding already timed out GIVE_UP_AFTER times records
    its remaining sessions as timeouts without running them, so that a hopeless point
    (the paper's encoding with six robots) costs minutes, not hours."""
    table: list[Row] = []
    timeouts: dict[tuple[str, int, int], int] = {}
    for k, job in enumerate(job_list):
        start = time.perf_counter()
        point = (job.encoding, job.robots, job.rooms)
        result: WorkerResult
        if timeouts.get(point, 0) >= GIVE_UP_AFTER:
            result = {phase: {"status": "timeout"} for phase in PHASES}
        else:
            result = run_job(job, timeout, workers, time_budget)
            if result["cold"].get("status") == "timeout":
                timeouts[point] = timeouts.get(point, 0) + 1
        new = rows(job, result)
        table.extend(new)
        if progress:
            phases = ", ".join(f"{row['phase']} {_fmt(row)}" for row in new)
            progress(
                f"bench {k + 1}/{len(job_list)}: {job.encoding}, {job.robots} robots, {job.rooms} rooms, "
                f"session {job.session + 1}: {phases} ({time.perf_counter() - start:.0f} s)"
            )
    return table


def _fmt(row: Row) -> str:
    return f"{float(row['total_s']):.2f} s" if row["status"].startswith("solved") else row["status"]
