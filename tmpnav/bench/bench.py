"""``tmpnav bench``: planning time against the number of rooms or robots (paper, Fig. 3(b), (c)).

For each point (a number of rooms, or of robots) and session, the rooms to visit are drawn
at random from a seed; every encoding asked for plans the same goals in the same world,
one run after the other on this machine, each in its own process (:mod:`worker`), cold
(empty cache), then warm (cost table and task plan from the cache), then re-planned
(cost table from the cache, the task planner runs again). A run that does not finish
within the time limit is killed and recorded as a timeout.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tmpnav.errors import InputError

#: cold: empty cache; warm: everything cached; replan: costs cached, the planner runs again
PHASES = ("cold", "warm", "replan")
CONFIGS = Path(__file__).resolve().parents[2] / "configs"
STAGES = ("roadmap", "oracle", "encode", "planner", "resimulate", "total")
COLUMNS = (
    "experiment",
    "encoding",
    "robots",
    "rooms",
    "session",
    "goals",
    "phase",
    "status",
    *(f"{s}_s" for s in STAGES),
    "planner_cost",
    "resimulated_cost",
    "actions",
    "pair_actions",
    "joint_simulations",
    "joint_factorized",
    "table_cache_hit",
    "plan_cache_hit",
)


def parse_counts(text: str, option: str) -> list[int]:
    """``2..10`` (every second number, as the paper), ``2..10:1``, or ``2,4,6``."""
    try:
        if ".." in text:
            span, _, step = text.partition(":")
            lo, hi = (int(v) for v in span.split(".."))
            values = list(range(lo, hi + 1, int(step) if step else 2))
        else:
            values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise InputError(f"{option} {text!r} is not a range A..B[:STEP] or a list A,B,C of integers") from None
    if not values or min(values) < 1:
        raise InputError(f"{option} {text!r} must name positive integers")
    return values


def scenario_for(robots: int, override: Path | None) -> Path:
    """The world of a point: ``--scenario`` (``{robots}`` in it is replaced by the number of
    robots), or configs/corridor-<N>robots.yaml."""
    if override is not None:
        path = Path(str(override).replace("{robots}", str(robots)))
        if not path.exists():
            raise InputError(f"--scenario {override}: {path} not found")
        return path
    path = CONFIGS / f"corridor-{robots}robots.yaml"
    if not path.exists():
        raise InputError(f"no benchmark scenario for {robots} robots ({path.name}); pass --scenario")
    return path


@dataclass(frozen=True)
class Job:
    experiment: str
    encoding: str
    robots: int
    rooms: int
    session: int
    goals: tuple[str, ...]
    scenario: Path


def jobs(
    experiment: str,
    robots: list[int],
    rooms: list[int],
    sessions: int,
    encodings: list[str],
    seed: int,
    scenario: Path | None,
    room_names: Callable[[Path], list[str]],
) -> list[Job]:
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


def run_job(job: Job, timeout: float, workers: int | None) -> dict[str, Any]:
    payload = {
        "scenario": str(job.scenario),
        "rooms": list(job.goals),
        "encoding": job.encoding,
        "planner_timeout": timeout,
        "workers": workers,
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
            _kill_group(proc)
            return {phase: {"status": "timeout"} for phase in PHASES}
        except BaseException:
            _kill_group(proc)
            raise
        _kill_group(proc)  # the run is over; nothing of it may outlive it
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    lines = [ln for ln in stdout.splitlines() if ln.startswith("{")]
    if proc.returncode != 0 or not lines:
        tail = (stderr.strip().splitlines() or ["no output"])[-1]
        return {phase: {"status": "error", "error": tail} for phase in PHASES}
    result: dict[str, Any] = json.loads(lines[-1])
    for phase in PHASES:
        if result[phase].get("status") == "PlannerTimeoutError":
            result[phase]["status"] = "timeout"
    return result


def _kill_group(proc: subprocess.Popen[str]) -> None:
    """Kill a run's whole process group (the worker and its oracle pool) and reap it."""
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, signal.SIGKILL)
    proc.communicate()


def rows(job: Job, result: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    for phase in PHASES:
        r = result.get(phase, {"status": "missing"})
        times = r.get("times", {})
        oracle = r.get("oracle", {})
        task = r.get("task", {})
        out.append(
            {
                "experiment": job.experiment,
                "encoding": job.encoding,
                "robots": job.robots,
                "rooms": job.rooms,
                "session": job.session,
                "goals": " ".join(job.goals),
                "phase": phase,
                "status": r.get("status"),
                **{f"{s}_s": _num(times.get(s)) for s in STAGES},
                "planner_cost": _num(r.get("planner_cost")),
                "resimulated_cost": _num(r.get("resimulated_cost")),
                "actions": r.get("actions", ""),
                "pair_actions": task.get("pair_actions", ""),
                "joint_simulations": oracle.get("joint_simulations", ""),
                "joint_factorized": oracle.get("joint_factorized", ""),
                "table_cache_hit": oracle.get("table_cache_hit", ""),
                "plan_cache_hit": r.get("plan_cache_hit", ""),
            }
        )
    return out


def _num(v: Any) -> str:
    return "" if v is None else f"{float(v):.6g}"


#: after this many timeouts at one point, an encoding's later sessions there are not run
GIVE_UP_AFTER = 2


def run_bench(
    job_list: list[Job], timeout: float, workers: int | None, progress: Callable[[str], None] | None = None
) -> list[dict[str, Any]]:
    """Run the jobs one after the other (timings on a shared machine would not mean much
    otherwise). A point where an encoding already timed out GIVE_UP_AFTER times records
    its remaining sessions as timeouts without running them, so that a hopeless point
    (the paper's encoding with six robots) costs minutes, not hours."""
    table: list[dict[str, Any]] = []
    timeouts: dict[tuple[str, int, int], int] = {}
    for k, job in enumerate(job_list):
        start = time.perf_counter()
        point = (job.encoding, job.robots, job.rooms)
        result: dict[str, Any]
        if timeouts.get(point, 0) >= GIVE_UP_AFTER:
            result = {**{phase: {"status": "timeout"} for phase in PHASES}, "skipped": True}
        else:
            result = run_job(job, timeout, workers)
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


def _fmt(row: dict[str, Any]) -> str:
    return f"{float(row['total_s']):.2f} s" if row["status"].startswith("solved") else str(row["status"])


def read_csv(path: Path) -> list[dict[str, Any]]:
    """The rows of a bench.csv written by :func:`to_csv` (for ``tmpnav bench --replot``)."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            table = list(reader)
            header = reader.fieldnames or []
    except OSError as err:
        raise InputError(f"--replot: cannot read {path}: {err.strerror}") from None
    missing = [c for c in COLUMNS if c not in header]
    if missing or not table:
        what = f"misses the columns {', '.join(missing)}" if missing else "has no rows"
        raise InputError(f"--replot: {path} is not a tmpnav bench.csv: it {what}")
    return table


def to_csv(table: list[dict[str, Any]]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(table)
    return buffer.getvalue()


def medians(table: list[dict[str, Any]], axis: str) -> dict[tuple[str, str, int], dict[str, Any]]:
    """(encoding, phase, point) -> median total and stages over the solved sessions."""
    out: dict[tuple[str, str, int], dict[str, Any]] = {}
    keys = sorted({(r["encoding"], r["phase"], int(r[axis])) for r in table})
    for enc, phase, point in keys:
        runs = [r for r in table if r["encoding"] == enc and r["phase"] == phase and int(r[axis]) == point]
        ok = [r for r in runs if str(r["status"]).startswith("solved")]
        entry: dict[str, Any] = {
            "runs": len(runs),
            "solved": len(ok),
            "timeouts": sum(r["status"] == "timeout" for r in runs),
        }
        for s in STAGES:
            vals = [float(r[f"{s}_s"]) for r in ok if r[f"{s}_s"] != ""]
            entry[s] = statistics.median(vals) if vals else None
        totals = sorted(float(r["total_s"]) for r in ok)
        entry["q1"] = totals[len(totals) // 4] if totals else None
        entry["q3"] = totals[(3 * len(totals)) // 4] if totals else None
        out[(enc, phase, point)] = entry
    return out


def summary(table: list[dict[str, Any]], axis: str, default: str = "mixed", timeout: float | None = None) -> str:
    """A Markdown table of medians per point, with the speed-up of ``default`` over the others.

    Where another encoding never finished, its speed-up is a lower bound: the time limit
    over ``default``'s median."""
    med = medians(table, axis)
    encodings = sorted({k[0] for k in med})
    points = sorted({k[2] for k in med})
    label = "rooms" if axis == "rooms" else "robots"
    lines = [
        f"| {label} | encoding | cache | solved | median total (s) | roadmap | oracle | encode | planner "
        f"| speed-up of {default} |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for point in points:
        for enc in encodings:
            for phase in PHASES:
                e = med.get((enc, phase, point))
                if e is None:
                    continue
                mine = med.get((default, phase, point), {}).get("total")
                not_run = e["solved"] == 0 and phase != "cold"  # a cold run past the limit skips the others
                cells = [_s(e.get(s)) for s in ("total", "roadmap", "oracle", "encode", "planner")]
                ratio = ""
                if not_run:
                    ratio, cells = "not run: the cold runs timed out", ["-"] * len(cells)
                elif enc != default and mine and e["total"]:
                    ratio = f"{e['total'] / mine:.1f}x"
                elif enc != default and mine and e["solved"] == 0:
                    ratio = f"> {timeout / mine:.0f}x (timeout)" if timeout else "> timeout"
                lines.append(
                    f"| {point} | {enc} | {phase} | {e['solved']}/{e['runs']} | " + " | ".join(cells) + f" | {ratio} |"
                )
    return "\n".join(lines) + "\n"


def _s(v: float | None) -> str:
    return "timeout" if v is None else f"{v:.2f}"


def write_atomic(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(fd, "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(tmp, path)
