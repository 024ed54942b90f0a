"""The request and answer bodies of ``tmpnav serve`` (pydantic models: the OpenAPI document is
generated from them).

The goals and the team's state are checked by tmpnav's own readers (the scenario schema, the
``tmpnav replan`` state reader), not re-described here: a client gets the same one-line
messages as the command line, naming the key (``state: robots.r1.pose: ...``).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field, JsonValue

GOALS_EXAMPLE: dict[str, JsonValue] = {"visit": ["S1", "N4"], "jobs": [{"name": "S1", "service": 30}]}
STATE_EXAMPLE: dict[str, JsonValue] = {
    "time": 95.5,
    "robots": {
        "r1": {"pose": [31.2, 7.1, 1.57], "covariance": [[0.02, 0, 0], [0, 0.02, 0], [0, 0, 0.004]]},
        "r2": {"status": "down"},
    },
    "doors": {"door-S6": "closed"},
    "goals": {"add": ["N9"], "remove": []},
}


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class PlanRequest(Strict):
    """Plan a shift of the site."""

    goals: dict[str, Any] | None = Field(
        None,
        description="The scenario's `goals` section for this shift (docs/scenario.md: visit, robots, jobs, "
        "ends); absent: the scenario's own goals.",
        json_schema_extra={"example": GOALS_EXAMPLE},
    )
    time_budget: float | None = Field(
        None, gt=0, description="Seconds for the anytime search (planner.time_budget); at most the service's limit."
    )
    wait: bool = Field(
        True,
        description="Answer when the plan is made (201); false: answer at once (202) with the job, whose "
        "progress `GET /jobs/{id}/events` streams.",
    )


class StateUpdate(Strict):
    """The team's state, to revise a plan from."""

    revision: int = Field(
        ..., ge=0, description="The revision this state was observed against: the plan's latest, else 409."
    )
    state: dict[str, Any] = Field(
        ...,
        description="The `tmpnav replan` state (docs/replan.md) as JSON: time (s since that revision's start), "
        "robots (pose, covariance 3x3 or AMCL's 6x6 / 36 numbers, or status: down), visited, doors, goals.",
        json_schema_extra={"example": STATE_EXAMPLE},
    )
    time_budget: float | None = Field(None, gt=0, description="Seconds for the anytime search; absent: replan's.")


class PlanInfo(BaseModel):
    """A plan held by the service and its latest revision."""

    id: str
    revision: int = Field(description="The latest revision: 0 for the first plan.")
    status: str
    cost: float
    makespan: float
    robots: list[str]
    links: dict[str, str]


class Job(BaseModel):
    """A search running in the background, or its end."""

    id: str
    plan: str
    kind: str = Field(description="plan or revision")
    status: str = Field(description="running, done, failed or cancelled")
    seconds: float
    result: dict[str, Any] | None = None
    problem: dict[str, Any] | None = None


class Problem(BaseModel):
    """An error, as RFC 9457 problem details (``application/problem+json``)."""

    type: str = "about:blank"
    title: str
    status: int
    detail: str = Field(description="The command line's one-line message(s), one per line.")
    exit_code: int = Field(description="The exit code `tmpnav` gives for the same error (docs/usage.md).")
    errors: list[str] = Field(description="Each one-line message.")
    latest: int | None = Field(None, description="With 409 for a stale update: the plan's latest revision.")
