"""What the tests' child processes start with."""

from __future__ import annotations

import signal
import subprocess
import sys


def sigint_default() -> None:
    """In a child (``preexec_fn``), SIGINT as a shell's foreground job has it: a suite started in
    the background (``make test &``, ``nohup``) passes SIGINT on ignored, and Python then never
    raises KeyboardInterrupt in the child, which the tests of interrupted runs send it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def run_python(script: str, timeout: float) -> subprocess.CompletedProcess[str]:
    """``script`` run by this Python in a child, its output captured, SIGINT as a foreground job has it."""
    return subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=timeout, preexec_fn=sigint_default
    )


def start_python(script: str) -> subprocess.Popen[str]:
    """``script`` started by this Python in a child, its stdout a pipe, SIGINT as a foreground job has it."""
    return subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, preexec_fn=sigint_default
    )
