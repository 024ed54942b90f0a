"""``tmpnav bench`` internals: a run killed at its time limit leaves no process behind."""

from __future__ import annotations

import os
import subprocess
import sys
import time

from tmpnav.bench.runs import kill_group

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
    kill_group(proc)
    deadline = time.monotonic() + 10
    while alive(helper) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not alive(helper)
    assert proc.returncode is not None
