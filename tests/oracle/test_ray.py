"""The oracle on a real Ray cluster started on this machine as a fleet would start one: ``ray start
--head`` and a second node process joining it (``ray start --address``), one CPU each. The
oracle's results are the ones it gives in this process, bit for bit (tests/oracle/test_executors.py
has the other executors), and ``tmpnav plan --executor ray --ray-address`` plans what local
processes plan. A file of its own, the suite's only user of Ray: its start takes seconds on an
idle machine and minutes on one the rest of the suite loads (the suite's order, tests/conftest.py,
starts it first), and ``ray stop`` at the end stops every Ray process of the machine's user."""

from __future__ import annotations

import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.oracle.support import ROOT, actions
from tmpnav.oracle import executors
from tmpnav.oracle.cache import NullCache
from tmpnav.oracle.executors import OracleContext, SerialExecutor
from tmpnav.oracle.oracle import Oracle
from tmpnav.report.plan_json import without_timings

pytest.importorskip("ray", reason="the Ray tests need Ray: pip install 'tmpnav[ray]' (make test installs it)")
pytestmark = [pytest.mark.ray, pytest.mark.slow]

RAY = Path(sys.executable).parent / "ray"
ENV = dict(os.environ, PYTHONPATH=str(ROOT), RAY_USAGE_STATS_ENABLED="0")


def _ray(*args: str) -> None:
    done = subprocess.run([str(RAY), *args], env=ENV, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"ray {' '.join(args)}: {done.stdout[-2000:]}{done.stderr[-2000:]}"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def cluster() -> Iterator[str]:
    """The address of a two-node cluster, one CPU a node, on loopback (its sockets in a short
    temporary folder: Unix sockets take paths of at most 107 bytes)."""
    temp = tempfile.mkdtemp(prefix="tmpnav-ray-")
    address = f"127.0.0.1:{_free_port()}"
    port = address.split(":")[1]
    common = ("--node-ip-address=127.0.0.1", "--num-cpus=1", "--disable-usage-stats")
    try:
        _ray("start", "--head", f"--port={port}", "--include-dashboard=false", f"--temp-dir={temp}", *common)
        _ray("start", f"--address={address}", *common)
        yield address
    finally:
        subprocess.run([str(RAY), "stop", "--force"], env=ENV, capture_output=True, timeout=300)
        shutil.rmtree(temp, ignore_errors=True)


@pytest.fixture(scope="module")
def reference(two_rooms: OracleContext):  # type: ignore[no-untyped-def]
    return Oracle(two_rooms, NullCache(), SerialExecutor()).evaluate(actions(two_rooms))


def test_the_oracle_on_a_two_node_cluster(cluster: str, two_rooms: OracleContext, reference, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The same results from the cluster's two workers; joining and leaving it leave the
    process's handlers of fatal signals as they were (the JVM's, in a run that started it:
    with Ray's or the default in place, the JVM's next safepoint poll ended the process)."""
    monkeypatch.setattr(executors, "BLOCK", 4)
    before = fatal_handlers()
    executor = executors.RayExecutor(cluster)
    try:
        assert executor.workers == 2  # one CPU on each node
        assert fatal_handlers() == before
        result = Oracle(two_rooms, NullCache(), executor).evaluate(actions(two_rooms))
    finally:
        executor.close()
    assert fatal_handlers() == before
    assert result == reference


def test_a_plan_on_the_cluster_is_the_plan_of_local_processes(cluster: str, tmp_path: Path) -> None:
    """``tmpnav plan --executor ray --ray-address`` with a cold cache (every move cost computed on
    the cluster) against the default local worker processes: the same plan.json but for the
    timings and the cache's folder."""
    docs = []
    for name, more in (("ray", ["--executor", "ray", "--ray-address", cluster]), ("local", [])):
        out = tmp_path / name
        command = [sys.executable, "-m", "tmpnav", "plan", "configs/two-rooms.yaml", "-q", "-o", str(out)]
        done = subprocess.run(
            [*command, "--cache-dir", str(tmp_path / f"cache-{name}"), *more],
            cwd=ROOT, env=ENV, capture_output=True, text=True, timeout=900,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
        doc = without_timings(json.loads((out / "plan.json").read_text()))
        assert doc["cache"]["misses"] > 0
        doc["cache"].pop("directory")
        docs.append(doc)
    assert docs[0] == docs[1]


def fatal_handlers() -> dict[int, int | None]:
    """The C-level handler of each signal Ray's start and shutdown replace (Linux; else empty)."""
    return {int(sig): action.handler for sig, action in executors.signal_actions().items()}
