"""What the service does, without HTTP: plan a shift, revise a plan from a team state, cancel
a search; each accepted plan and revision stored (:mod:`tmpnav.serve.store`) and told to the
plan's feed (:mod:`tmpnav.serve.events`).

Searches run in threads of their own, one planning at a time (:class:`tmpnav.serve.site.Site`);
a search past ``time_limit`` seconds is cancelled. Updates to one plan are applied one at a
time: each names the revision it was observed against, and one that is not the latest is
refused (:class:`Stale`), so none is applied twice or to a plan it did not see.
"""

from __future__ import annotations

import itertools
import json
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tmpnav.errors import TmpnavError
from tmpnav.results import PlanReport
from tmpnav.serve import problems
from tmpnav.serve.events import Feed, Job
from tmpnav.serve.site import Site
from tmpnav.serve.store import Store, StoredPlan


class Stale(Exception):
    """An update observed against a revision that is not the plan's latest."""

    def __init__(self, plan: str, given: int, latest: int):
        super().__init__(
            f"plan {plan}: the state was observed against revision {given}, the plan is at revision {latest}; "
            f"post it again against revision {latest}"
        )
        self.latest = latest


class Busy(Exception):
    """As many searches running or waiting as the service takes."""


class NotFound(Exception):
    """No such plan, revision or job."""


@dataclass
class Limits:
    """What the service allows one request."""

    time_limit: float = 300.0  # s a search may run before it is cancelled
    max_body: int = 1 << 20  # bytes of a request body
    max_queue: int = 64  # searches running or waiting their turn; more are refused (503)


@dataclass
class Service:
    """A site's plans, searches and feeds."""

    site: Site
    store: Store
    limits: Limits = field(default_factory=Limits)
    jobs: dict[str, Job] = field(default_factory=dict)
    feeds: dict[str, Feed] = field(default_factory=dict)
    _job_ids: itertools.count = field(default_factory=lambda: itertools.count(1))

    @classmethod
    def start(cls, scenario: str | Path, cache_dir: Path | None, limits: Limits | None = None) -> Service:
        from tmpnav.cachedir import CacheDir

        site = Site(scenario, cache_dir)
        return cls(site, Store(CacheDir.at(cache_dir).root, site.path), limits or Limits())

    def plan(self, goals: dict[str, Any] | None, time_budget: float | None) -> Job:
        """Start planning a shift; the job ends with the plan stored, or with its problem."""
        if goals is not None:
            self.site.loaded(goals)  # bad goals are the request's problem (422), before any job
        plan_id = self.store.new_id()
        try:
            job = self._job(plan_id, "plan")
        except Busy:
            self.store.drop(plan_id)
            raise

        def run() -> dict[str, Any]:
            try:
                report = self.site.plan(goals, self._budget(time_budget), job.watch)
                stored = self.store.add(plan_id, {"goals": goals}, _document(report))
            except BaseException:
                self.store.drop(plan_id)
                raise
            self.feed(plan_id).put("revision", self.info(stored))
            return self.info(stored)

        self._run(job, run)
        return job

    def revise(self, plan_id: str, based_on: int, state: dict[str, Any], time_budget: float | None) -> Job:
        """Start revising a plan from the team's state observed against revision ``based_on``."""
        stored = self.get(plan_id)
        if based_on != stored.latest:  # stale already: refused without waiting for the plan's turn
            raise Stale(plan_id, based_on, stored.latest)
        job = self._job(plan_id, "revision")

        def run() -> dict[str, Any]:
            with stored.lock:
                if based_on != stored.latest:
                    raise Stale(plan_id, based_on, stored.latest)
                report = self.site.revise(
                    stored.request.get("goals"), stored.path_of(based_on), state, self._budget(time_budget), job.watch
                )
                self.store.add_revision(stored, state, _document(report))
            info = self.info(stored)
            self.feed(plan_id).put("revision", info)
            return info

        self._run(job, run)
        return job

    def cancel(self, job_id: str) -> Job:
        job = self.job(job_id)
        job.watch.why = "cancelled by the client"
        job.watch.cancel.set()
        return job

    def _budget(self, asked: float | None) -> float | None:
        return None if asked is None else min(asked, self.limits.time_limit)

    def _job(self, plan_id: str, kind: str) -> Job:
        if sum(not j.done.is_set() for j in list(self.jobs.values())) >= self.limits.max_queue:
            raise Busy(f"{self.limits.max_queue} searches are running or waiting already; try again later")
        job = Job(f"j{next(self._job_ids)}", plan_id, kind)
        self.jobs[job.id] = job
        while len(self.jobs) > 1000:  # the oldest ended jobs are forgotten
            oldest = next((j for j in self.jobs.values() if j.done.is_set()), None)
            if oldest is None:
                break
            del self.jobs[oldest.id]
        return job

    def _run(self, job: Job, work: Any) -> None:
        def timeout() -> None:
            job.watch.why = f"stopped at the service's time limit ({self.limits.time_limit:g} s)"
            job.watch.cancel.set()

        timer = threading.Timer(self.limits.time_limit, timeout)
        timer.daemon = True

        def body() -> None:
            try:
                job.finish("done", result=work())
            except Stale as err:
                job.finish("failed", problem=problems.problem(409, [str(err)], 2, latest=err.latest))
            except TmpnavError as err:
                doc = problems.of_error(err)
                if job.watch.cancel.is_set():
                    limit = "time limit" in job.watch.why
                    doc = problems.problem(504 if limit else 409, [f"the search was {job.watch.why}"], err.exit_code)
                job.finish("cancelled" if job.watch.cancel.is_set() else "failed", problem=doc)
            except BaseException as err:  # a bug: told as one line, the service goes on
                job.finish("failed", problem=problems.internal(err))
            finally:
                timer.cancel()

        timer.start()
        threading.Thread(target=body, name=f"tmpnav-{job.id}", daemon=True).start()

    def get(self, plan_id: str) -> StoredPlan:
        if plan_id not in self.store.plans:
            raise NotFound(f"no plan {plan_id!r}; GET /plans lists them")
        return self.store.plans[plan_id]

    def job(self, job_id: str) -> Job:
        if job_id not in self.jobs:
            raise NotFound(f"no job {job_id!r}")
        return self.jobs[job_id]

    def document(self, plan_id: str, revision: int | None) -> dict[str, Any]:
        stored = self.get(plan_id)
        number = stored.latest if revision is None else revision
        if not 0 <= number <= stored.latest:
            raise NotFound(f"plan {plan_id} has no revision {number}; its latest is {stored.latest}")
        return stored.document(number)

    def feed(self, plan_id: str) -> Feed:
        return self.feeds.setdefault(plan_id, Feed())

    def info(self, stored: StoredPlan) -> dict[str, Any]:
        doc = stored.current
        base = f"/plans/{stored.id}"
        return {
            "id": stored.id,
            "revision": stored.latest,
            "status": doc.get("status", ""),
            "cost": float(doc.get("cost", {}).get("resimulated", 0.0)),
            "makespan": float(doc.get("schedule", {}).get("makespan", 0.0)),
            "robots": [r["name"] for r in doc.get("robots", [])],
            "links": {
                "plan": base,
                "schedule": f"{base}/schedule",
                "nav2": f"{base}/nav2",
                "states": f"{base}/states",
                "events": f"{base}/events",
                "view": f"/?plan={stored.id}",
            },
        }


def _document(report: PlanReport) -> dict[str, Any]:
    """plan.json as a client reads it (through JSON: plain lists, numbers and strings)."""
    from tmpnav.report.plan_json import plan_document

    doc: dict[str, Any] = json.loads(json.dumps(plan_document(report), allow_nan=False))
    return doc
