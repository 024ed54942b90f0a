"""``python -m tmpnav`` is the same as the ``tmpnav`` command (whose entry point is :func:`main`)."""

import os
import signal
import sys
import time


def main() -> None:
    """The command line, loaded here so that a Ctrl-C while it loads is one line too, and
    ended by :func:`_end`. A time limit counts from here (tmpnav.deadline.COMMAND_STARTED)."""
    started = time.perf_counter()
    import tmpnav.deadline

    tmpnav.deadline.COMMAND_STARTED = started
    try:
        from tmpnav.cli import main as run
    except KeyboardInterrupt:
        sys.stderr.write("error: interrupted\n")
        sys.exit(130)
    try:
        run()
    except SystemExit as done:
        _end(done.code)
    _end(0)


def _end(code: object) -> None:
    """End the process with the run's exit ``code`` (as ``sys.exit`` takes it) once the run is
    over: Python's exit handlers run as at any exit (ENHSP's server ended: tmpnav.task.enhsp_jvm;
    multiprocessing's and the temporary files' clean-up), the output is flushed, and the
    process ends without unloading its modules, which frees nothing the system does not and
    took about 0.3 s (numba, LLVM, OR-Tools, SciPy). The run's files are written and closed
    by then (tmpnav.atomic). A signal from here on ends the process at once, as it ends any
    program that has finished its work."""
    import atexit

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_DFL)
    if code is None:
        status = 0
    elif isinstance(code, int):
        status = code
    else:
        sys.stderr.write(f"{code}\n")
        status = 1
    atexit._run_exitfuncs()
    _flush_and_exit(status)


def _flush_and_exit(status: int) -> None:
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (tmpnav plan | head): nothing to add
            status = status or 1 if stream is sys.stdout else status
    os._exit(status)


if __name__ == "__main__":
    main()
