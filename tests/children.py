"""What the tests' child processes start with."""

from __future__ import annotations

import signal


def sigint_default() -> None:
    """In a child (``preexec_fn``), SIGINT as a shell's foreground job has it: a suite started in
    the background (``make test &``, ``nohup``) passes SIGINT on ignored, and Python then never
    raises KeyboardInterrupt in the child, which the tests of interrupted runs send it."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
