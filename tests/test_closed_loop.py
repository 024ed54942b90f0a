"""``tmpnav simulate --events``: the team executes its plan while the world changes and replans
from its beliefs (tmpnav.replan.loop): a door closing on a robot's path, a robot down with goals
left, goals added mid-run, a robot held up until it is late; each session also run blind and with
a plan that knew the events. Bad events files: one line and exit 2."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.test_replan import WORLD
from tmpnav.errors import InputError
from tmpnav.pipeline import PlanOptions, load_world
from tmpnav.replan.events import read_events
from tmpnav.replan.loop import LoopResult, Run, closed_loop

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def scenario(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("loop") / "loop.yaml"
    path.write_text(WORLD)
    return path


def run(scenario: Path, tmp: Path, events: str, sessions: int = 1) -> LoopResult:
    (tmp / "events.yaml").write_text(events)
    loaded, _ = load_world(scenario)
    options = PlanOptions.of(cache_dir=scenario.parent / "cache")
    return closed_loop(scenario, read_events(tmp / "events.yaml", loaded), sessions, 0, options)


def only(result: LoopResult, mode: str) -> Run:
    (one,) = result.runs[mode]
    return one


@pytest.mark.slow
def test_a_door_closing_on_a_robots_path_drops_its_room_and_the_rest_is_done(scenario: Path, tmp_path: Path) -> None:
    """r2 drives to B; at 8 s dB closes. The team replans at once: B is named out of reach, A is
    done, nothing twice, nothing lost. Blind, r2 is stopped by the door until its move is cut."""
    result = run(scenario, tmp_path, "events:\n  - {at: 8, close: dB}\n")
    loop = only(result, "closed loop")
    assert [p.reason for p in loop.replans] == ["dB closed"]
    assert loop.replans[0].unreachable == ("B",) and loop.replans[0].outcome == "planned"
    assert loop.dropped == ("B",) and loop.lost == () and loop.twice == ()
    assert set(loop.done) == {"A"}
    blind = only(result, "blind")
    assert "B" in blind.lost and blind.makespan > loop.makespan
    knowing = only(result, "knowing the events")
    assert knowing.dropped == ("B",) and knowing.lost == ()


#: the same building with a second door into B, further along the corridor
TWO_DOORS = WORLD.replace(
    "    - [[9.6, 4], [14.4, 4]]\n", "    - [[9.6, 4], [10.6, 4]]\n    - [[11.6, 4], [14.4, 4]]\n"
).replace("  - {name: dD,", "  - {name: dB2, segment: [[10.6, 4], [11.6, 4]]}\n  - {name: dD,")


@pytest.mark.slow
def test_a_door_closing_on_a_robots_path_sends_it_the_other_way(tmp_path: Path) -> None:
    """With a second door into B, the nearer one to r2 (dB2) closes at 2 s, on r2's way there: the
    replan drops nothing and goes in by dB; blind, r2 is stopped at dB2 and B is lost."""
    assert TWO_DOORS != WORLD and "dB2" in TWO_DOORS
    scenario = tmp_path / "two-doors.yaml"
    scenario.write_text(TWO_DOORS)
    result = run(scenario, tmp_path, "events:\n  - {at: 2, close: dB2}\n")
    loop = only(result, "closed loop")
    assert [p.reason for p in loop.replans] == ["dB2 closed"] and loop.replans[0].unreachable == ()
    assert sorted(loop.done) == ["A", "B"] and loop.dropped == () and loop.lost == () and loop.twice == ()
    assert only(result, "blind").lost == ("B",)


@pytest.mark.slow
def test_a_robot_down_leaves_its_goals_to_the_other_and_goals_added_mid_run_are_done(
    scenario: Path, tmp_path: Path
) -> None:
    """r2 goes down at 3 s with its goal left; D is added at 6 s: r1 does A, B and D, each once."""
    result = run(scenario, tmp_path, "events:\n  - {at: 3, robot: r2, down: true}\n  - {at: 6, add: [D]}\n")
    loop = only(result, "closed loop")
    assert [p.reason for p in loop.replans] == ["r2 down", "goals +D"]
    assert sorted(loop.done) == ["A", "B", "D"] and loop.lost == () and loop.twice == ()
    blind = only(result, "blind")
    assert "D" in blind.lost  # never known without the replan
    assert sorted(only(result, "knowing the events").done) == ["A", "B", "D"]


@pytest.mark.slow
def test_a_robot_held_up_makes_the_team_replan_when_it_is_late(scenario: Path, tmp_path: Path) -> None:
    result = run(scenario, tmp_path, "late: 5\nevents:\n  - {at: 2, robot: r1, stop: 12}\n")
    loop = only(result, "closed loop")
    assert loop.replans and loop.replans[0].reason.startswith("late by")
    assert loop.replans[0].time >= 2 + 5
    assert sorted(loop.done) == ["A", "B"] and loop.lost == () and loop.twice == ()


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("events: []\n", "events: expected a non-empty list of events"),
        ("events:\n  - {at: 3, robot: r9, down: true}\n", "events[0].robot: 'r9' is not a robot of scenario"),
        ("events:\n  - {at: 3, close: dZ}\n", "events[0].close: 'dZ' is not a door of scenario"),
        ("events:\n  - {at: 3, robot: r1, slow: 2, for: 5}\n", "events[0].slow: 2 is not a share of the speed"),
        ("events:\n  - {at: 3, robot: r1, slow: 0.5}\n", "events[0].for: missing"),
        ("events:\n  - {at: -1, robot: r1, stop: 5}\n", "events[0].at: -1 is not a number of seconds"),
        ("events:\n  - {at: 3, robot: r1, stop: 5, close: dA}\n", "events[0]: two kinds of event in one"),
        ("events:\n  - {at: 3, add: [Q]}\n", "events[0].add: 'Q' is not a room of scenario"),
        ("late: 0\nevents:\n  - {at: 3, add: [D]}\n", "late: 0 is not a number of seconds above 0"),
        ("events:\n  - {at: 3, robot: r1, stop: 5, for: 2}\n", "events[0].for: not a key of a stop event"),
        ("[1, 2]\n", "not an events file"),
        ("events:\n  - {at: 3, robot: r1, speed: 2}\n", "events[0].speed: not a key of an event"),
    ],
)
def test_a_bad_events_file_is_one_line_naming_the_key(scenario: Path, tmp_path: Path, text: str, said: str) -> None:
    path = tmp_path / "events.yaml"
    path.write_text(text)
    loaded, _ = load_world(scenario)
    with pytest.raises(InputError) as caught:
        read_events(path, loaded)
    message = str(caught.value)
    assert message.startswith(f"{path}: ") and said in message and "\n" not in message


@pytest.mark.slow
def test_the_command_line_prints_the_three_modes_and_writes_its_files(scenario: Path, tmp_path: Path) -> None:
    events = tmp_path / "events.yaml"
    events.write_text("events:\n  - {at: 4, add: [D]}\n")
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "simulate", str(scenario), "--events", str(events), "--sessions", "1", "-q",
         "--cache-dir", str(scenario.parent / "cache"), "-o", str(out)],
        capture_output=True, text=True, cwd=ROOT, timeout=600,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    for mode in ("closed loop:", "blind:", "knowing the events:"):
        assert f"  {mode} goals done" in proc.stdout
    assert sorted(p.name for p in out.iterdir()) == ["loop.csv", "loop.json", "replans.csv", "summary.md"]
    doc = json.loads((out / "loop.json").read_text())
    loop = [r for r in doc["runs"] if r["mode"] == "closed loop"]
    assert loop[0]["replans"][0]["reason"] == "goals +D" and "D" in loop[0]["done"]
    bad = tmp_path / "bad.yaml"
    bad.write_text("events:\n  - {at: 4, robot: r7, down: true}\n")
    args = ["simulate", str(scenario), "--events", str(bad), "-q", "-o", str(tmp_path / "o2")]
    proc = subprocess.run([sys.executable, "-m", "tmpnav", *args], capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "robot: 'r7' is not a robot" in proc.stderr
    assert not (tmp_path / "o2").exists()
