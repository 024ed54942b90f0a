"""The independent conflict checker on trajectories built in code: crossing, head-on, parallel
passes, uncertainty widening the margin, robots standing where they ended, true contacts."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.belief.conflicts import contacts, find_conflicts, margin_factor, position_sigma, seen_std
from tmpnav.scenario import load as load_scenario
from tmpnav.shipped import configs_dir
from tmpnav.types import ScanModelKind, TrajectoryStep

DT = 0.5
RADII = {"a": 0.25, "b": 0.25}


def line(start: tuple[float, float], end: tuple[float, float], steps: int, sigma: float = 0.05) -> list[TrajectoryStep]:
    """A robot driving straight from ``start`` to ``end`` in ``steps`` steps of DT, with an
    isotropic position std ``sigma`` (m)."""
    xy = np.linspace(start, end, steps + 1)
    cov = ((sigma**2, 0.0, 0.0), (0.0, sigma**2, 0.0), (0.0, 0.0, 0.01))
    return [TrajectoryStep(k * DT, (float(x), float(y), 0.0), cov) for k, (x, y) in enumerate(xy)]


def test_robots_crossing_at_the_same_time_conflict_once_where_they_cross() -> None:
    found = find_conflicts({"a": line((-5, 0), (5, 0), 20), "b": line((0, -5), (0, 5), 20)}, RADII)
    assert len(found) == 1
    c = found[0]
    assert c.robots == ("a", "b") and c.closest_distance == pytest.approx(0.0, abs=1e-9)
    assert c.t_from < 5.0 < c.t_to and c.t_from + c.t_to == pytest.approx(10.0)  # symmetric about the crossing
    assert c.where == pytest.approx((0.0, 0.0), abs=1e-9)
    assert c.required_separation == pytest.approx(0.5 + margin_factor(0.05) * 0.1)


def test_crossing_one_after_the_other_is_no_conflict() -> None:
    late = [TrajectoryStep(s.t + 10.0, s.mean, s.cov) for s in line((0, -5), (0, 5), 20)]
    waiting = [TrajectoryStep(k * DT, late[0].mean, late[0].cov) for k in range(20)]
    assert find_conflicts({"a": line((-5, 0), (5, 0), 20), "b": waiting + late}, RADII) == []


def test_head_on_in_a_corridor_is_one_conflict() -> None:
    found = find_conflicts({"a": line((-5, 0), (5, 0), 20), "b": line((5, 0.2), (-5, 0.2), 20)}, RADII)
    assert len(found) == 1 and found[0].closest_distance == pytest.approx(0.2)


def test_parallel_passes_at_a_safe_distance_are_no_conflict() -> None:
    assert find_conflicts({"a": line((-5, 0), (5, 0), 20), "b": line((5, 2.0), (-5, 2.0), 20)}, RADII) == []


def test_uncertainty_widens_the_margin() -> None:
    """Passing 1 m apart is safe for robots that know where they are, not for lost ones."""
    sure = {"a": line((-5, 0), (5, 0), 20, 0.05), "b": line((5, 1.0), (-5, 1.0), 20, 0.05)}
    lost = {"a": line((-5, 0), (5, 0), 20, 0.2), "b": line((5, 1.0), (-5, 1.0), 20, 0.2)}
    assert find_conflicts(sure, RADII) == []
    found = find_conflicts(lost, RADII)
    assert len(found) == 1 and found[0].required_separation == pytest.approx(0.5 + margin_factor(0.05) * 0.4)
    assert find_conflicts(lost, RADII, delta=0.5) == []  # a looser risk threshold, a smaller margin


def test_the_margin_bounds_the_touch_risk_by_delta() -> None:
    """At the required separation the Gaussian tail bound exp(-m^2 / (2 (s_i + s_j)^2)) is delta."""
    for delta in (0.01, 0.05, 0.2):
        m = margin_factor(delta) * 0.3
        assert math.exp(-(m**2) / (2 * 0.3**2)) == pytest.approx(delta)
    assert margin_factor(1.0) == 0.0  # any risk allowed (--max-risk 1): the radii alone
    for bad in (0.0, 1.5):
        with pytest.raises(ValueError):
            margin_factor(bad)


def test_a_robot_stands_where_its_trajectory_ends() -> None:
    """A robot whose trajectory ends stands there: another that drives through later meets it."""
    found = find_conflicts({"a": line((-5, 0), (0, 0), 10), "b": line((0, -5), (0, 5), 30)}, RADII)
    assert len(found) == 1 and found[0].t_from > 10 * DT and found[0].where == pytest.approx((0.0, 0.0), abs=0.05)


def test_two_meetings_of_one_pair_are_two_conflicts() -> None:
    there = line((-5, 0), (5, 0), 20)
    back = [TrajectoryStep(s.t + 10.5, s.mean, s.cov) for s in line((5, 0), (-5, 0), 20)]
    standing = [TrajectoryStep(k * DT, (0.0, 0.0, 0.0), there[0].cov) for k in range(len(there) + len(back))]
    found = find_conflicts({"a": there + back, "b": standing}, RADII)
    assert len(found) == 2 and found[0].t_to < found[1].t_from


def test_trajectories_on_different_grids_are_refused() -> None:
    off = [TrajectoryStep(s.t + 0.25, s.mean, s.cov) for s in line((0, 0), (1, 0), 4)]
    with pytest.raises(ValueError):
        find_conflicts({"a": line((0, 0), (1, 0), 4), "b": off}, RADII)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=9, max_size=9))
def test_position_sigma_is_the_largest_eigenvalue(values: list[float]) -> None:
    m = np.array(values).reshape(3, 3)
    cov = m @ m.T
    assert position_sigma(cov) == pytest.approx(math.sqrt(max(np.linalg.eigvalsh(cov[:2, :2]).max(), 0.0)), abs=1e-9)


def test_true_contacts_have_no_margin() -> None:
    a = np.array([[0.0, 0.0, 0.0]] * 5)
    near = np.array([[0.45, 0.0, 0.0]] * 3)  # held after its end
    far = np.array([[0.55, 0.0, 0.0]] * 5)
    assert [c.robots for c in contacts({"a": a, "b": near}, RADII, DT)] == [("a", "b")]
    assert contacts({"a": a, "b": far}, RADII, DT) == []


def test_robots_passing_two_seconds_apart_conflict_within_a_three_second_window() -> None:
    a = line((-5, 0), (5, 0), 20)  # at the crossing at 5 s
    first = line((0, -5), (0, 5), 20)
    b = [TrajectoryStep(k * DT, first[0].mean, first[0].cov) for k in range(4)]  # it stands 2 s first
    b += [TrajectoryStep(s.t + 2.0, s.mean, s.cov) for s in first]  # at the crossing at 7 s
    assert find_conflicts({"a": a, "b": b}, RADII) == []
    assert find_conflicts({"a": a, "b": b}, RADII, windows={("a", "b"): np.zeros(len(b))}) == []
    found = find_conflicts({"a": a, "b": b}, RADII, windows={("a", "b"): np.full(len(b), 3.0)})
    assert len(found) == 1
    c = found[0]
    assert c.robots == ("a", "b") and c.window == 3.0
    assert c.closest_distance == pytest.approx(0.0, abs=1e-9) and c.where == pytest.approx((0.0, 0.0), abs=1e-9)
    assert c.t_from < 5.0 < c.t_to  # a's clock
    # half a second is too short a window for crossings 2 s apart
    assert find_conflicts({"a": a, "b": b}, RADII, windows={("a", "b"): np.full(len(b), 0.5)}) == []


def test_robots_that_see_each_other_are_kept_apart_by_their_local_error() -> None:
    """Under nav2's AMCL with walls: local, another robot is where the lidar sees it: two robots
    passing 1 m apart with 0.3 m global stds conflict by their beliefs (0.5 + 2.45 x 0.6 m
    needed), not by their local errors (0.5 + 2.45 x 0.1 m)."""
    a, b = line((-5, 0), (5, 0), 20, sigma=0.3), line((5, 1.0), (-5, 1.0), 20, sigma=0.3)
    by_belief = find_conflicts({"a": a, "b": b}, RADII)
    assert len(by_belief) == 1 and by_belief[0].required_separation == pytest.approx(0.5 + margin_factor(0.05) * 0.6)
    assert find_conflicts({"a": a, "b": b}, RADII, seen=0.05) == []
    near = line((5, 0.6), (-5, 0.6), 20, sigma=0.3)
    found = find_conflicts({"a": a, "b": near}, RADII, seen=0.05)
    assert len(found) == 1 and found[0].required_separation == pytest.approx(0.5 + margin_factor(0.05) * 0.1)


def test_only_the_amcl_model_with_local_walls_separates_by_the_local_error() -> None:
    scenario = load_scenario(configs_dir() / "building-4robots.yaml")
    sensor = scenario.models.range_sensor
    assert sensor is not None and sensor.localiser.kind is ScanModelKind.AMCL  # the shipped default
    amcl = sensor.localiser
    assert seen_std(scenario.models) == amcl.local_std
    beams = replace(scenario.models, range_sensor=replace(sensor, localiser=replace(amcl, kind=ScanModelKind.BEAMS)))
    assert seen_std(beams) is None  # the sensor's bound: the beliefs
    on_map = replace(scenario.models, range_sensor=replace(sensor, localiser=replace(amcl, walls="map")))
    assert seen_std(on_map) is None and seen_std(replace(scenario.models, range_sensor=None)) is None


def _shortfalls_broadcast(mi, mj, si, sj, rr, k, window):  # type: ignore[no-untyped-def]
    """The shortfalls by numpy's broadcasting over every shift at once: an independent reference."""
    steps = len(mi)
    index = np.arange(steps)
    worst = np.full(steps, -np.inf)
    gap_at, need_at, other = np.zeros(steps), np.zeros(steps), index.copy()
    for d in range(-int(window.max(initial=0)), int(window.max(initial=0)) + 1):
        at = np.clip(index + d, 0, steps - 1)
        gap = np.hypot(*(mi - mj[at]).T)
        need = rr + k * (si + sj[at])
        shortfall = np.where(np.abs(d) <= window, need - gap, -np.inf)
        better = shortfall > worst
        worst[better], gap_at[better], need_at[better], other[better] = (
            shortfall[better],
            gap[better],
            need[better],
            at[better],
        )
    return worst, gap_at, need_at, other


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(1, 120), st.sampled_from([3.0, 30.0]))
def test_the_compiled_shortfalls_are_the_broadcast_ones_to_the_bit(seed: int, steps: int, room: float) -> None:
    """Where robot i comes within the separation (a positive shortfall), to the bit; elsewhere
    negative too (the compiled one passes over blocks of steps where the two are far apart:
    ``room`` 30 m spreads them)."""
    from tmpnav.belief.conflicts import _shortfalls

    rng = np.random.default_rng(seed)
    mi, mj = rng.uniform(0, room, (steps, 2)), rng.uniform(0, room, (steps, 2))
    if room > 3.0:  # robots that keep to their own parts of the floor, and meet now and then
        mi, mj = np.sort(mi, axis=0), np.sort(mj, axis=0)[::-1]
    si, sj = rng.uniform(0, 0.3, steps), rng.uniform(0, 0.3, steps)
    window = np.minimum(np.arange(steps) // 7, rng.integers(0, 9)).astype(np.int64)  # grows as a clock drifts
    ours = _shortfalls(mi, mj, si, sj, 0.5, 1.96, window)
    theirs = _shortfalls_broadcast(mi, mj, si, sj, 0.5, 1.96, window)
    near = theirs[0] > 0.0
    assert np.array_equal(ours[0] > 0.0, near)
    for a, b in zip(ours, theirs, strict=True):
        assert np.array_equal(a[near], b[near])
    assert np.all(ours[0][~near] <= 0.0)
