"""``tmpnav bench`` internals: a run killed at its time limit leaves no process behind."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tmpnav.bench.bench import COLUMNS, PHASES, _kill_group, read_csv, summary, to_csv
from tmpnav.errors import InputError

#: a run that starts a helper process (as the oracle starts its worker pool) and hangs
HANGING_RUN = (
    "import subprocess, sys, time\n"
    "helper = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(300)'])\n"
    "print(helper.pid, flush=True)\n"
    "time.sleep(300)\n"
)


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a killed process that is not reaped yet is a zombie: dead for our purpose
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


def test_killing_a_run_kills_the_processes_it_started() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-c", HANGING_RUN],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    assert proc.stdout is not None
    helper = int(proc.stdout.readline())
    assert alive(helper)
    _kill_group(proc)
    deadline = time.monotonic() + 10
    while alive(helper) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not alive(helper)
    assert proc.returncode is not None


def row(encoding: str, phase: str, status: str, total: str, session: int = 0) -> dict[str, str]:
    base = dict.fromkeys(COLUMNS, "")
    stages = dict.fromkeys((f"{s}_s" for s in ("roadmap", "oracle", "encode", "planner", "resimulate")), "0.1")
    return {
        **base,
        **(stages if total else {}),
        "experiment": "robots",
        "encoding": encoding,
        "robots": "4",
        "rooms": "8",
        "session": str(session),
        "phase": phase,
        "status": status,
        "total_s": total,
    }


def test_a_timed_out_encoding_shows_a_lower_bound_cold_and_not_run_otherwise() -> None:
    table = [row("mixed", phase, "solved-optimally", "2.0") for phase in PHASES]
    table += [row("paper", phase, "timeout", "") for phase in PHASES]
    text = summary(table, "robots", default="mixed", timeout=60.0)
    lines = {tuple(c.strip() for c in line.split("|")[2:4]): line for line in text.splitlines()[2:]}
    assert "> 30x (timeout)" in lines[("paper", "cold")]
    assert "not run: the cold runs timed out" in lines[("paper", "warm")]
    assert "not run" in lines[("paper", "replan")] and "timeout |" not in lines[("paper", "replan")]


def test_read_csv_round_trips_and_rejects_other_files(tmp_path: Path) -> None:
    table = [row("mixed", phase, "solved-optimally", "2.0") for phase in PHASES]
    path = tmp_path / "bench.csv"
    path.write_text(to_csv(table))
    assert read_csv(path) == table
    other = tmp_path / "other.csv"
    other.write_text("a,b\n1,2\n")
    with pytest.raises(InputError, match=r"is not a tmpnav bench\.csv"):
        read_csv(other)
    with pytest.raises(InputError, match="cannot read"):
        read_csv(tmp_path / "missing.csv")
