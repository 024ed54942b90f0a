"""A small Python client of ``tmpnav serve`` (docs/serve.md), on the standard library alone.

    from tmpnav.client import Client

    fleet = Client("http://127.0.0.1:8765", token=None)
    plan = fleet.plan()                                  # the scenario's goals; or goals={...}
    revised = fleet.post_state(plan["id"], plan["revision"], {"time": 95.5, "robots": {"r2": {"status": "down"}}})
    files = fleet.nav2(plan["id"])                       # file name -> text, of the latest revision

An error answer raises :class:`ServiceError` with the problem details: the command line's
message (``detail``), its exit code, the HTTP status, and for a stale update the plan's
``latest`` revision to post again against.
"""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from collections.abc import Iterator
from typing import Any

__all__ = ["Client", "ServiceError"]


class ServiceError(Exception):
    """An error answer of the service (RFC 9457 problem details)."""

    def __init__(self, status: int, problem: dict[str, Any]):
        super().__init__(problem.get("detail") or f"HTTP {status}")
        self.status = status
        self.problem = problem
        self.exit_code = int(problem.get("exit_code", 1))
        self.latest: int | None = problem.get("latest")


class Client:
    """Calls to one service; ``timeout``: seconds a call may wait for its answer."""

    def __init__(self, url: str, token: str | None = None, timeout: float = 600.0):
        self.url = url.rstrip("/")
        self.token = token
        self.timeout = timeout

    def plan(self, goals: dict[str, Any] | None = None, time_budget: float | None = None) -> dict[str, Any]:
        """Plan a shift (the scenario's goals, or ``goals``: its ``goals`` section); the plan's info."""
        return self._call("POST", "/plans", {"goals": goals, "time_budget": time_budget})

    def start_plan(self, goals: dict[str, Any] | None = None, time_budget: float | None = None) -> dict[str, Any]:
        """Start planning and return the job at once (follow it with :meth:`events`)."""
        return self._call("POST", "/plans", {"goals": goals, "time_budget": time_budget, "wait": False})

    def post_state(self, plan: str, revision: int, state: dict[str, Any]) -> dict[str, Any]:
        """The revision planned from ``state`` (a ``tmpnav replan`` state), observed against ``revision``."""
        return self._call("POST", f"/plans/{plan}/states", {"revision": revision, "state": state})

    def plans(self) -> list[dict[str, Any]]:
        out: list[dict[str, Any]] = self._call("GET", "/plans")
        return out

    def document(self, plan: str, revision: int | None = None) -> dict[str, Any]:
        """The plan.json of a plan's latest revision, or of ``revision``."""
        return self._call("GET", f"/plans/{plan}" + ("" if revision is None else f"?revision={revision}"))

    def schedule(self, plan: str) -> dict[str, Any]:
        return self._call("GET", f"/plans/{plan}/schedule")

    def nav2(self, plan: str) -> dict[str, str]:
        files: dict[str, str] = self._call("GET", f"/plans/{plan}/nav2")["files"]
        return files

    def job(self, job: str) -> dict[str, Any]:
        return self._call("GET", f"/jobs/{job}")

    def cancel(self, job: str) -> dict[str, Any]:
        """Cancel a running search."""
        return self._call("DELETE", f"/jobs/{job}")

    def events(self, path: str) -> Iterator[tuple[str, dict[str, Any]]]:
        """The server-sent events of ``path`` (``/jobs/j1/events``, ``/plans/p1/events``) as
        (event, data), until the stream ends."""
        with urllib.request.urlopen(self._request("GET", path, None), timeout=self.timeout) as answer:
            kind, data = "message", []
            for raw in answer:
                line = raw.decode("utf-8").rstrip("\n")
                if line.startswith("event:"):
                    kind = line[6:].strip()
                elif line.startswith("data:"):
                    data.append(line[5:].strip())
                elif not line and data:
                    yield kind, json.loads("\n".join(data))
                    kind, data = "message", []

    def _request(self, method: str, path: str, body: dict[str, Any] | None) -> urllib.request.Request:
        headers = {"Accept": "application/json"}
        if self.token is not None:
            headers["Authorization"] = f"Bearer {self.token}"
        data = None
        if body is not None:
            data = json.dumps({k: v for k, v in body.items() if v is not None}).encode()
            headers["Content-Type"] = "application/json"
        return urllib.request.Request(self.url + path, data=data, method=method, headers=headers)

    def _call(self, method: str, path: str, body: dict[str, Any] | None = None) -> Any:
        try:
            with urllib.request.urlopen(self._request(method, path, body), timeout=self.timeout) as answer:
                return json.loads(answer.read())
        except urllib.error.HTTPError as err:
            text = err.read()
            try:
                problem = json.loads(text)
            except ValueError:
                problem = {"detail": text.decode("utf-8", "replace")[:200]}
            raise ServiceError(err.code, problem) from None
