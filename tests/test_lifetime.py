"""tmpnav.lifetime.gather: a signal the kernel hands to another thread still ends the wait at once."""

from __future__ import annotations

import signal
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from types import FrameType

import pytest

from tests.children import run_python
from tmpnav.lifetime import SIGNAL_POLL, gather


class Signalled(Exception):
    pass


def _raise(signum: int, frame: FrameType | None) -> None:
    raise Signalled


@pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="needs pthread_kill")
def test_a_signal_given_to_a_worker_thread_ends_the_wait_within_a_slice() -> None:
    """The signal goes to the worker (as the kernel may do with a process-directed one): its C
    handler only sets a flag, and Python runs the handler in the main thread when that next
    runs Python code. An untimed Future.result() waited the worker's 3 s out."""
    previous = signal.signal(signal.SIGUSR1, _raise)
    release = threading.Event()
    started = threading.Event()

    def work() -> int:
        started.set()
        release.wait(3.0)
        return 1

    pool = ThreadPoolExecutor(max_workers=1)
    try:
        future = pool.submit(work)
        started.wait(1.0)
        worker = next(t for t in threading.enumerate() if t.name.startswith("ThreadPoolExecutor"))
        assert worker.ident is not None
        # sent from a third thread once the main one waits in gather: sent from the main thread,
        # the handler could run before gather is entered (it did once in a full run of the suite)
        sender = threading.Timer(0.3, signal.pthread_kill, (worker.ident, signal.SIGUSR1))
        begun = time.monotonic()
        sender.start()
        with pytest.raises(Signalled):
            list(gather([future]))
        assert time.monotonic() - begun < 0.3 + 1.0 + SIGNAL_POLL  # not the worker's 3 s
        sender.join()
    finally:
        release.set()
        pool.shutdown(wait=True)
        signal.signal(signal.SIGUSR1, previous)


def test_gather_gives_the_results_in_the_futures_order() -> None:
    with ThreadPoolExecutor(max_workers=3) as pool:
        futures = [pool.submit(time.sleep, d) for d in (0.2, 0.0, 0.1)]
        assert list(gather(futures)) == [None, None, None]
        futures = [pool.submit(lambda k=k: k * k) for k in range(5)]
        assert list(gather(futures)) == [0, 1, 4, 9, 16]


UNRAISABLE = """
import os, signal, sys, time, weakref
from tmpnav import lifetime
lifetime.guard()
try:
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(5)
except KeyboardInterrupt:
    pass
class Held:
    pass
def interrupted(ref):
    raise KeyboardInterrupt  # as a Ctrl-C landing in importlib's module-lock callback does
def broken(ref):
    raise ValueError("a real bug")
first, second = Held(), Held()
refs = [weakref.ref(first, interrupted), weakref.ref(second, broken)]
del first, second
print("went on", flush=True)
"""


def test_the_signals_own_exception_where_python_cannot_raise_it_prints_no_traceback() -> None:
    """Python prints an exception raised in a weakref callback as "Exception ignored in ...",
    traceback included: after a Ctrl-C, the fault-injection test saw one land in importlib's
    module-lock callback. The signal is remembered, so that one is silent; others are not."""
    proc = run_python(UNRAISABLE, timeout=60)
    assert proc.returncode == 0 and proc.stdout == "went on\n", proc.stderr
    assert "KeyboardInterrupt" not in proc.stderr
    assert "ValueError: a real bug" in proc.stderr


@pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="needs pthread_kill")
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_given_to_another_thread_inside_a_held_block_is_raised_when_it_ends(sig: signal.Signals) -> None:
    """The main thread holds the signals while it forks; the kernel gives one to another
    thread (the JVM's), and Python runs the handler in the main thread inside the block, where
    at-fork handlers dropped its exception: the run went on to its end. It is raised when the
    block ends, and the block's work is not cut short."""
    script = f"""
import signal, sys, threading, time
from tmpnav import lifetime
signal.signal(signal.SIGTERM, lifetime._raise_terminated)
signal.signal(signal.SIGINT, lifetime._raise_interrupted)
other = threading.Thread(target=time.sleep, args=(2.0,), daemon=True)
other.start()
try:
    with lifetime.signals_held():
        signal.pthread_kill(other.ident, {int(sig)})
        until = time.monotonic() + 0.3
        while time.monotonic() < until:  # bytecode: the handler runs here, in this thread
            pass
        print("block done", flush=True)
    print("not raised", flush=True)
except (KeyboardInterrupt, lifetime.Terminated) as err:
    print("raised", type(err).__name__, flush=True)
"""
    proc = run_python(script, timeout=30)
    expected = "KeyboardInterrupt" if sig == signal.SIGINT else "Terminated"
    assert proc.stdout.split("\n")[:2] == ["block done", f"raised {expected}"], proc.stdout + proc.stderr
