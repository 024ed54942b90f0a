"""Work done in a thread beside the run's main thread, its result given where it is asked for.

A run has stretches where its main thread waits while other work could go on: OR-Tools' guided
local search releases the interpreter's lock while it searches, so the search's two first
routings run at once (tmpnav.task.search). Work that holds the lock (Python code) belongs in a
process instead: beside a main thread that waits often and briefly, it takes the lock in 5 ms
turns and each short wait waits a turn (tmpnav.planning.bound.LaterBound). :class:`Beside` runs
such work in a daemon thread: a run that ends early (its time limit, an error, a signal) does
not wait for it, and an error it raises is raised in the thread that asks for its result. The
work must not touch the run's stage times (their clock is the main thread's) or anything else
the main thread writes meanwhile."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")

#: s: the longest the asking thread waits at once
WAIT_SLICE = 0.1


class Beside(Generic[T]):
    """``work()`` started now in a daemon thread named ``name``; calling the object waits for it
    and gives its result, or raises its error (every call the same)."""

    def __init__(self, work: Callable[[], T], name: str):
        self._done = threading.Event()
        self._value: T | None = None
        self._error: BaseException | None = None
        threading.Thread(target=self._run, args=(work,), name=name, daemon=True).start()

    def _run(self, work: Callable[[], T]) -> None:
        try:
            self._value = work()
        except BaseException as error:  # raised where the result is asked for
            self._error = error
        finally:
            self._done.set()

    def __call__(self) -> T:
        # in slices: a signal the kernel hands to another thread is run by the main thread
        # only between slices (tmpnav.lifetime.gather)
        while not self._done.wait(WAIT_SLICE):
            pass
        if self._error is not None:
            raise self._error
        return self._value  # type: ignore[return-value]
