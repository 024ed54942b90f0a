"""A run's long-lived objects kept out of Python's full collections (``gc.freeze``).

JPype, which runs ENHSP inside the tmpnav process (:mod:`tmpnav.task.enhsp_jvm`), ties the
two collectors together: after every collection of the JVM's heap, its reference thread runs
a full Python collection, holding the interpreter's lock. ENHSP's searches fill the young
generation every 0.1-0.5 s, and a full collection walks every Python object there is, most
of them the libraries' (numba's type system, scipy, OR-Tools, OMPL's bindings): measured on
the 10-room corridor after the bench's warm-up, 8 such collections of 70-170 ms, 0.8 s of a
2.7 s run, during which every other thread waited for the lock (the searches' own threads
too: their first two searches took 0.3 s each instead of 0.01 s).

So a run moves the objects that exist when it starts (imported modules, the world, the
roadmap) into the permanent generation, which collections skip (each then took 2-3 ms),
and gives them back to the oldest generation when it ends: the run's own garbage is
collected as before, and nothing stays frozen after the run. Runs may nest or overlap in
threads; the last one to end gives the objects back.
"""

from __future__ import annotations

import contextlib
import gc
import threading
from collections.abc import Iterator

_lock = threading.Lock()
_runs = 0


@contextlib.contextmanager
def long_lived_frozen() -> Iterator[None]:
    """Inside, the objects that existed on entry are not walked by Python's collections."""
    global _runs
    with _lock:
        _runs += 1
        gc.freeze()
    try:
        yield
    finally:
        with _lock:
            _runs -= 1
            if _runs == 0:
                gc.unfreeze()
