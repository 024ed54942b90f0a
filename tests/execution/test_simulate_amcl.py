"""``tmpnav simulate --localiser amcl``: the plan executed with nav2's AMCL on every robot, and
the planner's AMCL scan model against it (nav2's AMCL through the optional extra)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tmpnav.execution.consistency import Agreement
from tmpnav.types import NAV2_AMCL, RangeSensor, ScanModel
from tmpnav.world.grid import OccupancyGrid
from tmpnav.world.lidar import signed_distance
from tmpnav.world.scan_information import information_matrices

ROOT = Path(__file__).resolve().parents[2]
LIDAR = "models:\n  range_sensor: {range: 12, beams: 60, sigma_range: 0.03, divergence: 0.01}\n"


def corridor(length: float = 30.0, width: float = 2.0, res: float = 0.05) -> OccupancyGrid:
    """A featureless corridor: walls along both sides and at both ends."""
    rows, cols = round((width + 0.4) / res), round((length + 0.4) / res)
    occupied = np.ones((rows, cols), dtype=bool)
    occupied[4:-4, 4:-4] = False
    return OccupancyGrid(occupied, (-0.2, -0.2), res)


def test_the_amcl_model_gives_a_scan_less_information_than_independent_beams() -> None:
    """The likelihood field's endpoint noise sigma_hit (0.2 m) and its share of random returns
    leave a scan far less informative than 60 independent 3 cm beams: the position std one scan
    leaves in a room-sized box is centimetres, not millimetres."""
    grid = corridor(6.0, 4.0)
    sdf = signed_distance(grid)
    pose = np.array([[2.0, 2.0, 0.3]])
    beams = RangeSensor(12.0, 2 * math.pi, 60, 0.03, 0.1, math.radians(75), 0.01, ScanModel())
    amcl = RangeSensor(12.0, 2 * math.pi, 60, 0.03, 0.1, math.radians(75), 0.01, NAV2_AMCL)
    std = {}
    for name, sensor in (("beams", beams), ("amcl", amcl)):
        J = information_matrices(sdf, grid, sensor, pose)[0]
        std[name] = float(np.sqrt(np.linalg.inv(J)[0, 0]))
    assert std["beams"] < 0.01 and std["amcl"] > 5 * std["beams"]


def test_a_long_corridor_keeps_its_shape_in_the_amcl_model() -> None:
    """The planner's AMCL model sees nothing along a featureless corridor: one scan's information
    along it is a tiny share of that across it."""
    grid = corridor()
    sdf = signed_distance(grid)
    sensor = RangeSensor(12.0, 2 * math.pi, 60, 0.03, 0.1, math.radians(75), 0.01, NAV2_AMCL)
    J = information_matrices(sdf, grid, sensor, np.array([[15.0, 1.0, 0.0]]))[0]
    assert J[0, 0] < 0.01 * J[1, 1]


def test_a_long_corridor_keeps_its_shape_under_amcl() -> None:
    """nav2's AMCL driven down the same corridor: the actual error and AMCL's own std along the
    corridor are much larger than across it."""
    pytest.importorskip("amcl", reason="nav2's AMCL bindings (the optional extra tmpnav[amcl]) are not installed")
    from tmpnav.execution.amcl import AmclLocaliser
    from tmpnav.scenario.nav2_params import AmclParams
    from tmpnav.world.lidar import scan, sensor_params

    grid = corridor()
    sdf = signed_distance(grid)
    sensor = RangeSensor(12.0, 2 * math.pi, 60, 0.03, 0.1, math.radians(75), 0.01, NAV2_AMCL)
    cov = np.diag([0.1**2, 0.1**2, 0.05**2])
    truth = np.array([2.0, 1.0, 0.0])
    loc = AmclLocaliser(grid, sensor, AmclParams(), truth.copy(), cov, seed=1)
    rng = np.random.default_rng(1)
    angles, params = sensor.beam_angles(), sensor_params(sensor)
    errors, stds = [], []
    odom = truth.copy()
    for _ in range(100):  # 25 m at 0.25 m per step, the truth drifting with 5% speed noise
        odom = odom + np.array([0.25, 0.0, 0.0])
        truth = truth + np.array([0.25 * (1 + 0.05 * rng.standard_normal()), 0.002 * rng.standard_normal(), 0.0])
        r, H, var = np.empty(angles.size), np.empty((angles.size, 3)), np.empty(angles.size)
        scan(sdf, *grid.origin, grid.resolution, truth, angles, params, r, H, var)
        loc.update(odom, r + 0.03 * rng.standard_normal(angles.size))
        if 12.0 < truth[0] < 18.0:  # the middle: both ends out of the lidar's 12 m
            errors.append(loc.mean[:2] - truth[:2])
            stds.append(np.sqrt(np.diag(loc.cov)[:2]))
    e, s = np.abs(np.array(errors)), np.array(stds)
    assert np.sqrt(np.mean(e[:, 0] ** 2)) > 3 * np.sqrt(np.mean(e[:, 1] ** 2))
    assert np.median(s[:, 0]) > 2 * np.median(s[:, 1])


def test_agreement_of_a_consistent_gaussian_reads_as_consistent() -> None:
    """Errors drawn from the plan's own covariance: median NEES about 1.39, about 1.1% beyond 3 sigma,
    the predicted std as large as the RMS error."""
    rng = np.random.default_rng(0)
    P = np.array([[0.04, 0.01], [0.01, 0.02]])
    e = rng.multivariate_normal([0, 0], P, 20000)
    rows = np.column_stack([e, np.tile([0.1, 0.0, 0.1, P[0, 0], P[0, 1], P[1, 1]], (e.shape[0], 1))])
    a = Agreement.of(rows)
    assert abs(a.nees - 2 * math.log(2)) < 0.05 and abs(a.beyond - math.exp(-4.5)) < 0.004
    assert abs(a.inflation - 1.0) < 0.03


@pytest.mark.slow
def test_simulate_with_amcl_reports_the_plan_against_amcl(tmp_path: Path) -> None:
    """The command as a user runs it: the summary names the localiser, the site and the true motion
    noise, and prints the plan's beliefs against AMCL per robot; consistency.csv has a line per move."""
    pytest.importorskip("amcl", reason="nav2's AMCL bindings (the optional extra tmpnav[amcl]) are not installed")
    scenario = tmp_path / "two-rooms-lidar.yaml"
    scenario.write_text((ROOT / "configs" / "two-rooms.yaml").read_text() + LIDAR)
    out = tmp_path / "out"
    run = subprocess.run(
        [sys.executable, "-m", "tmpnav", "simulate", str(scenario), "--localiser", "amcl", "--sessions", "1",
         "--workers", "1", "-q", "--cache-dir", str(tmp_path / "cache"), "-o", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    text = run.stdout
    assert "localiser: nav2 AMCL" in text and "site: clutter" in text and "true motion noise" in text
    assert "steering on where the lidar places it among the walls" in text  # --steer auto: local with AMCL
    assert "median NEES" in text and "beyond 3 sigma" in text and "team" in text
    assert "nan" not in text and "mutual observations" not in text
    csv = (out / "consistency.csv").read_text().splitlines()
    assert csv[0].startswith("robot,step,driving_steps") and len(csv) >= 3


@pytest.mark.slow
def test_amcl_sessions_are_the_same_however_they_are_spread_over_workers(tmp_path: Path) -> None:
    """Each AMCL session runs in a process of its own: the bindings draw a filter's initial
    particles from a counter of the process, so in one process the second and third sessions drew
    other particles than in a pool of two, and the results depended on the workers."""
    pytest.importorskip("amcl", reason="nav2's AMCL bindings (the optional extra tmpnav[amcl]) are not installed")
    scenario = tmp_path / "two-rooms-lidar.yaml"
    scenario.write_text((ROOT / "configs" / "two-rooms.yaml").read_text() + LIDAR)
    outputs = {}
    for workers in ("1", "2"):
        out = tmp_path / f"out{workers}"
        run = subprocess.run(
            [sys.executable, "-m", "tmpnav", "simulate", str(scenario), "--localiser", "amcl", "--sessions", "3",
             "--workers", workers, "-q", "--cache-dir", str(tmp_path / "cache"), "-o", str(out)],
            capture_output=True, text=True, timeout=600,
        )  # fmt: skip
        assert run.returncode == 0, run.stderr
        outputs[workers] = (out / "errors.csv").read_text(), (out / "consistency.csv").read_text()
    assert outputs["1"] == outputs["2"]


def test_simulate_with_amcl_refuses_a_bad_site_in_one_line(tmp_path: Path) -> None:
    run = subprocess.run(
        [sys.executable, "-m", "tmpnav", "simulate", str(ROOT / "configs" / "two-rooms.yaml"), "--localiser",
         "amcl", "--site", "clutter=lots"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1 and "clutter" in run.stderr


def test_steering_on_what_the_lidar_sees_needs_a_lidar(tmp_path: Path) -> None:
    """--steer local on a scenario whose robots carry no range sensor: one line saying what to add."""
    run = subprocess.run(
        [sys.executable, "-m", "tmpnav", "simulate", str(ROOT / "configs" / "two-rooms.yaml"), "--steer", "local",
         "--sessions", "1", "--workers", "1", "-q", "--cache-dir", str(tmp_path / "cache")],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert run.returncode != 0 and "Traceback" not in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1 and "models.range_sensor" in run.stderr
