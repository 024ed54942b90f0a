"""The oracle on a real local Ray instance gives the results it gives in this process, bit for bit
(tests/oracle/test_executors.py has the other executors). A file of its own: Ray's start takes
seconds on an idle machine and minutes on one the rest of the suite loads, and the suite's order
(tests/conftest.py) starts it first."""

from __future__ import annotations

import pytest

from tests.oracle.support import actions
from tmpnav.oracle import executors
from tmpnav.oracle.cache import NullCache
from tmpnav.oracle.executors import OracleContext, SerialExecutor
from tmpnav.oracle.oracle import Oracle


@pytest.fixture(scope="module")
def reference(two_rooms: OracleContext):  # type: ignore[no-untyped-def]
    return Oracle(two_rooms, NullCache(), SerialExecutor()).evaluate(actions(two_rooms))


@pytest.mark.ray
@pytest.mark.slow
def test_ray(two_rooms: OracleContext, reference, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    """The same results from a real local Ray instance; its start and shutdown leave the
    process's handlers of fatal signals as they were (the JVM's, in a run that started it:
    with Ray's or the default in place, the JVM's next safepoint poll ended the process)."""
    pytest.importorskip("ray")
    monkeypatch.setattr(executors, "BLOCK", 4)
    before = fatal_handlers()
    executor = executors.RayExecutor(num_cpus=2)
    try:
        assert executor.workers == 2
        assert fatal_handlers() == before
        result = Oracle(two_rooms, NullCache(), executor).evaluate(actions(two_rooms))
    finally:
        executor.close()
    assert fatal_handlers() == before
    assert result == reference


def fatal_handlers() -> dict[int, int | None]:
    """The C-level handler of each signal Ray's start and shutdown replace (Linux; else empty)."""
    return {int(sig): action.handler for sig, action in executors.signal_actions().items()}
