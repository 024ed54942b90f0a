"""Runs in the background and what they tell: a :class:`Job` per search (its progress, its end),
a :class:`Feed` per plan (its revisions as they are accepted), both read as server-sent events.

A feed is a list that only grows; a reader keeps its place in it and waits for more, so a slow
reader misses nothing and holds up no writer.
"""

from __future__ import annotations

import asyncio
import json
import threading
import time
from collections.abc import AsyncIterator
from dataclasses import dataclass, field
from typing import Any

from tmpnav.serve.site import Watch

#: how often a server-sent event stream looks for new events, and sends a comment to keep the
#: connection open through proxies when there are none
POLL_SECONDS, KEEPALIVE_SECONDS = 0.2, 15.0


@dataclass
class Feed:
    """Events in the order they happened; ``closed`` once no more will come."""

    events: list[tuple[str, dict[str, Any]]] = field(default_factory=list)
    closed: bool = False
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def put(self, kind: str, data: dict[str, Any]) -> None:
        with self._lock:
            self.events.append((kind, data))

    def close(self) -> None:
        self.closed = True

    async def stream(self, disconnected: Any, start: int = 0) -> AsyncIterator[str]:
        """The feed as server-sent events from its ``start``-th, until it is closed or the
        client goes (``disconnected``: the request's coroutine telling so)."""
        place, quiet = start, time.monotonic()
        while True:
            events = self.events[place:]
            for kind, data in events:
                place += 1
                yield f"id: {place}\nevent: {kind}\ndata: {json.dumps(data, allow_nan=False)}\n\n"
            if events:
                quiet = time.monotonic()
            elif self.closed or await disconnected():
                return
            elif time.monotonic() - quiet > KEEPALIVE_SECONDS:
                quiet = time.monotonic()
                yield ": keep-alive\n\n"
            await asyncio.sleep(POLL_SECONDS)


@dataclass
class Job:
    """A search running in the background: a plan or a revision of one."""

    id: str
    plan: str
    kind: str  # "plan" | "revision"
    feed: Feed = field(default_factory=Feed)
    watch: Watch = field(default_factory=Watch)
    status: str = "running"  # running | done | failed | cancelled
    result: dict[str, Any] | None = None  # what the client is answered when done
    problem: dict[str, Any] | None = None  # the problem details when failed or cancelled
    started: float = field(default_factory=time.monotonic)
    done: threading.Event = field(default_factory=threading.Event, repr=False)

    def __post_init__(self) -> None:
        self.watch.tell = lambda event: self.feed.put("progress", event)

    def finish(self, status: str, result: dict[str, Any] | None = None, problem: dict[str, Any] | None = None) -> None:
        self.status, self.result, self.problem = status, result, problem
        self.feed.put(status, result if result is not None else (problem or {}))
        self.feed.close()
        self.done.set()

    def summary(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "plan": self.plan,
            "kind": self.kind,
            "status": self.status,
            "seconds": round(time.monotonic() - self.started, 3),
            "result": self.result,
            "problem": self.problem,
        }
