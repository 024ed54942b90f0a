"""Bad input to tmpnav serve: the project's fuzz set (tests/fuzz/strategies.py) sent as request
bodies, oversize and malformed bodies, no token or a wrong one. Every answer is a documented
status with one-line messages as problem details, and the service is still up after."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.fuzz.strategies import SCENARIO_KEYS, mutated_doc, mutated_text, whole_file_attacks
from tests.serve.server import ROOT, Server
from tmpnav.client import Client
from tmpnav.errors import EXIT_CODES

#: the statuses docs/serve.md documents for a request body (a valid one: 201, or 202 at once)
DOCUMENTED = {201, 202, 401, 404, 405, 409, 413, 422}
SMOKE = settings(
    max_examples=8, derandomize=True, deadline=None, database=None, suppress_health_check=list(HealthCheck)
)
STATE = {
    "time": 5.0,
    "robots": {
        "r1": {"pose": [3.0, 5.0, 0.0], "covariance": [[0.02, 0, 0], [0, 0.02, 0], [0, 0, 0.004]]},
        "r2": {"status": "down"},
    },
    "visited": ["A"],
    "doors": {"door-A": "open"},
    "goals": {"add": ["C"], "remove": []},
}
STATE_KEYS = [
    ("time",),
    ("robots", "r1", "pose"),
    ("robots", "r1", "covariance"),
    ("robots", "r2", "status"),
    ("visited",),
    ("doors", "door-B"),
    ("goals", "add"),
    ("goals", "remove"),
]
GOALS = {"visit": ["C"], "robots": {"r1": ["B"]}, "jobs": [{"name": "C", "service": 5}]}
GOAL_KEYS = [k[1:] for k in SCENARIO_KEYS if k[0] == "goals" and len(k) > 1]


@pytest.fixture(scope="module")
def http(server: Server) -> Iterator[httpx.Client]:
    with httpx.Client(base_url=server.url, timeout=600) as session:
        yield session


def check(answer: httpx.Response) -> None:
    """A documented status; an error is problem details of one-line messages."""
    assert answer.status_code in DOCUMENTED, (answer.status_code, answer.text[:500])
    if answer.status_code >= 400:
        assert answer.headers["content-type"].startswith("application/problem+json")
        problem = answer.json()
        assert problem["status"] == answer.status_code and problem["exit_code"] in EXIT_CODES
        assert problem["errors"] and all(line and "\n" not in line for line in problem["errors"])
        assert "Traceback" not in problem["detail"] and "internal error" not in problem["detail"]


def settle(http: httpx.Client, answer: httpx.Response) -> None:
    """A search the fuzz set started by chance (a valid body) is cancelled and waited for."""
    if answer.status_code == 202:
        job = answer.json()["id"]
        http.delete(f"/jobs/{job}")
        with http.stream("GET", f"/jobs/{job}/events") as events:
            for _ in events.iter_lines():
                pass


def send(http: httpx.Client, path: str, content: bytes) -> httpx.Response:
    return http.post(path, content=content, headers={"content-type": "application/json"})


def as_json(doc: Any) -> bytes:
    return json.dumps(doc, allow_nan=True).encode("utf-8", errors="surrogatepass")


@SMOKE
@given(mutated_doc(STATE, STATE_KEYS))
def test_fuzzed_states(http: httpx.Client, first: dict, case: tuple[Any, list[str]]) -> None:
    latest = http.get(f"/plans/{first['id']}").json().get("revision", {"number": 0})
    number = latest["number"] if isinstance(latest, dict) else 0
    check(send(http, f"/plans/{first['id']}/states", as_json({"revision": number, "state": case[0]})))


@SMOKE
@given(mutated_doc(GOALS, GOAL_KEYS))
def test_fuzzed_goals(http: httpx.Client, first: dict, case: tuple[Any, list[str]]) -> None:
    answer = send(http, "/plans", as_json({"goals": case[0], "wait": False}))
    check(answer)
    settle(http, answer)


@SMOKE
@given(st.one_of(whole_file_attacks(), mutated_text(json.dumps({"revision": 0, "state": STATE}))))
def test_fuzzed_raw_bodies(http: httpx.Client, first: dict, case: tuple[bytes, list[str]]) -> None:
    for path in ("/plans", f"/plans/{first['id']}/states"):
        answer = send(http, path, case[0])
        check(answer)
        settle(http, answer)


def test_oversize_and_malformed_bodies(http: httpx.Client, first: dict) -> None:
    big = b'{"revision": 0, "state": {"time": 1, "visited": [' + b'"A", ' * 300_000 + b'"A"]}}'
    answer = send(http, f"/plans/{first['id']}/states", big)
    assert answer.status_code == 413 and "larger than the service's limit" in answer.json()["detail"]
    chunked = http.post("/plans", content=iter([b"[" * 600_000, b"]" * 600_000]))
    assert chunked.status_code == 413
    deep = send(http, "/plans", b"[" * 200_000)
    check(deep)
    for body in (b"", b"null", b"[]", b'{"goals": 3}', b'{"wait": "soon"}', b'{"time_budget": -1}', b"\xff\xfe"):
        check(send(http, "/plans", body))
    check(http.get("/plans/nope/schedule"))
    check(http.get(f"/plans/{first['id']}/states"))  # 405
    check(http.put("/plans", content=b"{}"))
    check(http.delete("/jobs/nope"))
    assert http.get("/health").json()["status"] == "ok"


@pytest.fixture(scope="module")
def guarded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    running = Server("configs/two-rooms.yaml", tmp_path_factory.mktemp("guarded"), "--token", "s3cret")
    try:
        yield running
    finally:
        running.stop()


def test_with_a_token_every_request_carries_it(guarded: Server) -> None:
    with httpx.Client(base_url=guarded.url, timeout=60) as http:
        for headers in ({}, {"Authorization": "Bearer wrong"}, {"Authorization": "Basic s3cret"}):
            answer = http.get("/plans", headers=headers)
            check(answer)
            assert answer.status_code == 401 and answer.headers["www-authenticate"].startswith("Bearer")
        assert http.post("/plans", json={}).status_code == 401
        assert http.get("/plans/p1/events", params={"token": "wrong"}).status_code == 401
        assert http.get("/plans", headers={"Authorization": "Bearer s3cret"}).json() == []
        assert http.get("/site", params={"token": "s3cret"}).json()["name"] == "two-rooms"
        assert http.get("/").status_code == 200  # the page holds no data: its calls carry the token
    assert Client(guarded.url, token="s3cret").plans() == []


def test_without_a_token_only_loopback(tmp_path: Path) -> None:
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "tmpnav",
            "serve",
            "configs/two-rooms.yaml",
            "--host",
            "0.0.0.0",
            "--port",
            "0",
            "--cache-dir",
            str(tmp_path),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    assert run.returncode == 2
    assert run.stderr.strip().splitlines() == [
        "error: --host 0.0.0.0: without --token the service binds only a loopback address (127.0.0.1, ::1); "
        "give --token to serve other machines"
    ]
