"""The compiled kernel (the production path) against the filterpy reference, and its maths.

Every simulation here runs through :func:`tmpnav.belief.sequences.propagate_sequences`,
the same entry point the oracle uses; :func:`propagate_reference` is the filterpy EKF.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.belief.support import models, random_case
from tmpnav.belief.reference import cost_terms_from_history, propagate_reference, robot_traces
from tmpnav.belief.rollout import Propagation, Rollout, propagate_rollout
from tmpnav.belief.sequences import (
    EKFConstants,
    MotionArrays,
    SequenceBatch,
    Sequences,
    StartGroups,
    propagate_sequences,
    standard_normal_draws,
)
from tmpnav.types import Belief, Models, RangeBearingSensor


def assert_same_propagation(fast: Propagation, ref: Propagation) -> None:
    np.testing.assert_allclose(fast.means, ref.means, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.covs, ref.covs, rtol=0, atol=1e-9)
    for mine, theirs in zip(fast.terms, ref.terms, strict=True):
        assert mine.c_u == pytest.approx(theirs.c_u, abs=1e-12)
        assert mine.c_G == pytest.approx(theirs.c_G, abs=1e-9)
        assert mine.c_Sigma == pytest.approx(theirs.c_Sigma, abs=1e-9)
    assert fast.mutual_steps == ref.mutual_steps


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]), st.booleans(), st.sampled_from(["auto", "rpp"]))
def test_kernel_matches_filterpy_step_by_step(seed: int, n: int, ml: bool, controller: str) -> None:
    """Step by step, with the Euler step (the paper's) and the midpoint step (RPP's)."""
    rng = np.random.default_rng(seed)
    T, L = int(rng.integers(1, 12)), int(rng.integers(0, 4))
    belief, rollout, landmarks, noise = random_case(rng, n, T, L)
    m = models(ml, controller=controller)
    assert m.midpoint == (controller == "rpp")
    fast = propagate_rollout(belief, rollout, landmarks, m, noise)
    ref = propagate_reference(belief, rollout, landmarks, m, noise)
    assert_same_propagation(fast, ref)


def test_the_running_sums_are_the_cost_definition() -> None:
    """c_Sigma and c_G accumulated step by step equal their definition on the history."""
    belief, rollout, landmarks, noise = random_case(np.random.default_rng(8), 3, 15, 3)
    run = propagate_rollout(belief, rollout, landmarks, models(), noise)
    for mine, defined in zip(run.terms, cost_terms_from_history(run.means, run.covs, rollout, 0.2), strict=True):
        assert mine.c_u == defined.c_u
        assert mine.c_G == pytest.approx(defined.c_G, abs=1e-12)
        assert mine.c_Sigma == pytest.approx(defined.c_Sigma, rel=1e-12)


def _two_motions_sharing(shared: int, T: int, L: int, rng: np.random.Generator) -> MotionArrays:
    """Two motions of one robot from the origin that agree on their first ``shared`` steps."""
    ctrl = np.column_stack([rng.uniform(0.0, 0.6, T), rng.uniform(-0.5, 0.5, T)])
    other = ctrl.copy()
    other[shared:, 1] += 0.3
    poses = []
    for c in (ctrl, other):
        p = [np.zeros(3)]
        for k in range(T):
            p.append(np.array([p[-1][0] + c[k, 0] * 0.2 * np.cos(p[-1][2]), p[-1][1], p[-1][2] + c[k, 1] * 0.2]))
        poses.append(np.array(p))
    vis = rng.random((T + 1, L)) < 0.5
    return MotionArrays.of([ctrl, other], poses, [vis, vis], np.zeros(2, dtype=np.int64), L)


def _batch(motions: MotionArrays, order: list[int], restarts: list[int], T: int, L: int) -> SequenceBatch:
    C = len(order)
    landmarks = np.random.default_rng(1).uniform(-6, 6, (L, 2))
    return SequenceBatch(
        n=1,
        ekf=EKFConstants.of(models(), landmarks),
        motions=motions,
        landmark_noise=standard_normal_draws([5], (T + 1, L, 2)),
        groups=StartGroups(np.zeros((1, 3)), np.eye(3)[None] * 0.01, np.zeros((1, T + 1, 1, 1, 2))),
        sequences=Sequences(
            group=np.zeros(C, dtype=np.int64),
            motions=np.array(order, dtype=np.int64)[:, None],
            restart=np.array(restarts, dtype=np.int64),
            horizon=np.full(C, T, dtype=np.int64),
            mutual_offset=np.zeros(C, dtype=np.int64),
        ),
        mutual_visible=np.zeros((T + 1, 1, 1), dtype=bool),
        c_sigma_history=True,
    )


def test_restart_from_shared_prefix_is_bit_identical() -> None:
    """A simulation restarted from its predecessor's state equals one run from scratch."""
    T, L = 10, 3
    motions = _two_motions_sharing(6, T, L, np.random.default_rng(3))
    shared = propagate_sequences(_batch(motions, [0, 1], [0, 6], T, L))
    alone = propagate_sequences(_batch(motions, [1], [0], T, L))
    assert shared.c_sigma_history is not None and alone.c_sigma_history is not None
    for name in ("mean", "cov", "c_sigma", "arrival_xy", "c_sigma_history"):
        assert np.array_equal(getattr(shared, name)[1], getattr(alone, name)[0]), name
    assert shared.c_sigma_history[1, -1, 0] == shared.c_sigma[1, 0]


def test_a_simulation_does_not_depend_on_its_batch() -> None:
    """Each group's simulation gives the same bits alone and among others."""
    cases = [random_case(np.random.default_rng(s), 2, 9, 3) for s in (10, 11, 12)]
    landmarks = cases[0][2]
    alone = [propagate_rollout(b, r, landmarks, models(), noise) for b, r, _, noise in cases]
    # the three as three groups of one kernel call
    steps = [list(map(int, r.active_steps)) for _, r, _, _ in cases]
    motions = MotionArrays.of(
        [r.controls[i, : s[i]] for (_, r, _, _), s in zip(cases, steps, strict=True) for i in range(2)],
        [r.true_poses[i, : s[i] + 1] for (_, r, _, _), s in zip(cases, steps, strict=True) for i in range(2)],
        [r.lm_visible[i, : s[i] + 1] for (_, r, _, _), s in zip(cases, steps, strict=True) for i in range(2)],
        np.arange(6),
        3,
    )
    batch = SequenceBatch(
        n=2,
        ekf=EKFConstants.of(models(), landmarks),
        motions=motions,
        landmark_noise=np.concatenate([c[3].landmark for c in cases]),
        groups=StartGroups(
            np.stack([c[0].mean for c in cases]),
            np.stack([c[0].cov for c in cases]),
            np.stack([c[3].mutual.transpose(2, 0, 1, 3) for c in cases]),
        ),
        sequences=Sequences(
            np.arange(3), np.arange(6).reshape(3, 2), np.zeros(3, dtype=np.int64), np.full(3, 9), np.arange(3) * 10
        ),
        mutual_visible=np.ascontiguousarray(np.concatenate([c[1].mutual_visible.transpose(2, 0, 1) for c in cases])),
    )
    together = propagate_sequences(batch)
    for c, one in enumerate(alone):
        assert np.array_equal(together.mean[c], one.means[-1])
        assert np.array_equal(together.cov[c], one.covs[-1])
        assert together.c_sigma[c].tolist() == [t.c_Sigma for t in one.terms]
    assert np.array_equal(together.last_means, alone[-1].means)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]), st.booleans())
def test_covariances_stay_symmetric_positive_semidefinite(seed: int, n: int, ml: bool) -> None:
    belief, rollout, landmarks, noise = random_case(np.random.default_rng(seed), n, 20, 5, p_see=0.6)
    covs = propagate_rollout(belief, rollout, landmarks, models(ml), noise).covs
    np.testing.assert_allclose(covs, np.swapaxes(covs, -1, -2), rtol=0, atol=1e-15)
    assert np.linalg.eigvalsh(covs).min() >= -1e-12


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([2, 3]))
def test_mutual_observations_never_increase_the_joint_uncertainty(seed: int, n: int) -> None:
    # maximum-likelihood mode: the means, hence the linearisation points, do not depend
    # on the observations, and one more observation can only shrink the covariance
    belief, rollout, landmarks, noise = random_case(np.random.default_rng(seed), n, 15, 3)
    alone = propagate_rollout(belief, rollout, landmarks, models(True, mutual=False), noise)
    together = propagate_rollout(belief, rollout, landmarks, models(True), noise)
    assert np.all(np.trace(together.covs, axis1=-2, axis2=-1) <= np.trace(alone.covs, axis1=-2, axis2=-1) + 1e-12)
    for mine, theirs in zip(together.terms, alone.terms, strict=True):
        assert mine.c_Sigma <= theirs.c_Sigma + 1e-12


def test_uncertainty_grows_monotonically_far_from_landmarks() -> None:
    belief, rollout, landmarks, noise = random_case(np.random.default_rng(11), 2, 30, 3)
    straight = np.zeros_like(rollout.controls)
    straight[..., 0] = 0.8  # driving straight, no observations, from uncorrelated beliefs
    blind = replace(
        rollout,
        controls=straight,
        active_steps=np.full(2, 30),
        lm_visible=np.zeros_like(rollout.lm_visible),
        mutual_visible=np.zeros_like(rollout.mutual_visible),
    )
    diagonal = Belief(belief.mean, np.diag(np.diagonal(belief.cov)))
    traces = robot_traces(propagate_rollout(diagonal, blind, landmarks, models(), noise).covs)  # (T+1, n)
    assert np.all(np.diff(traces, axis=0) > 0)


def straight_drive(steps: int, T: int, mean0: np.ndarray) -> tuple[Belief, Rollout]:
    controls = np.zeros((1, T, 2))
    controls[0, :steps, 0] = 1.0
    poses = np.zeros((1, T + 1, 3))
    poses[0, :, 0] = 0.1 * np.minimum(np.arange(T + 1), steps)
    rollout = Rollout(
        controls, poses, np.array([steps]), np.zeros((1, T + 1, 0), dtype=bool), np.zeros((1, 1, T + 1), dtype=bool)
    )
    return Belief(mean0, np.diag([0.01, 0.01, 0.001])), rollout


def hand_models() -> Models:
    sensor = RangeBearingSensor(range=5.0, fov=2 * np.pi, sigma_range=0.1, sigma_bearing=0.1)
    return replace(models(dt=0.1), motion_noise=(0.1, 0.0, 0.05, 0.0), landmark_sensor=sensor, mutual_sensor=sensor)


def test_cost_terms_of_a_straight_drive_by_hand() -> None:
    # v = 1 m/s, omega = 0, dt = 0.1 s, W = diag(0.1 v², 0.05 v²): R = diag(1e-3, 0, 5e-4)
    # and F adds v dt = 0.1 times theta to y. From P0 = diag(0.01, 0.01, 0.001):
    #   P1 = xx 0.011, yy 0.01001,  yth 1e-4,   thth 0.0015  -> trace 0.02251
    #   P2 = xx 0.012, yy 0.010045, yth 2.5e-4, thth 0.002   -> trace 0.024045
    #   P3 = xx 0.013, yy 0.010115,             thth 0.0025  -> trace 0.025615
    no_landmarks = np.zeros((0, 2))
    run = propagate_rollout(*straight_drive(3, 3, np.zeros(3)), no_landmarks, hand_models())
    np.testing.assert_allclose(robot_traces(run.covs)[1:, 0], [0.02251, 0.024045, 0.025615])
    (terms,) = run.terms
    assert terms.c_u == pytest.approx(3 * 1.0 * 0.1)
    assert terms.c_Sigma == pytest.approx((0.02251 + 0.024045 + 0.025615) * 0.1)
    assert terms.c_G == pytest.approx(0.0, abs=1e-12)

    # arrived after 2 steps, then waits: neither waiting step nor its trace counts, and
    # a mean that started 0.1 m right and 0.2 m behind stays off the goal by that much
    early = propagate_rollout(*straight_drive(2, 4, np.array([0.1, -0.2, 0.0])), no_landmarks, hand_models())
    (terms,) = early.terms
    assert terms.c_u == pytest.approx(2 * 0.1)
    assert terms.c_Sigma == pytest.approx((0.02251 + 0.024045) * 0.1)
    assert terms.c_G == pytest.approx(np.hypot(0.1, 0.2))
    np.testing.assert_array_equal(early.covs[2], early.covs[4])  # waiting adds no noise


def test_zero_steps_and_bad_shapes() -> None:
    run = propagate_rollout(*straight_drive(0, 0, np.zeros(3)), np.zeros((0, 2)), hand_models())
    (terms,) = run.terms
    assert (terms.c_u, terms.c_G, terms.c_Sigma) == (0.0, 0.0, 0.0)
    T, L = 4, 2
    batch = _batch(_two_motions_sharing(2, T, L, np.random.default_rng(0)), [0, 1], [0, 2], T, L)
    propagate_sequences(batch)
    bad = [
        (replace(batch, groups=batch.groups._replace(cov0=np.eye(3))), "groups.cov0"),
        (replace(batch, landmark_noise=np.zeros((1, T + 1, L + 1, 2))), "landmark_noise"),
        (replace(batch, landmark_noise=np.zeros((1, T, L, 2))), "noise draws"),
        (replace(batch, sequences=batch.sequences._replace(motions=np.array([[0], [2]]))), "sequences.motions"),
        (replace(batch, mutual_visible=np.zeros((T, 1, 1), dtype=bool)), "mutual_visible"),
    ]
    for broken, name in bad:
        with pytest.raises(ValueError, match=name):
            propagate_sequences(broken)


def test_the_kernel_unpacks_the_named_tuples_in_field_order() -> None:
    """run_sequences unpacks MotionArrays and EKFConstants by position: reordering a field
    must fail here, not silently swap arrays in compiled code."""
    assert MotionArrays._fields == (
        "offset",
        "steps",
        "controls",
        "poses",
        "lm_visible",
        "noise_stream",
        "reach",
        "reach_values",
        "reach_row",
        "scan_row",
        "scan_table",
    )
    assert EKFConstants._fields == (
        "dt",
        "alphas",
        "Q_landmark",
        "chol_landmark",
        "Q_mutual",
        "chol_mutual",
        "max_likelihood",
        "landmarks",
        "scans",
        "scan_thresholds",
        "fuse_others",
        "local_var",
        "local_rho",
        "hazard",
        "midpoint",
    )
