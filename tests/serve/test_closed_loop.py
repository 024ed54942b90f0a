"""``tmpnav simulate --events --server URL``: the closed loop's plan and revisions made by a real
``tmpnav serve`` (a process of its own), executed here: the disturbance suite against the
service. A service of another site, and none at all, are one line each."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.serve.server import ROOT, Server
from tests.test_replan import WORLD
from tmpnav.client import Client
from tmpnav.errors import InputError
from tmpnav.pipeline import PlanOptions, load_world
from tmpnav.replan.events import read_events
from tmpnav.replan.loop import closed_loop
from tmpnav.replan.remote import RemoteError, RemotePlans
from tmpnav.replan.state import read_state, state_document


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Path, Server]]:
    folder = tmp_path_factory.mktemp("loop-serve")
    scenario = folder / "loop.yaml"
    scenario.write_text(WORLD)
    (folder / "cache").mkdir()
    running = Server(str(scenario), folder / "cache")
    try:
        yield scenario, running
    finally:
        running.stop()


@pytest.mark.slow
def test_a_door_closing_is_replanned_by_the_service(site: tuple[Path, Server], tmp_path: Path) -> None:
    """As tests/test_closed_loop.py's first case, the revision coming from the service: r2 drives
    to B, dB closes at 8 s, the service names B out of reach, A is done, nothing lost or twice."""
    scenario, server = site
    (tmp_path / "events.yaml").write_text("events:\n  - {at: 8, close: dB}\n")
    loaded, _ = load_world(scenario)
    options = PlanOptions.of(cache_dir=server.cache)
    events = read_events(tmp_path / "events.yaml", loaded)
    result = closed_loop(scenario, events, 1, 0, options, server=server.url)
    (loop,) = result.runs["closed loop"]
    assert [(p.reason, p.outcome, p.unreachable) for p in loop.replans] == [("dB closed", "planned", ("B",))]
    assert loop.dropped == ("B",) and loop.lost == () and loop.twice == () and set(loop.done) == {"A"}
    (blind,) = result.runs["blind"]
    assert "B" in blind.lost
    (plan,) = Client(server.url).plans()
    assert plan["revision"] == 1  # the session's plan, revised once by the posted state


def test_a_service_of_another_site_is_named(site: tuple[Path, Server]) -> None:
    _, server = site
    with pytest.raises(InputError, match=r"the service plans .*loop\.yaml, whose roadmap is not that of other\.yaml"):
        RemotePlans.at(server.url, None).first("another-roadmap", "other.yaml")


def test_no_service_is_one_line_with_exit_code_3() -> None:
    with pytest.raises(RemoteError) as err:
        RemotePlans.at("http://127.0.0.1:9", None).first("x", "loop.yaml")
    assert err.value.exit_code == 3 and "expected a running tmpnav serve there" in str(err.value)


def test_server_without_events_is_refused_by_the_command_line() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "tmpnav", "simulate", "configs/two-rooms.yaml", "--server", "http://127.0.0.1:9"],
        cwd=ROOT, capture_output=True, text=True,
    )  # fmt: skip
    assert done.returncode == 2 and "--server" in done.stderr and "expected --events EVENTS" in done.stderr
    assert "Traceback" not in done.stderr


def test_a_state_document_reads_back_as_the_state(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    path.write_text(
        '{"time": 12.5, "robots": {"r1": {"pose": [1, 2, 0.5], "covariance": [[0.01, 0, 0], [0, 0.01, 0], '
        '[0, 0, 0.001]], "interrupted": true}, "r2": {"status": "down"}}, "visited": ["A"], '
        '"doors": {"dB": "closed"}, "goals": {"add": ["C", {"name": "D", "service": 30, "window": [10, 90]}], '
        '"remove": ["E"]}}'
    )
    team = read_state(path)
    path.write_text(json.dumps(state_document(team)))
    assert read_state(path) == team
