"""write_outputs: every file complete or none of this run; an earlier plan.json is never half-replaced."""

from __future__ import annotations

import json
import multiprocessing
import os
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from tmpnav import atomic
from tmpnav.errors import OutputError
from tmpnav.report import figures, outputs
from tmpnav.report.outputs import write_outputs
from tmpnav.results import PlanReport

PDDL = ("(define (domain rooms))\n", "(define (problem three-rooms) (:domain rooms))\n")
NAMES = ["plan.json", "plan.png", "schedule.png", "domain.pddl", "problem.pddl"]
CORE_TO_SPARE = outputs.core_to_spare  # the real one: the tests replace it (a_core_to_spare)

pytestmark = pytest.mark.slow  # every test writes the session's real plan


@pytest.fixture(autouse=True)
def a_core_to_spare(monkeypatch: pytest.MonkeyPatch) -> None:
    """schedule.png drawn aside whatever else runs on the machine (the tests run in parallel)."""
    monkeypatch.setattr(outputs, "core_to_spare", lambda: True)


def earlier_run(out: Path) -> dict[str, bytes]:
    """Files of an earlier run in ``out``: what must survive a failed write."""
    out.mkdir(parents=True, exist_ok=True)
    old = {
        "plan.json": b'{"schema": "tmpnav-plan/1", "earlier": true}\n',
        "plan.png": b"\x89PNG\r\n\x1a\nearlier",
        "schedule.png": b"\x89PNG\r\n\x1a\nearlier schedule",
        "domain.pddl": b"(define (domain earlier))\n",
        "problem.pddl": b"(define (problem earlier))\n",
    }
    for name, content in old.items():
        (out / name).write_bytes(content)
    return old


def contents(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}


def test_writes_all_files(plan_report: PlanReport, tmp_path: Path) -> None:
    out = tmp_path / "new" / "out"  # missing: created
    written = write_outputs(plan_report, out, PDDL)
    assert written == [out / name for name in NAMES]
    assert sorted(os.listdir(out)) == sorted(NAMES)  # no temporary file left
    doc = json.loads((out / "plan.json").read_text(encoding="utf-8"))
    assert doc["schema"] == "tmpnav-plan/2" and len(doc["actions"]) == len(plan_report.actions)
    assert (out / "plan.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "schedule.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "domain.pddl").read_text() == PDDL[0] and (out / "problem.pddl").read_text() == PDDL[1]


def test_files_get_the_umask_mode_not_mkstemp_0600(plan_report: PlanReport, tmp_path: Path) -> None:
    old = os.umask(0o022)
    try:
        write_outputs(plan_report, tmp_path, PDDL)
    finally:
        os.umask(old)
    assert {(tmp_path / n).stat().st_mode & 0o777 for n in NAMES} == {0o644}


def test_without_pddl(plan_report: PlanReport, tmp_path: Path) -> None:
    written = write_outputs(plan_report, tmp_path, None)
    assert written == [tmp_path / "plan.json", tmp_path / "plan.png", tmp_path / "schedule.png"]
    assert sorted(os.listdir(tmp_path)) == ["plan.json", "plan.png", "schedule.png"]


def test_replaces_an_earlier_run(plan_report: PlanReport, tmp_path: Path) -> None:
    old = earlier_run(tmp_path)
    write_outputs(plan_report, tmp_path, PDDL)
    new = contents(tmp_path)
    assert set(new) == set(NAMES)
    assert all(new[name] != old[name] for name in NAMES)


def test_figure_failure_leaves_the_earlier_run_untouched(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    old = earlier_run(tmp_path)

    def broken_render(fig: object, path: Path, dpi: int = 110) -> None:
        path.write_bytes(b"\x89PNG half a figure")  # some bytes, then the failure
        raise RuntimeError("matplotlib fell over")

    monkeypatch.setattr(figures, "render", broken_render)
    with pytest.raises(RuntimeError, match="fell over"):
        write_outputs(plan_report, tmp_path, PDDL)
    assert contents(tmp_path) == old  # same files, same bytes, no temporary file


def test_a_schedule_figure_that_fails_leaves_the_earlier_run_untouched(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """schedule.png is drawn in a process forked for it while plan.png is drawn here: its failure,
    half-way through its bytes, is raised here once plan.json and plan.png are staged, none of the
    new files replaces an earlier one, and no half-written schedule.png is left."""
    old = earlier_run(tmp_path)
    real = figures.render
    drawn: list[str] = []

    def render_then_fail_on_the_schedule(fig: Any, out: Any, dpi: int = 110) -> None:
        title = fig.axes[0].get_title()
        drawn.append(title)
        if "schedule of" in title:
            out.write(b"\x89PNG half a schedule")
            raise RuntimeError("the schedule fell over")
        real(fig, out, dpi)

    monkeypatch.setattr(figures, "render", render_then_fail_on_the_schedule)
    with pytest.raises(RuntimeError, match="schedule fell over"):
        write_outputs(plan_report, tmp_path, PDDL)
    assert len(drawn) == 1 and "schedule of" not in drawn[0]  # only plan.png was drawn in this process
    assert contents(tmp_path) == old
    assert multiprocessing.active_children() == []


def test_a_drawing_process_that_dies_fails_the_write(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The process drawing schedule.png ends without a word (killed, out of memory): the write
    fails naming the file, and the earlier run stays."""
    old = earlier_run(tmp_path)
    real = figures.render

    def die_on_the_schedule(fig: Any, out: Any, dpi: int = 110) -> None:
        if "schedule of" in fig.axes[0].get_title():
            os._exit(3)
        real(fig, out, dpi)

    monkeypatch.setattr(figures, "render", die_on_the_schedule)
    with pytest.raises(OutputError, match=r"schedule\.png ended without it \(exit status 3\)"):
        write_outputs(plan_report, tmp_path, PDDL)
    assert contents(tmp_path) == old


def test_a_failure_here_ends_the_drawing_process(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """plan.png fails while schedule.png is still being drawn: the drawing process is ended, not
    waited for, and none is left."""
    old = earlier_run(tmp_path)
    real = figures.render

    def slow_schedule_broken_plan(fig: Any, out: Any, dpi: int = 110) -> None:
        if "schedule of" in fig.axes[0].get_title():
            time.sleep(60)
            real(fig, out, dpi)
        raise RuntimeError("the plan fell over")

    monkeypatch.setattr(figures, "render", slow_schedule_broken_plan)
    began = time.perf_counter()
    with pytest.raises(RuntimeError, match="plan fell over"):
        write_outputs(plan_report, tmp_path, PDDL)
    assert time.perf_counter() - began < 30
    assert multiprocessing.active_children() == []
    assert contents(tmp_path) == old


def test_an_error_that_does_not_pickle_comes_back_as_its_text(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    class Unpicklable(Exception):
        def __reduce__(self) -> Any:
            raise TypeError("no pickling")

    real = figures.render

    def fail_oddly_on_the_schedule(fig: Any, out: Any, dpi: int = 110) -> None:
        if "schedule of" in fig.axes[0].get_title():
            raise Unpicklable("a font went missing")
        real(fig, out, dpi)

    monkeypatch.setattr(figures, "render", fail_oddly_on_the_schedule)
    with pytest.raises(OutputError, match="Unpicklable: a font went missing"):
        write_outputs(plan_report, tmp_path, PDDL)
    assert os.listdir(tmp_path) == []


def test_with_no_core_to_spare_both_figures_are_drawn_here(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    real = figures.render
    drawn: list[str] = []

    def render(fig: Any, out: Any, dpi: int = 110) -> None:
        drawn.append(fig.axes[0].get_title())
        real(fig, out, dpi)

    monkeypatch.setattr(figures, "render", render)
    monkeypatch.setattr(outputs, "core_to_spare", lambda: False)
    write_outputs(plan_report, tmp_path, PDDL)
    assert len(drawn) == 2 and "schedule of" in drawn[1]
    assert sorted(os.listdir(tmp_path)) == sorted(NAMES)


def test_a_core_to_spare_needs_a_second_core(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0})
    assert CORE_TO_SPARE() is False


def test_outside_the_main_thread_both_figures_are_drawn_here(plan_report: PlanReport, tmp_path: Path) -> None:
    """A library caller's thread does not fork (its process's other threads may hold locks): the
    same files, drawn in this process."""
    with ThreadPoolExecutor(1) as pool:
        pool.submit(write_outputs, plan_report, tmp_path / "thread", PDDL).result()
    write_outputs(plan_report, tmp_path / "main", PDDL)
    assert contents(tmp_path / "thread").keys() == set(NAMES)
    for name in ("plan.png", "schedule.png"):
        assert (tmp_path / "thread" / name).read_bytes() == (tmp_path / "main" / name).read_bytes()


def test_failure_while_writing_a_file_leaves_no_partial_file(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    old = earlier_run(tmp_path)
    real = atomic._stage
    calls: list[str] = []

    def disk_full_on_problem(tmp: Path, content: atomic.Content) -> None:
        calls.append(tmp.name.split(".tmpnav-")[0].lstrip("."))
        if calls[-1] == "problem.pddl":  # the others are staged, problem.pddl fails half-way
            assert isinstance(content, str)
            tmp.write_text(content[: len(content) // 2])
            raise OSError(28, "No space left on device", str(tmp))
        real(tmp, content)

    monkeypatch.setattr(atomic, "_stage", disk_full_on_problem)
    with pytest.raises(OSError, match="No space left") as caught:
        write_outputs(plan_report, tmp_path, PDDL)
    assert calls == NAMES
    assert caught.value.filename == str(tmp_path / "problem.pddl")  # the file asked for, not a temporary one
    assert contents(tmp_path) == old
    assert json.loads((tmp_path / "plan.json").read_text())["earlier"] is True


def test_partial_plan_json_never_replaces_the_earlier_one(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    old = earlier_run(tmp_path)

    def interrupted(tmp: Path, content: atomic.Content) -> None:
        tmp.write_text(str(content)[:100])
        raise KeyboardInterrupt

    monkeypatch.setattr(atomic, "_stage", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_outputs(plan_report, tmp_path, None)
    assert contents(tmp_path) == old


def test_a_late_rename_failure_puts_the_earlier_files_back(plan_report: PlanReport, tmp_path: Path) -> None:
    """The last rename fails (problem.pddl is a directory): the three files already replaced
    get their earlier content back, and the error names problem.pddl."""
    old = earlier_run(tmp_path)
    (tmp_path / "problem.pddl").unlink()
    (tmp_path / "problem.pddl").mkdir()
    (tmp_path / "problem.pddl" / "keep").write_text("x")
    del old["problem.pddl"]
    with pytest.raises(OSError) as caught:
        write_outputs(plan_report, tmp_path, PDDL)
    assert caught.value.filename == str(tmp_path / "problem.pddl")
    assert contents(tmp_path) == old
    assert sorted(os.listdir(tmp_path)) == sorted(NAMES)  # no temporary or backup file left


def test_failure_removes_the_directory_it_created(
    plan_report: PlanReport, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken_figure(report: PlanReport, crop: bool = True) -> None:
        raise RuntimeError("no figure")

    monkeypatch.setattr(outputs, "plan_figure", broken_figure)
    out = tmp_path / "fresh"
    with pytest.raises(RuntimeError):
        write_outputs(plan_report, out, PDDL)
    assert not out.exists()
    assert os.listdir(tmp_path) == []


def test_wrong_pddl_arity_writes_nothing(plan_report: PlanReport, tmp_path: Path) -> None:
    with pytest.raises(ValueError):
        write_outputs(plan_report, tmp_path, ("only a domain",))  # type: ignore[arg-type]
    assert os.listdir(tmp_path) == []
