"""No process outlives the tmpnav run that started it, however the run ends.

A run starts processes whose start it does not control: ENHSP's JVM (unified-planning
starts it in a session of its own, so neither Ctrl-C in the terminal nor a signal to
tmpnav's process group reaches it), Ray's local instance, the bench's runs. When tmpnav
ends by a signal it cannot catch (SIGKILL, the out-of-memory killer), or by one it can
but while the JVM runs, nothing in tmpnav is left to stop them: the JVM searched on,
holding hundreds of MB, until its own time limit.

So the command line marks each run (:func:`guard`): an environment variable holding a
token of the run, which every program it starts inherits, and a small sentinel process,
started first, in a session of its own (signals to tmpnav's process group leave it
alone). Linux tells the sentinel when the run's process ends, whatever the cause (the
parent-death signal); the sentinel then kills every process that still carries the
run's token, and exits. After a normal end there are none, and it exits at once. The
oracle's forked workers do not exec, so they keep the environment tmpnav started with:
they end with tmpnav by their own parent-death signal (tmpnav.oracle.executors).

SIGTERM becomes :class:`Terminated`, raised in the main thread like Ctrl-C's
KeyboardInterrupt, so that a terminated run cleans up as an interrupted one does (the
oracle's workers stopped, temporary output files removed, the earlier outputs kept).

Either signal is also remembered (:func:`signalled`): Python raises the signal's exception
wherever the main thread is, and some code turns it into another one or drops it. A C
extension being imported at that instant (matplotlib's, for the figure) fails as
``ImportError: initialization failed``; a library may catch it with ``except Exception``.
The command line reports any exception after a signal as that signal's end, and the
all-or-nothing writes (tmpnav.atomic) call :func:`check_signals` before they commit, so a
run whose interrupt was swallowed still ends as interrupted, its earlier outputs kept.
The cleanup is bounded: a second SIGTERM, or CLEANUP_SECONDS after the first, ends the
process at once. Forked children (the oracle's workers) start with SIGTERM's default.

Temporary files (ENHSP's PDDL and plan files, the bench's caches) go in one scratch folder
per process (:func:`scratch`), named with the run's token and the process id, and removed at
the process's exit. A process that ends without its exit handlers (SIGKILL; ``os._exit``,
which the command line and the bench's worker end with, while a search in the background
still holds its files) used to leave them: 74 folders of ENHSP's files and a 56 MB bench
cache were found in /tmp after a day of tests and benchmarks. Now the sentinel removes the
run's scratch folders after it has ended the run's processes, and the bench removes a
worker's after it kills the worker's process group (:func:`remove_scratch`).

The sentinel needs Linux (prctl and /proc); elsewhere :func:`guard` only handles SIGTERM.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import os
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Collection, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, wait
from pathlib import Path
from types import FrameType
from typing import TypeVar

#: the environment variable that marks the processes of a run
ENV = "TMPNAV_RUN"
#: prctl(2) option: the signal a process gets when its parent ends (Linux)
PR_SET_PDEATHSIG = 1
#: the sentinel learns of the run's end by this signal (blocked, then waited for)
DEATH_SIGNAL = signal.SIGUSR1
#: seconds a terminated run may take to clean up before it ends regardless
CLEANUP_SECONDS = 10.0
#: seconds between the main thread's looks at signals while it waits for other threads' work
SIGNAL_POLL = 0.1

T = TypeVar("T")

_sentinel: subprocess.Popen[bytes] | None = None
#: this process's scratch folder once made (the process id: a forked child makes its own)
_scratch: tuple[int, Path] | None = None
_scratch_lock = threading.Lock()
#: the signal (SIGINT or SIGTERM) that asked this run to end, once one has
_signalled: signal.Signals | None = None
#: blocks of :func:`signals_held` running now, and whether a signal's exception waits for their end
_holding = 0
_deferred = False


class Terminated(BaseException):
    """SIGTERM arrived: end the run as Ctrl-C would, then end as terminated by SIGTERM.

    A BaseException, like KeyboardInterrupt and SystemExit, so that ``except Exception``
    does not swallow it."""


def guard() -> None:
    """Mark this process as a run: SIGTERM raises :class:`Terminated`, and (on Linux) a
    sentinel ends the processes the run started once the run's process ends.

    For command-line entry points, called first, before any thread starts; once per process.
    """
    if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:  # a process told to ignore SIGTERM keeps ignoring it
        signal.signal(signal.SIGTERM, _raise_terminated)
        os.register_at_fork(after_in_child=_default_sigterm)
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # likewise for SIGINT
        signal.signal(signal.SIGINT, _raise_interrupted)
        os.register_at_fork(after_in_child=_default_sigint)
    sys.unraisablehook = _quiet_when_signalled(sys.unraisablehook)
    _start_sentinel()


def _quiet_when_signalled(
    previous: Callable[[sys.UnraisableHookArgs], object],
) -> Callable[[sys.UnraisableHookArgs], None]:
    """An unraisable-exception hook that says nothing of the signal's own exception.

    Raised where Python cannot propagate it (a weakref callback, such as importlib's module
    locks', or a ``__del__``), KeyboardInterrupt or Terminated is printed as "Exception
    ignored in ..." with a traceback, and dropped. The signal is remembered all the same
    (:func:`signalled`), and the run ends as that signal asked (:func:`check_signals`), so the
    traceback is noise on a user's terminal. Any other exception goes to ``previous``."""

    def hook(unraisable: sys.UnraisableHookArgs) -> None:
        if _signalled is not None and isinstance(unraisable.exc_value, KeyboardInterrupt | Terminated):
            return
        previous(unraisable)

    return hook


def signalled() -> signal.Signals | None:
    """The signal (SIGINT or SIGTERM) that asked this run to end, or None."""
    return _signalled


def check_signals() -> None:
    """Raise the exception of a signal that arrived, in case the code that was running when
    it did swallowed it (see the module docstring); nothing when no signal came."""
    global _deferred
    if _signalled is not None:
        _deferred = False  # raised here: the end of a held block need not raise it again
    if _signalled == signal.SIGINT:
        raise KeyboardInterrupt
    if _signalled == signal.SIGTERM:
        raise Terminated()


def _raise_interrupted(signum: int, frame: FrameType | None) -> None:
    """Ctrl-C: Python's own KeyboardInterrupt, remembered (raised when a held block ends,
    :func:`signals_held`, if one is running)."""
    global _signalled, _deferred
    _signalled = _signalled or signal.SIGINT
    if _holding:
        _deferred = True
        return
    raise KeyboardInterrupt


def _default_sigint() -> None:
    with contextlib.suppress(ValueError):
        signal.signal(signal.SIGINT, signal.default_int_handler)


def _raise_terminated(signum: int, frame: FrameType | None) -> None:
    """The first SIGTERM: unwind (Terminated), within CLEANUP_SECONDS; the next one kills."""
    global _signalled, _deferred
    _signalled = signal.SIGTERM
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    timer = threading.Timer(CLEANUP_SECONDS, os.kill, (os.getpid(), signal.SIGTERM))
    timer.daemon = True
    timer.start()
    if _holding:
        _deferred = True
        return
    raise Terminated()


def _default_sigterm() -> None:
    with contextlib.suppress(ValueError):  # not the main thread: cannot happen after fork
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def end_as_terminated() -> None:
    """End this process as SIGTERM's default action does (its parent sees "killed by SIGTERM")."""
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    os.kill(os.getpid(), signal.SIGTERM)
    time.sleep(5)  # the signal is delivered at once; never reached in practice
    os._exit(128 + signal.SIGTERM)


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM while this thread forks: CPython runs its at-fork handlers
    (logging's, threading's) right after fork(), and KeyboardInterrupt or Terminated raised
    in one of them is printed as "Exception ignored" and lost; the run went on to its end.
    Held, a signal is delivered when the block ends, to ordinary code. The kernel may give
    it to another thread meanwhile (one reading ENHSP's answers, or waiting for a search),
    and Python then runs its handler in this thread all the same, inside the block: the
    handler only remembers the signal, and its exception is raised when the block ends (a
    fault-injection run interrupted while its workers forked ran on to its end, remembering
    its plan)."""
    global _holding, _deferred
    held = {signal.SIGINT, signal.SIGTERM}
    if threading.current_thread() is not threading.main_thread():
        yield  # Python runs signal handlers in the main thread only
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    _holding += 1
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)
        _holding -= 1
    if not _holding and _deferred:
        _deferred = False
        check_signals()


def gather(futures: Sequence[Future[T]]) -> Iterator[T]:
    """The results of ``futures``, in their order, waited for in short slices.

    A process-directed signal is given by the kernel to any thread that does not block it:
    one of a pool's threads, or one waiting for an ENHSP search. Its handler (KeyboardInterrupt,
    :class:`Terminated`) then runs when the main thread next runs Python code, which an
    untimed wait (``Future.result()``, ``Executor.map``) never does until its work ends: a
    Ctrl-C waited for a search's time limit. Waited for in slices of SIGNAL_POLL seconds,
    it is raised within that."""
    for future in futures:
        while not wait([future], timeout=SIGNAL_POLL).done:
            pass
        yield future.result()


def first_done(futures: Collection[Future[T]]) -> set[Future[T]]:
    """Those of ``futures`` done once one of them is, waited for in slices as :func:`gather` waits."""
    while True:
        done, _ = wait(futures, timeout=SIGNAL_POLL, return_when=FIRST_COMPLETED)
        if done:
            return done


def _start_sentinel() -> None:
    global _sentinel
    if _sentinel is not None or not sys.platform.startswith("linux") or not Path("/proc/self/environ").exists():
        return
    token = f"{os.getpid()}-{secrets.token_hex(8)}"
    try:
        # no pre-exec function: Python code between fork and exec can hang on a lock that
        # another thread (numpy's BLAS pool, started at import) held at the fork
        _sentinel = subprocess.Popen(
            [sys.executable, "-m", "tmpnav.lifetime", token, str(os.getpid())],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            close_fds=True,
            start_new_session=True,
        )
    except OSError:  # no sentinel (no memory, no processes left): the run goes on unguarded
        return
    os.environ[ENV] = token  # after the sentinel started: it does not carry the token itself


def scratch() -> Path:
    """This process's folder for temporary files, made on first use in the system's temporary
    folder (``TMPDIR``) as ``tmpnav-run-<token>-p<pid>-<random>`` (``tmpnav-p<pid>-<random>``
    outside a guarded run), removed at the process's exit (see the module docstring)."""
    global _scratch
    with _scratch_lock:
        if _scratch is None or _scratch[0] != os.getpid():
            token = os.environ.get(ENV)
            prefix = f"tmpnav-run-{token}-p{os.getpid()}-" if token else f"tmpnav-p{os.getpid()}-"
            _scratch = (os.getpid(), Path(tempfile.mkdtemp(prefix=prefix)))
        return _scratch[1]


@contextlib.contextmanager
def scratch_folder(prefix: str) -> Iterator[str]:
    """A new folder in :func:`scratch`, removed when the block ends (as far as it can be: a
    file still held open elsewhere goes with the scratch folder at exit)."""
    with tempfile.TemporaryDirectory(prefix=prefix, dir=scratch(), ignore_cleanup_errors=True) as folder:
        yield folder


def remove_scratch(token: str | None = None, pid: int | None = None) -> int:
    """Remove the scratch folders of the run ``token`` or of the process ``pid`` (another
    process, ended); returns how many were removed."""
    if token is not None:
        pattern = f"tmpnav-run-{token}-p*"
    elif pid is not None:
        pattern = f"tmpnav-*p{pid}-*"
    else:
        return 0
    found = [p for p in Path(tempfile.gettempdir()).glob(pattern) if p.is_dir()]
    for folder in found:
        shutil.rmtree(folder, ignore_errors=True)
    return len(found)


def _remove_own_scratch() -> None:
    """At exit: this process's scratch folder, if it made one (registered when this module is
    imported, so that it runs after the exit handlers registered later: the end of ENHSP's
    server and of its searches, whose files are in it)."""
    if _scratch is not None and _scratch[0] == os.getpid():
        shutil.rmtree(_scratch[1], ignore_errors=True)


atexit.register(_remove_own_scratch)


def carriers(token: str) -> Iterator[int]:
    """The processes (other than this one) whose environment holds the run's ``token``.

    /proc/PID/environ is the environment a process was started with; processes of other
    users cannot be read and are never ours."""
    entry = f"{ENV}={token}".encode()
    me = os.getpid()
    for name in os.listdir("/proc"):
        if not name.isdigit() or int(name) == me:
            continue
        try:
            with open(f"/proc/{name}/environ", "rb") as fh:
                environment = fh.read()
        except OSError:
            continue
        if entry in environment.split(b"\0"):
            yield int(name)


def end_carriers(token: str, rounds: int = 20) -> int:
    """Kill every process that carries ``token``, again until none is left (a process may
    start another while it is being killed); returns how many were killed."""
    killed = 0
    for _ in range(rounds):
        found = list(carriers(token))
        if not found:
            break
        for pid in found:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, signal.SIGKILL)
                killed += 1
        time.sleep(0.05)
    return killed


def _sentinel_main(token: str, parent: int) -> None:
    """Wait for the run's process to end, then end what it left running.

    The death signal is blocked first (it is waited for, and must not end the sentinel
    before), then asked for from the kernel for when the parent ends."""
    for sig in (signal.SIGINT, signal.SIGHUP, signal.SIGQUIT):
        signal.signal(sig, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_SETMASK, {DEATH_SIGNAL})
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, DEATH_SIGNAL, 0, 0, 0)
    if os.getppid() == parent:  # else the run ended before the kernel was asked to tell us
        signal.sigwait({DEATH_SIGNAL})
    end_carriers(token)
    remove_scratch(token=token)


if __name__ == "__main__":
    _sentinel_main(sys.argv[1], int(sys.argv[2]))
