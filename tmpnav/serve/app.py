"""The HTTP routes of ``tmpnav serve`` (FastAPI): plans, revisions, jobs, their event streams,
the site's geometry and the live view. docs/serve.md describes them; the OpenAPI document
(docs/openapi.json) is generated from this module.

    app = create_app(Service.start("configs/two-rooms.yaml", cache_dir=None), token=None)
"""

from __future__ import annotations

import asyncio
from importlib import resources
from typing import Any

from fastapi import FastAPI, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, Response, StreamingResponse
from starlette.exceptions import HTTPException as StarletteHTTPException

from tmpnav.errors import TmpnavError
from tmpnav.serve import models, problems
from tmpnav.serve.guard import Guard
from tmpnav.serve.service import Busy, NotFound, Service, Stale
from tmpnav.serve.sitemap import site_geometry
from tmpnav.version import __version__

#: how long a request that waits for its search waits at most between looks at its client
WAIT_SLICE = 1.0


def create_app(service: Service, token: str | None = None) -> FastAPI:
    """The service's FastAPI application; ``token``: every request must carry it."""
    app = FastAPI(
        title="tmpnav serve",
        version=__version__,
        summary="Multi-robot task-motion planning in belief space, as a service",
        description="Plan a shift of a site, post the team's state, get the revision. docs/serve.md.",
        responses=problems.RESPONSES,
    )
    app.add_middleware(Guard, token=token, max_body=service.limits.max_body)
    _errors(app)
    _plans(app, service)
    _jobs(app, service)
    _view(app, service)
    _describe_problems(app)
    return app


def _describe_problems(app: FastAPI) -> None:
    """The Problem schema in the OpenAPI document, which every route's error answers name."""
    from fastapi.openapi.utils import get_openapi

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is None:
            doc = get_openapi(
                title=app.title,
                version=app.version,
                summary=app.summary,
                description=app.description,
                routes=app.routes,
            )
            doc.setdefault("components", {}).setdefault("schemas", {})["Problem"] = models.Problem.model_json_schema()
            app.openapi_schema = doc
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]


def _errors(app: FastAPI) -> None:
    @app.exception_handler(TmpnavError)
    async def tmpnav_error(request: Request, err: TmpnavError) -> JSONResponse:
        return problems.respond(problems.of_error(err))

    @app.exception_handler(Stale)
    async def stale(request: Request, err: Stale) -> JSONResponse:
        return problems.answer(409, str(err), latest=err.latest)

    @app.exception_handler(Busy)
    async def busy(request: Request, err: Busy) -> JSONResponse:
        return problems.answer(503, str(err), 1, headers={"Retry-After": "10"})

    @app.exception_handler(NotFound)
    async def not_found(request: Request, err: NotFound) -> JSONResponse:
        return problems.answer(404, str(err))

    @app.exception_handler(RequestValidationError)
    async def malformed(request: Request, err: RequestValidationError) -> JSONResponse:
        lines = [_validation_line(e) for e in err.errors()] or ["body: not valid"]
        return problems.respond(problems.problem(422, lines, 2))

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, err: StarletteHTTPException) -> JSONResponse:
        if err.status_code == 400:  # FastAPI's "error parsing the body": bytes that are not UTF-8 text
            return problems.answer(422, "body: not JSON (not UTF-8 text)")
        return problems.answer(err.status_code, str(err.detail), 2, headers=dict(err.headers or {}))

    @app.exception_handler(Exception)
    async def bug(request: Request, err: Exception) -> JSONResponse:
        return problems.respond(problems.internal(err))


def _validation_line(error: Any) -> str:
    where = ".".join(str(p) for p in error.get("loc", ()) if p != "body") or "(top level)"
    kind = error.get("type", "")
    if kind == "json_invalid":
        return f"body: not JSON ({error.get('ctx', {}).get('error', 'invalid')})"
    return f"body: {where}: {error.get('msg', 'not valid')}"


async def _answer(request: Request, service: Service, job_id: str, wait: bool, created: int) -> JSONResponse:
    """The job's result when it ends (``created``), its problem if it fails; or at once (202)."""
    job = service.job(job_id)
    # waited for in a worker thread, a slice at a time: the answer leaves as soon as the job ends
    while wait and not await asyncio.to_thread(job.done.wait, WAIT_SLICE):
        if await request.is_disconnected():  # the client went: its search is not wanted
            service.cancel(job_id)
            break
    if not job.done.is_set():
        return JSONResponse(job.summary(), status_code=202, headers={"Location": f"/jobs/{job.id}"})
    if job.status == "done":
        return JSONResponse(job.result, status_code=created)
    return problems.respond(job.problem or problems.problem(500, ["the search ended without a result"], 1))


def _plans(app: FastAPI, service: Service) -> None:
    @app.post(
        "/plans",
        status_code=201,
        response_model=models.PlanInfo,
        tags=["plans"],
        responses={202: {"model": models.Job, "description": "with wait: false, the job planning it"}},
    )
    async def plan(request: Request, body: models.PlanRequest) -> JSONResponse:
        """Plan a shift: the scenario's goals, or those of the body (its `goals` section)."""
        job = await asyncio.to_thread(service.plan, body.goals, body.time_budget)
        return await _answer(request, service, job.id, body.wait, 201)

    @app.get("/plans", response_model=list[models.PlanInfo], tags=["plans"])
    def plans() -> list[dict[str, Any]]:
        """Every plan the service holds, with its latest revision."""
        return [service.info(p) for p in list(service.store.plans.values())]

    @app.get("/plans/{plan_id}", tags=["plans"])
    def plan_json(plan_id: str, revision: int | None = Query(None, ge=0)) -> dict[str, Any]:
        """The plan's plan.json (docs/plan-json.md): its latest revision, or `revision`."""
        return service.document(plan_id, revision)

    @app.get("/plans/{plan_id}/schedule", tags=["plans"])
    def schedule(plan_id: str, revision: int | None = Query(None, ge=0)) -> dict[str, Any]:
        """The plan's schedule on the team's clock (plan.json's `schedule`)."""
        doc: dict[str, Any] = service.document(plan_id, revision).get("schedule", {})
        return doc

    @app.get("/plans/{plan_id}/nav2", tags=["plans"])
    def nav2(plan_id: str, revision: int | None = Query(None, ge=0)) -> dict[str, dict[str, str]]:
        """The plan's nav2 files (`tmpnav export`), file name -> text; a revision's names carry its number."""
        from tmpnav.export.nav2 import files

        number = service.get(plan_id).latest if revision is None else revision
        out = files(service.document(plan_id, number))
        return {"files": {_tagged(name, number): text for name, text in out.items()}}

    @app.post("/plans/{plan_id}/states", status_code=201, response_model=models.PlanInfo, tags=["plans"])
    async def state(request: Request, plan_id: str, body: models.StateUpdate) -> JSONResponse:
        """Post the team's state; get the revision planned from it (its number one more than `revision`)."""
        service.get(plan_id)
        job = service.revise(plan_id, body.revision, body.state, body.time_budget)
        return await _answer(request, service, job.id, True, 201)

    @app.get("/plans/{plan_id}/events", tags=["plans"], response_class=StreamingResponse)
    def plan_events(request: Request, plan_id: str) -> StreamingResponse:
        """Server-sent events: `revision` (a PlanInfo) each time a revision is accepted, the latest first."""
        stored = service.get(plan_id)
        feed = service.feed(plan_id)
        if not feed.events:
            feed.put("revision", service.info(stored))
        return _sse(feed.stream(request.is_disconnected, start=len(feed.events) - 1))


def _tagged(name: str, number: int) -> str:
    if number == 0:
        return name
    stem, dot, suffix = name.rpartition(".")
    return f"{stem}.rev{number}{dot}{suffix}" if dot else f"{name}.rev{number}"


def _sse(events: Any) -> StreamingResponse:
    return StreamingResponse(events, media_type="text/event-stream", headers={"Cache-Control": "no-store"})


def _jobs(app: FastAPI, service: Service) -> None:
    @app.get("/jobs/{job_id}", response_model=models.Job, tags=["jobs"])
    def job(job_id: str) -> dict[str, Any]:
        """A search: running, done (its result), failed or cancelled (its problem)."""
        return service.job(job_id).summary()

    @app.delete("/jobs/{job_id}", response_model=models.Job, status_code=202, tags=["jobs"])
    def cancel(job_id: str) -> dict[str, Any]:
        """Cancel a running search: it stops at its next progress event, and nothing is stored."""
        return service.cancel(job_id).summary()

    @app.get("/jobs/{job_id}/events", tags=["jobs"], response_class=StreamingResponse)
    def job_events(request: Request, job_id: str) -> StreamingResponse:
        """Server-sent events of a search: `progress` (costs done, the search's best plan), then
        `done` (a PlanInfo), `failed` or `cancelled` (a Problem)."""
        return _sse(service.job(job_id).feed.stream(request.is_disconnected))


def _view(app: FastAPI, service: Service) -> None:
    @app.get("/health", tags=["service"])
    def health() -> dict[str, Any]:
        """The service is up: its site, version and how many plans it holds."""
        return {
            "status": "ok",
            "site": service.site.scenario.name,
            "version": __version__,
            "plans": len(service.store.plans),
        }

    @app.get("/site", tags=["service"])
    def site() -> dict[str, Any]:
        """The site for the view: bounds, rooms, doors, landmarks, stations, robots' starts."""
        return site_geometry(service.site)

    @app.get("/site/map.png", tags=["service"], response_class=Response)
    def map_png() -> Response:
        """The occupancy grid as a PNG image (walls dark), covering the site's bounds."""
        from tmpnav.serve.sitemap import map_png as png

        return Response(png(service.site), media_type="image/png", headers={"Cache-Control": "max-age=3600"})

    @app.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index() -> HTMLResponse:
        return HTMLResponse(_asset("index.html"))

    @app.get("/view/{name}", include_in_schema=False)
    def asset(name: str) -> Response:
        kinds = {"js": "text/javascript", "css": "text/css"}
        suffix = name.rpartition(".")[2]
        if "/" in name or suffix not in kinds:
            raise NotFound(f"no view file {name!r}")
        return Response(_asset(name), media_type=kinds[suffix])


def _asset(name: str) -> str:
    try:
        return resources.files("tmpnav.serve.view").joinpath(name).read_text(encoding="utf-8")
    except (FileNotFoundError, OSError):
        raise NotFound(f"no view file {name!r}") from None
