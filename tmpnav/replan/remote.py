"""The closed loop's plans made by a running ``tmpnav serve``: ``tmpnav simulate --events --server URL``.

The team is simulated here; its plans come from the service, as a fleet manager's would. The
first plan is asked for with the scenario's goals (``POST /plans``); at each replan the team's
state (:func:`tmpnav.replan.state.state_document`: each robot's estimate and covariance, the
robots down, the doors, the goals added and removed) is posted against the plan's latest
revision (``POST /plans/{id}/states``), and the revision's plan.json is read back and executed
(:func:`tmpnav.execution.moves.queues_of_document`). So the same disturbance suite exercises the
service: its HTTP, its store, its revisions numbered in order.

The service must plan the same site: its first plan's roadmap is the one this process grows
for the scenario (its fingerprint), else the loop stops with one line saying so.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tmpnav.client import Client, ServiceError
from tmpnav.errors import InputError, TmpnavError
from tmpnav.replan.revise import NothingLeft
from tmpnav.replan.state import TeamState, state_document


class RemoteError(TmpnavError):
    """The service failed or refused a plan (its one-line message, its exit code)."""

    def __init__(self, message: str, exit_code: int = 1):
        super().__init__(message)
        self.exit_code = exit_code


class NothingLeftRemote(RemoteError):
    """The service found no goal left to plan."""


@dataclass
class RemotePlans:
    """One plan of the service at ``url`` and its revisions, as the closed loop asks for them."""

    client: Client
    plan: str = ""
    revision: int = 0

    @classmethod
    def at(cls, url: str, token: str | None) -> RemotePlans:
        return cls(Client(url, token))

    def first(self, fingerprint: str, scenario: str) -> dict[str, Any]:
        """A new plan of the scenario's goals: its plan.json. ``fingerprint``: the roadmap this
        process grows for ``scenario``, which the service's must be."""
        info = self._call(lambda: self.client.plan())
        self.plan, self.revision = str(info["id"]), int(info["revision"])
        doc = self._call(lambda: self.client.document(self.plan, self.revision))
        theirs = doc.get("roadmap", {}).get("fingerprint")
        if theirs != fingerprint:
            served = doc.get("scenario", {}).get("file", "?")
            raise InputError(
                f"--server {self.client.url}: the service plans {served}, whose roadmap is not that of {scenario}; "
                "expected a service started on the same scenario (tmpnav serve SCENARIO)"
            )
        return doc

    def revise(self, team: TeamState) -> dict[str, Any]:
        """The revision planned from ``team``, against the latest revision: its plan.json."""
        state = state_document(team)
        info = self._call(lambda: self.client.post_state(self.plan, self.revision, state))
        self.revision = int(info["revision"])
        return self._call(lambda: self.client.document(self.plan, self.revision))

    def _call(self, call: Any) -> Any:
        try:
            return call()
        except ServiceError as err:
            kind = NothingLeftRemote if err.problem.get("type") == NothingLeft.problem_type else RemoteError
            raise kind(f"tmpnav serve at {self.client.url}: {err}", err.exit_code) from None
        except OSError as err:  # refused, reset, timed out
            raise RemoteError(
                f"--server {self.client.url}: {getattr(err, 'reason', err)}; expected a running tmpnav serve there", 3
            ) from None


def at_start_of_document(doc: dict[str, Any]) -> list[str]:
    """The goal rooms a plan.json's robots visit by starting in them: the goals it leaves to
    no move that it neither drops nor names out of reach (as :func:`tmpnav.replan.loop._at_start`
    of the plan itself)."""
    goals = doc.get("goals", {})
    wanted = list(goals.get("visit", [])) + [x for rooms in goals.get("per_robot", {}).values() for x in rooms]
    moved = {m["to"] for a in doc.get("actions", []) for m in a["moves"]}
    out = set(goals.get("dropped", [])) | {u["room"] for u in (doc.get("revision") or {}).get("unreachable", [])}
    return [x for x in dict.fromkeys(wanted) if x not in moved and x not in out]


def unreachable_of_document(doc: dict[str, Any]) -> tuple[str, ...]:
    """The rooms a revision names out of reach."""
    return tuple(u["room"] for u in (doc.get("revision") or {}).get("unreachable", []))
