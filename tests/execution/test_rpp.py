"""nav2's Regulated Pure Pursuit as ``tmpnav simulate --follower rpp`` drives a move."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tmpnav.belief.models import motion, motion_noise_cov
from tmpnav.belief.pursuit import pursuit_controls
from tmpnav.execution.rpp import CONTROLLER_FREQUENCY, RppFollower, RppParams, densify
from tmpnav.execution.rpp import drive as drive_step

ROOT = Path(__file__).resolve().parents[2]
DT = 0.1
FREE = 5.0  # m: no obstacle near


def follower(points: list[list[float]], speed: float = 0.5, turn_rate: float = 1.0) -> RppFollower:
    return RppFollower(np.array(points, dtype=float), RppParams(), speed, turn_rate, DT)


def drive(f: RppFollower, pose: np.ndarray, steps: int = 2000) -> tuple[np.ndarray, int]:
    """Integrate the unicycle with RPP's commands until nav2's goal checker says it is there."""
    for k in range(steps):
        if f.at_goal(pose):
            return pose, k
        v, w = f.command(pose, FREE)
        pose = pose + np.array([v * math.cos(pose[2]) * DT, v * math.sin(pose[2]) * DT, w * DT])
    return pose, steps


def test_densify_keeps_every_vertex_and_spaces_the_rest_by_a_cell() -> None:
    path, at = densify(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.52]]))
    assert at.tolist() == [0, 20, 31]
    assert np.allclose(path[at], [[0, 0], [1, 0], [1, 0.52]])
    assert np.hypot(*np.diff(path, axis=0).T).max() <= 0.05 + 1e-12


def test_on_a_straight_path_it_drives_at_the_robots_speed_with_no_turn() -> None:
    v, w = follower([[0, 0], [5, 0]]).command(np.array([0.0, 0.0, 0.0]), FREE)
    assert v == pytest.approx(0.5) and w == pytest.approx(0.0)


def test_a_carrot_far_to_the_side_turns_it_on_the_spot_within_the_angular_acceleration() -> None:
    v, w = follower([[0, 0], [0, 5]]).command(np.array([0.0, 0.0, 0.0]), FREE)
    assert v == 0.0 and w == pytest.approx(3.2 * DT)  # from standing: max_angular_accel for one step


def test_it_slows_on_a_tight_arc_and_near_walls_but_not_below_the_minimum_speed() -> None:
    bend = follower([[0, 0], [0.5, 0], [0.5, 2]])  # the carrot round the corner, at (0.5, 0.33): 34 deg off
    v_bend, w_bend = bend.command(np.array([0.0, 0.0, 0.0]), FREE)
    kappa = 2 * math.sqrt(0.6**2 - 0.5**2) / 0.6**2  # an arc of radius 0.54 m, below 0.9 m
    assert v_bend == pytest.approx(0.5 / kappa / 0.9, rel=0.02) and w_bend == pytest.approx(v_bend * kappa, rel=0.02)
    straight = follower([[0, 0], [5, 0]])
    assert straight.command(np.array([0.0, 0.0, 0.0]), 0.45)[0] == pytest.approx(0.5 * 0.45 / 0.6)
    assert straight.command(np.array([0.0, 0.0, 0.0]), 0.2)[0] == pytest.approx(0.25)


def test_an_l_shaped_move_turns_while_it_drives_and_ends_within_the_goal_tolerance() -> None:
    """4 m along x, then 3 m along y: it cuts the bend (passes it abreast, never on it), stops
    within nav2's goal tolerance, and takes less than the 2.9 s a metre of turning on the spot
    at every node (0.5 m/s, 1 rad/s) but more than driving at full speed (2.0 s/m)."""
    f = follower([[0, 0], [4, 0], [4, 3]])
    pose, steps = drive(f, np.array([0.0, 0.0, 0.0]))
    assert np.hypot(pose[0] - 4, pose[1] - 3) <= 0.25
    assert f.passed(1)
    per_metre = steps * DT / (7 - 0.25)
    assert 2.0 < per_metre < 2.3


def test_simulate_with_the_rpp_follower_names_it_and_executes_the_plan(tmp_path: Path) -> None:
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "tmpnav",
            "simulate",
            str(ROOT / "configs" / "two-rooms.yaml"),
            "--sessions",
            "1",
            "--follower",
            "rpp",
            "--cache-dir",
            str(tmp_path / "cache"),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert out.returncode == 0, out.stderr
    assert "follower: nav2 Regulated Pure Pursuit (lookahead 0.6 m" in out.stdout
    assert "makespan" in out.stdout


def two_rooms_with(tmp_path: Path, models: str) -> Path:
    """configs/two-rooms.yaml with a ``models:`` section."""
    text = (ROOT / "configs" / "two-rooms.yaml").read_text()
    path = tmp_path / "two-rooms.yaml"
    path.write_text(text + f"\nmodels: {models}\n")
    return path


def test_a_plan_driven_by_rpp_is_simulated_with_rpp_and_keeps_its_clock(tmp_path: Path) -> None:
    """A scenario whose robots carry a lidar plans with RPP's motions (models.controller: auto);
    simulate follows it with RPP by default, and the executed makespan is the planned one."""
    scenario = two_rooms_with(tmp_path, "{range_sensor: {}}")
    out = subprocess.run(
        [sys.executable, "-m", "tmpnav", "simulate", str(scenario), "--sessions", "3", "--cache-dir",
         str(tmp_path / "cache")],
        capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert "follower: nav2 Regulated Pure Pursuit" in out.stdout
    (line,) = [x for x in out.stdout.splitlines() if x.startswith("makespan (until the last robot is done)")]
    planned = float(line.split("planned ")[1].split(" s")[0])
    executed = float(line.split("executed with mutual observations ")[1].split(" s")[0])
    assert abs(executed - planned) <= 0.05 * planned, line


def test_an_unknown_controller_is_one_error_line(tmp_path: Path) -> None:
    scenario = two_rooms_with(tmp_path, "{controller: dwb}")
    out = subprocess.run(
        [sys.executable, "-m", "tmpnav", "validate", str(scenario)], capture_output=True, text=True, cwd=ROOT
    )
    assert out.returncode != 0
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "models.controller" in lines[0] and "rpp" in lines[0], out.stderr
    assert "Traceback" not in out.stderr


def test_nav2s_goal_checker_holds_the_position_once_reached_and_waits_for_the_heading() -> None:
    f = RppFollower(np.array([[0.0, 0.0], [3.0, 0.0]]), RppParams(), 0.5, 1.0, DT, goal_heading=math.pi / 2)
    assert not f.at_goal(np.array([2.8, 0.0, 0.0]))  # there, but facing away from the pose's heading
    v, w = f.command(np.array([2.8, 0.0, 0.0]), FREE)
    assert v == 0.0 and w > 0.0  # it turns on the spot, to the left
    # stateful, as nav2's SimpleGoalChecker: a drift past the tolerance while turning keeps the position reached
    assert f.at_goal(np.array([2.7, 0.0, math.pi / 2 - 0.2]))
    plain = follower([[0.0, 0.0], [3.0, 0.0]])
    assert plain.at_goal(np.array([2.8, 0.0, 0.0]))  # a goal without a heading: its position only


def test_a_control_step_holds_the_laws_commands_at_nav2s_rate_on_the_dead_reckoned_pose() -> None:
    """RppFollower.step gives the commands the compiled law gives 20 times a second, each on the
    pose the ones before it reached: the planner's rollout of the law at dt / N, step for step."""
    points = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 3.0]])
    f = RppFollower(points, RppParams(), 0.5, 1.0, 0.5)
    assert f.substeps == round(0.5 * CONTROLLER_FREQUENCY) == 10
    clear, origin = np.full((200, 200), FREE), (-5.0, -5.0)
    fine = pursuit_controls(points, 0.4, 0.5, 1.0, 0.05, RppParams(), clear, origin, 0.05, substeps=1)
    assert fine is not None
    pose = np.array([0.0, 0.0, 0.4])
    for k in range(3):  # three control steps: a turn on the spot, then driving
        commands = f.step(pose, FREE)
        assert np.allclose(commands, fine.controls[10 * k : 10 * k + 10])
        pose = drive_step(pose, commands, np.zeros(2), np.zeros(4), 0.5)
        assert np.allclose(pose, fine.poses[10 * k + 10])


def test_the_commands_after_the_goal_checker_is_satisfied_are_zero() -> None:
    f = RppFollower(np.array([[0.0, 0.0], [1.0, 0.0]]), RppParams(), 0.5, 1.0, 0.5)
    commands = f.step(np.array([0.7, 0.0, 0.0]), FREE)  # 0.3 m to go, 0.25 m of tolerance: stops within the step
    stopped = np.flatnonzero(np.all(commands == 0.0, axis=1))
    assert 0 < stopped[0] < len(commands) and np.all(commands[stopped[0] :] == 0.0)
    assert f.within and f.at_goal(drive_step(np.array([0.7, 0.0, 0.0]), commands, np.zeros(2), np.zeros(4), 0.5))


def test_one_command_drives_the_motion_models_step_with_its_noise() -> None:
    """drive with one command is the motion model's midpoint step of u + sqrt(W(u)) z, eq. (4)."""
    pose, u, z = np.array([1.0, 2.0, 0.3]), np.array([0.4, 0.5]), np.array([0.7, -1.2])
    alphas = np.array([0.1, 0.02, 0.03, 0.2])
    W = motion_noise_cov(u, alphas)
    expected = motion(pose, u + np.sqrt(np.diag(W)) * z, 0.5, midpoint=True)
    assert np.allclose(drive_step(pose, u[None], z, alphas, 0.5), expected)


def test_at_nav2s_rate_the_robot_weaves_less_and_arrives_no_later_than_the_plan_says() -> None:
    """The planner evaluates the law once per 0.5 s control step; driven 20 times a second through
    a door-like bend, the same path takes no longer and is driven no longer (less weaving)."""
    points = np.array([[0.0, 0.0], [3.0, 0.0], [3.3, 0.8], [3.3, 4.0]])
    clear, origin = np.full((300, 300), FREE), (-5.0, -5.0)
    plan = pursuit_controls(points, math.pi / 2, 0.5, 1.0, 0.5, RppParams(), clear, origin, 0.05)
    assert plan is not None
    f = RppFollower(points, RppParams(), 0.5, 1.0, 0.5)
    pose, steps, driven = np.array([0.0, 0.0, math.pi / 2]), 0, 0.0
    while not f.at_goal(pose) and steps < 200:
        after = drive_step(pose, f.step(pose, FREE), np.zeros(2), np.zeros(4), 0.5)
        driven += float(np.hypot(*(after[:2] - pose[:2])))
        pose, steps = after, steps + 1
    planned = float(np.hypot(*np.diff(plan.poses[:, :2], axis=0).T).sum())
    assert f.at_goal(pose) and steps <= plan.n_steps and steps >= 0.9 * plan.n_steps
    assert driven <= planned
