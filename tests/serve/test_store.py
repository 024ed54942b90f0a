"""The service's store on its own: plans and revisions written as groups, read back at start,
a killed writer's temporary file ignored, revision numbers without gaps."""

from __future__ import annotations

from pathlib import Path

from tests.serve.server import ROOT
from tmpnav.serve.store import Store

SITE = ROOT / "configs" / "two-rooms.yaml"


def test_plans_and_revisions_are_read_back(tmp_path: Path) -> None:
    store = Store(tmp_path, SITE)
    plan_id = store.new_id()
    plan = store.add(plan_id, {"goals": None}, {"status": "solved", "n": 0})
    assert store.add_revision(plan, {"time": 1.0}, {"status": "solved", "n": 1}) == 1
    assert store.add_revision(plan, {"time": 2.0}, {"status": "solved", "n": 2}) == 2
    # a writer killed in the middle of revision 3 leaves only its temporary file
    (plan.folder / ".rev-0003.json.tmpnav-999999-0a1b.tmp").write_text('{"status": "sol')
    again = Store(tmp_path, SITE)
    reread = again.plans[plan_id]
    assert reread.latest == 2 and reread.current["n"] == 2 and reread.request == {"goals": None}
    assert [reread.document(n)["n"] for n in range(3)] == [0, 1, 2]
    assert again.new_id() == "p2"
    assert again.add_revision(reread, {"time": 3.0}, {"n": 3}) == 3


def test_a_plan_id_without_a_plan_is_not_a_plan(tmp_path: Path) -> None:
    store = Store(tmp_path, SITE)
    first = store.new_id()  # its search was killed before the plan was stored
    assert Store(tmp_path, SITE).plans == {}
    assert Store(tmp_path, SITE).new_id() != first
