"""A run's long-lived objects kept out of Python's full collections (``gc.freeze``).

Python's full collections walk every object there is: the libraries' (numba's type system,
SciPy, OR-Tools, OMPL's bindings) and the run's own (cost tables, oracle results, the
search's state). They were frequent while ENHSP's JVM ran inside tmpnav, through JPype (until
2026-11-28; :mod:`tmpnav.task.enhsp_jvm` now runs it as a process), which tied the two
collectors together: after every collection of the JVM's heap, its reference thread ran a
full Python collection, holding the interpreter's lock, every 0.1-0.5 s of ENHSP's
searches. Measured then, after the bench's warm-up: on
the 10-room corridor 8 such collections of 70-170 ms, 0.8 s of a 2.7 s run; on the 40-room
office 131 collections, 18 s of a 44.5 s run. Every other thread waited for the lock
meanwhile, the searches' own too (the first two searches of a 10-room run took 0.3 s each
instead of 0.01 s). Python's own full collections remain (one each time the objects that
survived the last grow by a quarter), and the run's objects only grow.

So a run moves the objects that exist when it starts (imported modules, the world, the
roadmap) into the permanent generation, which collections skip, and after each full
collection during the run, what it kept: each full collection then walks only what was
made since the one before (40-room office: 242 collections, 0.18 s in all; the run 34.7 s).
When the run ends, the objects go back to the oldest generation. The cost: a structure
that survives a full collection and later becomes unreachable in a cycle waits for the
run's end to be collected (objects freed by their reference counts, most of them, are freed
at once as before); peak memory stayed the same (40 rooms: 1.88 GB frozen, 1.89 GB not).
Runs may nest or overlap in threads; the last one to end gives the objects back.
"""

from __future__ import annotations

import contextlib
import gc
import threading
from collections.abc import Iterator

#: the generation a full collection collects (CPython has three: 0, 1, 2)
OLDEST = len(gc.get_threshold()) - 1

_lock = threading.Lock()
_runs = 0


@contextlib.contextmanager
def long_lived_frozen() -> Iterator[None]:
    """Inside, the objects that existed on entry, and those that survive a full collection,
    are not walked by Python's collections again."""
    global _runs
    with _lock:
        _runs += 1
        if _runs == 1:
            gc.callbacks.append(_freeze_survivors)
        gc.freeze()
    try:
        yield
    finally:
        with _lock:
            _runs -= 1
            if _runs == 0:
                gc.callbacks.remove(_freeze_survivors)
                gc.unfreeze()


def _freeze_survivors(phase: str, info: dict[str, int]) -> None:
    """After a full collection (the collection itself is over): freeze what it kept."""
    if phase == "stop" and info["generation"] == OLDEST:
        gc.freeze()
