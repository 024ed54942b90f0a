"""A crash loses no accepted plan: the service killed (SIGKILL) in the middle of a revision and
started again on the same cache directory has every plan and revision it had answered for,
none half-written, and goes on numbering revisions from there."""

from __future__ import annotations

import json
import signal
import threading
import time
from pathlib import Path

from tests.serve.server import Server
from tmpnav.client import Client, ServiceError


def stored_files(cache: Path) -> list[Path]:
    return sorted(p for p in (cache / "serve").rglob("*.json") if not p.name.startswith("."))


def test_a_service_killed_mid_revision_restarts_with_every_accepted_revision(tmp_path: Path) -> None:
    accepted: dict[int, dict] = {}
    server = Server("configs/two-rooms.yaml", tmp_path)
    try:
        client = Client(server.url)
        plan = client.plan()
        accepted[0] = client.document(plan["id"])
        one = client.post_state(plan["id"], 0, {"time": 6.0})
        accepted[1] = client.document(plan["id"])
        answers: list[object] = []

        def post() -> None:
            try:
                answers.append(client.post_state(plan["id"], one["revision"], {"time": 4.0}))
            except (ServiceError, OSError) as err:
                answers.append(err)

        poster = threading.Thread(target=post)
        poster.start()
        time.sleep(1.0)  # the revision is under way (it takes seconds): kill the service in it
        server.kill()
        poster.join(60)
    finally:
        server._group(signal.SIGKILL)
        server.stop()
    if answers and isinstance(answers[0], dict):  # it ended before the kill: accepted too
        accepted[2] = {}
    for path in stored_files(tmp_path):
        json.loads(path.read_text())  # none half-written
    restarted = Server("configs/two-rooms.yaml", tmp_path)
    try:
        client = Client(restarted.url)
        plans = client.plans()
        assert [p["id"] for p in plans] == [plan["id"]]
        latest = plans[0]["revision"]
        assert latest >= max(accepted)
        for number, doc in accepted.items():
            if doc:
                assert client.document(plan["id"], number) == doc
        after = client.post_state(plan["id"], latest, {"time": 2.0})
        assert after["revision"] == latest + 1
        assert client.document(plan["id"])["revision"]["number"] == latest + 1
    finally:
        restarted.stop()
