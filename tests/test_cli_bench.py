"""Smoke runs of ``tmpnav bench`` and ``tmpnav simulate`` (CI).

Every bench run is a worker process that first warms up (two plans of a tiny scenario) and then
plans cold, warm and again: some 8-10 s each on a loaded machine. So each test runs as few as
show its point: two encodings at one point, two team sizes, one session each.
"""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def tmpnav(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "tmpnav", *args], capture_output=True, text=True, cwd=ROOT, timeout=900
    )


@pytest.mark.slow
def test_bench_rooms_compares_encodings(tmp_path: Path) -> None:
    proc = tmpnav(
        "bench",
        "--scenario",
        "configs/two-rooms.yaml",
        "--rooms",
        "2",  # one point (every count of a range: test_bench_rooms_2_to_3_runs_every_size_from_2_to_3)
        "--sessions",
        "1",  # each session its own goals: tests/bench/test_runs.py
        "--encoding",
        "mixed",
        "--encoding",
        "paper",
        "--run-timeout",
        "120",
        "-o",
        str(tmp_path),
        "-q",
    )
    assert proc.returncode == 0, proc.stderr
    rows = list(csv.DictReader((tmp_path / "bench.csv").open()))
    assert len(rows) == 1 * 1 * 2 * 3  # points x sessions x encodings x (cold, warm, replan)
    assert len({r["goals"] for r in rows}) == 1  # both encodings plan the same goals
    assert all(r["status"].startswith("solved") for r in rows), rows
    # the paper's encoding costs the whole table first (cached as one entry); mixed, with
    # carried costs by default, costs what its search asks for (each answer cached)
    assert all(
        r["table_cache_hit"] == "True" for r in rows if r["phase"] in ("warm", "replan") and r["encoding"] == "paper"
    )
    assert all(r["plan_cache_hit"] == "True" for r in rows if r["phase"] == "warm")
    assert all(r["plan_cache_hit"] == "False" for r in rows if r["phase"] in ("cold", "replan"))
    costs: dict[tuple[str, str, str], set[str]] = {}
    for r in rows:  # the cache never changes the plan
        costs.setdefault((r["encoding"], r["rooms"], r["session"]), set()).add(r["planner_cost"])
    assert all(len(v) == 1 for v in costs.values()), costs
    assert (tmp_path / "bench.png").stat().st_size > 0
    summary = (tmp_path / "summary.md").read_text()
    assert "speed-up of mixed" in summary and "| paper |" in summary


@pytest.mark.slow
def test_bench_robots(tmp_path: Path) -> None:
    proc = tmpnav(
        "bench",
        "--robots",
        "2,3",
        "--rooms",
        "2",
        "--sessions",
        "1",
        "--scenario",
        "configs/corridor-{robots}robots.yaml",
        "--run-timeout",
        "120",
        "-o",
        str(tmp_path),
        "-q",
    )
    assert proc.returncode == 0, proc.stderr
    rows = list(csv.DictReader((tmp_path / "bench.csv").open()))
    assert {r["robots"] for r in rows} == {"2", "3"}
    assert all(r["status"].startswith("solved") for r in rows)
    assert all(float(r["makespan"]) > 0.0 for r in rows)  # the robots moving at once, next to cost and time
    assert "| makespan (s) |" in (tmp_path / "summary.md").read_text()


@pytest.mark.slow
def test_bench_rooms_2_to_3_runs_every_size_from_2_to_3(tmp_path: Path) -> None:
    proc = tmpnav("bench", "--rooms", "2..3", "--sessions", "1", "-o", str(tmp_path), "-q")
    assert proc.returncode == 0, proc.stderr
    rows = list(csv.DictReader((tmp_path / "bench.csv").open()))
    assert sorted({int(r["rooms"]) for r in rows}) == [2, 3]
    table = [line for line in proc.stdout.splitlines() if line.startswith("|")]
    assert len(table) == 2 + 2 * 3  # header, rule, 2 sizes x (cold, warm, replan)
    assert "speed-up" not in proc.stdout  # one encoding: nothing to compare, no empty column
    assert not [line for line in table if "||" in line.replace(" ", "")]


def test_bench_rejects_bad_ranges(tmp_path: Path) -> None:
    proc = tmpnav("bench", "--rooms", "two..ten", "-o", str(tmp_path))
    assert proc.returncode == 2
    assert proc.stderr.startswith("error: --rooms 'two..ten'")


@pytest.mark.slow
def test_simulate_two_sessions(tmp_path: Path) -> None:
    proc = tmpnav("simulate", "configs/corridor.yaml", "--sessions", "2", "--no-cache", "-o", str(tmp_path), "-q")
    assert proc.returncode == 0, proc.stderr
    assert "lower with mutual observations" in proc.stdout
    rows = list(csv.DictReader((tmp_path / "errors.csv").open()))
    assert {r["config"] for r in rows} == {"1", "2"}
    assert all(float(r["mean_error_m"]) >= 0 for r in rows)


@pytest.mark.slow
def test_a_run_past_the_time_limit_is_a_timeout_and_leaves_nothing_behind(tmp_path: Path) -> None:
    """The limit holds for the whole run (here it ends in the oracle, long before ENHSP):
    the worker gives up at the limit instead of the bench waiting for its backstop, and the
    oracle's worker processes go with it."""
    args = ("bench", "--rooms", "10", "--sessions", "1", "--timeout", "0.5", "-o", str(tmp_path), "-q")
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,  # the old backstop alone was 61.5 s
    )
    assert proc.returncode == 0, proc.stderr
    rows = list(csv.DictReader((tmp_path / "bench.csv").open()))
    assert [r["status"] for r in rows] == ["timeout"] * 3
    leftovers = subprocess.run(["pgrep", "-f", "tmpnav.bench.worker"], capture_output=True, text=True).stdout
    assert leftovers.strip() == ""
