"""Errors as RFC 9457 problem details: the command line's one-line messages and exit codes, with
the HTTP status a client acts on (the table is in docs/serve.md, "Errors")."""

from __future__ import annotations

from http import HTTPStatus
from typing import Any

from fastapi.responses import JSONResponse

from tmpnav.errors import (
    CacheError,
    ConflictError,
    InputError,
    PlannerCrashError,
    PlannerError,
    PlannerTimeoutError,
    PlannerUnavailableError,
    RiskError,
    ScenarioError,
    TmpnavError,
    UnsolvableError,
    WindowError,
)
from tmpnav.replan.revise import NothingLeft
from tmpnav.serve.site import Cancelled

#: an error class -> the HTTP status of its answer; the first class the error is an instance of
STATUS: tuple[tuple[type[TmpnavError], int], ...] = (
    (Cancelled, 409),  # the search was cancelled: no plan, nothing written
    (InputError, 422),  # the request is well-formed JSON but its goals or state are not valid
    (UnsolvableError, 422),
    (RiskError, 422),
    (ConflictError, 422),
    (WindowError, 422),
    (PlannerUnavailableError, 503),
    (PlannerTimeoutError, 504),
    (PlannerCrashError, 502),
    (PlannerError, 500),
    (CacheError, 500),
)

MEDIA_TYPE = "application/problem+json"


def problem(status: int, lines: list[str], exit_code: int, **extra: Any) -> dict[str, Any]:
    """The problem details document (a dict) of an error."""
    doc: dict[str, Any] = {
        "type": "about:blank",
        "title": HTTPStatus(status).phrase,
        "status": status,
        "detail": "\n".join(lines),
        "exit_code": exit_code,
        "errors": lines,
    }
    doc.update({k: v for k, v in extra.items() if v is not None})
    return doc


def of_error(err: TmpnavError) -> dict[str, Any]:
    """The problem details of a library error: its one-line messages, its exit code."""
    status = next((code for kind, code in STATUS if isinstance(err, kind)), 500)
    lines = [str(p) for p in err.problems] if isinstance(err, ScenarioError) else [str(err)]
    doc = problem(status, lines, err.exit_code)
    if isinstance(err, NothingLeft):  # a state with no goal left: a client's loop ends, it did not fail
        doc["type"] = NothingLeft.problem_type
    return doc


def internal(err: BaseException) -> dict[str, Any]:
    """A bug's problem details, one line as the command line prints it."""
    return problem(500, [f"internal error: {type(err).__name__}: {err}"], 1)


def respond(doc: dict[str, Any], headers: dict[str, str] | None = None) -> JSONResponse:
    return JSONResponse(doc, status_code=doc["status"], media_type=MEDIA_TYPE, headers=headers)


def answer(
    status: int, message: str, exit_code: int = 2, headers: dict[str, str] | None = None, **extra: Any
) -> JSONResponse:
    """A problem of the request itself (not found, too large, unauthorised ...), one line."""
    return respond(problem(status, [message], exit_code, **extra), headers)


#: the answers every route may give, for the OpenAPI document
RESPONSES: dict[int | str, dict[str, Any]] = {
    code: {"description": text, "content": {MEDIA_TYPE: {"schema": {"$ref": "#/components/schemas/Problem"}}}}
    for code, text in (
        (401, "no or wrong token (with --token)"),
        (404, "no such plan or job"),
        (405, "a method the path does not take"),
        (409, "a stale update (the plan's latest revision in `latest`), or a cancelled search"),
        (413, "the body is larger than the service's limit"),
        (422, "malformed body, or goals or a state that are not valid, or no plan for them"),
        (500, "the planner or the service failed"),
        (503, "no usable planner (Java 17+ missing), or too many searches running or waiting (Retry-After)"),
        (504, "the search ran past the service's time limit"),
    )
}
