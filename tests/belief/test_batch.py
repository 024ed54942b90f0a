"""The vectorised fast path: agreement with the filterpy reference, masking, costs."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.belief.batch import (
    BatchInputs,
    FilterParams,
    cost_terms_from_history,
    predict,
    propagate,
    robot_traces,
)
from tmpnav.belief.models import motion
from tmpnav.belief.propagate import ObservationNoise, Propagation, Rollout, simulate_reference
from tmpnav.types import Belief, Models, ObservationMode, RangeBearingSensor

DT = 0.2
ALPHAS = (0.05, 0.01, 0.02, 0.05)
LM_SENSOR = RangeBearingSensor(range=8.0, fov=2 * np.pi, sigma_range=0.1, sigma_bearing=0.05)
MUTUAL_SENSOR = RangeBearingSensor(range=4.0, fov=2 * np.pi, sigma_range=0.15, sigma_bearing=0.08)


def models(max_likelihood: bool) -> Models:
    mode = ObservationMode.MAX_LIKELIHOOD if max_likelihood else ObservationMode.NOISY
    return Models(DT, ALPHAS, LM_SENSOR, MUTUAL_SENSOR, True, mode, seed=0)


def params(max_likelihood: bool) -> FilterParams:
    Q_lm, Q_mu = LM_SENSOR.Q, MUTUAL_SENSOR.Q
    return FilterParams(
        DT,
        ALPHAS,
        ((Q_lm[0, 0], 0.0), (0.0, Q_lm[1, 1])),
        ((Q_mu[0, 0], 0.0), (0.0, Q_mu[1, 1])),
        max_likelihood,
    )


def random_inputs(rng: np.random.Generator, B: int, n: int, T: int, L: int, p_see: float = 0.4) -> BatchInputs:
    """Robots 4 m apart near y = 0 driving at most 1.6 m; landmarks at 4 <= y <= 8."""
    start = np.zeros((B, n, 3))
    start[:, :, 0] = 4.0 * np.arange(n) + rng.uniform(-0.5, 0.5, (B, n))
    start[:, :, 1] = rng.uniform(-0.5, 0.5, (B, n))
    start[:, :, 2] = rng.uniform(-np.pi, np.pi, (B, n))
    controls = np.stack([rng.uniform(0.0, 1.0, (B, n, T)), rng.uniform(-1.0, 1.0, (B, n, T))], -1)
    steps = rng.integers(0, T + 1, (B, n))
    controls[np.arange(T)[None, None, :] >= steps[:, :, None]] = 0.0  # waiting after arrival
    poses = [start]
    for k in range(T):
        poses.append(motion(poses[-1], controls[:, :, k], DT))
    true_poses = np.stack(poses, axis=2)
    A = rng.normal(0, 0.1, (B, 3 * n, 3 * n))
    mean0 = start.reshape(B, 3 * n) + rng.normal(0, 0.05, (B, 3 * n))
    mean0[:, 2::3] = np.mod(mean0[:, 2::3] + np.pi, 2 * np.pi) - np.pi
    return BatchInputs(
        mean0=mean0,
        cov0=A @ np.swapaxes(A, 1, 2) + 1e-3 * np.eye(3 * n),
        controls=controls,
        true_poses=true_poses,
        active_steps=steps,
        landmarks=np.column_stack([rng.uniform(-2, 4 * n, L), rng.uniform(4, 8, L)]),
        lm_visible=rng.random((B, n, T + 1, L)) < p_see,
        mutual_visible=(rng.random((B, n, n, T + 1)) < p_see) & ~np.eye(n, dtype=bool)[None, :, :, None],
        lm_noise=rng.standard_normal((B, n, T + 1, L, 2)),
        mutual_noise=rng.standard_normal((B, n, n, T + 1, 2)),
    )


def reference(inputs: BatchInputs, b: int, max_likelihood: bool) -> Propagation:
    rollout = Rollout(
        controls=inputs.controls[b],
        true_poses=inputs.true_poses[b],
        active_steps=inputs.active_steps[b],
        lm_visible=inputs.lm_visible[b],
        mutual_visible=inputs.mutual_visible[b],
    )
    assert inputs.lm_noise is not None and inputs.mutual_noise is not None
    noise = ObservationNoise(inputs.lm_noise[b], inputs.mutual_noise[b])
    belief = Belief(inputs.mean0[b], inputs.cov0[b])
    return simulate_reference(belief, rollout, inputs.landmarks, models(max_likelihood), noise)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]), st.booleans())
def test_fast_path_matches_the_filterpy_reference_step_by_step(seed: int, n: int, ml: bool) -> None:
    rng = np.random.default_rng(seed)
    B, T, L = int(rng.integers(1, 4)), int(rng.integers(1, 8)), int(rng.integers(0, 4))
    inputs = random_inputs(rng, B, n, T, L)
    result = propagate(inputs, params(ml))
    assert result.means is not None and result.covs is not None
    for b in range(B):
        ref = reference(inputs, b, ml)
        np.testing.assert_allclose(result.means[b], ref.means, rtol=0, atol=1e-9)
        np.testing.assert_allclose(result.covs[b], ref.covs, rtol=0, atol=1e-9)
        for mine, theirs in zip(result.terms(b), ref.terms, strict=True):
            assert mine.c_u == pytest.approx(theirs.c_u, abs=1e-9)
            assert mine.c_G == pytest.approx(theirs.c_G, abs=1e-9)
            assert mine.c_Sigma == pytest.approx(theirs.c_Sigma, abs=1e-9)
        assert result.mutual_steps[b] == ref.mutual_steps


def test_same_inputs_give_bit_identical_outputs() -> None:
    inputs = random_inputs(np.random.default_rng(7), 5, 3, 12, 4)
    first, second = propagate(inputs, params(False)), propagate(inputs, params(False))
    for name in ("final_mean", "final_cov", "c_u", "c_G", "c_Sigma", "means", "covs"):
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))


def test_without_history_the_costs_and_final_beliefs_are_the_same() -> None:
    inputs = random_inputs(np.random.default_rng(8), 6, 2, 15, 3)
    full = propagate(inputs, params(False))
    lean = propagate(inputs, params(False), keep_history=False)
    assert lean.means is None and lean.covs is None
    for name in ("final_mean", "final_cov", "c_u", "c_G", "c_Sigma", "mutual_steps"):
        np.testing.assert_array_equal(getattr(full, name), getattr(lean, name))
    assert full.means is not None and full.covs is not None
    np.testing.assert_array_equal(full.final_cov, full.covs[:, -1])
    # the running sums equal the cost's definition on the full history
    c_u, c_g, c_sigma = cost_terms_from_history(
        full.means, full.covs, inputs.controls, inputs.true_poses, inputs.active_steps, DT
    )
    np.testing.assert_allclose(full.c_u, c_u, atol=1e-12)
    np.testing.assert_allclose(full.c_G, c_g, atol=1e-12)
    np.testing.assert_allclose(full.c_Sigma, c_sigma, atol=1e-12)


def test_masked_updates_are_exact_no_ops() -> None:
    inputs = random_inputs(np.random.default_rng(9), 4, 2, 6, 3)
    blind = replace(
        inputs,
        lm_visible=np.zeros_like(inputs.lm_visible),
        mutual_visible=np.zeros_like(inputs.mutual_visible),
    )
    result = propagate(blind, params(False))
    mean, cov = inputs.mean0.copy(), inputs.cov0.copy()
    for k in range(6):
        mean, cov = predict(mean, cov, inputs.controls[:, :, k], DT, ALPHAS)
    np.testing.assert_array_equal(result.final_mean, mean)
    np.testing.assert_array_equal(result.final_cov, cov)


def test_a_simulation_does_not_depend_on_the_rest_of_its_batch() -> None:
    inputs = random_inputs(np.random.default_rng(10), 6, 2, 10, 4)
    together = propagate(inputs, params(False))
    for b in (0, 3):
        alone = propagate(
            BatchInputs(
                **{name: value if name == "landmarks" else value[b : b + 1] for name, value in vars(inputs).items()}
            ),
            params(False),
        )
        np.testing.assert_allclose(alone.final_cov[0], together.final_cov[b], rtol=0, atol=1e-14)
        np.testing.assert_allclose(alone.final_mean[0], together.final_mean[b], rtol=0, atol=1e-14)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]), st.booleans())
def test_covariances_stay_symmetric_positive_semidefinite(seed: int, n: int, ml: bool) -> None:
    rng = np.random.default_rng(seed)
    inputs = random_inputs(rng, 3, n, 20, 5, p_see=0.6)
    result = propagate(inputs, params(ml))
    assert result.covs is not None
    covs = result.covs
    np.testing.assert_allclose(covs, np.swapaxes(covs, -1, -2), rtol=0, atol=1e-15)
    assert np.linalg.eigvalsh(covs).min() >= -1e-12


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([2, 3]))
def test_mutual_observations_never_increase_the_joint_uncertainty(seed: int, n: int) -> None:
    # maximum-likelihood mode: the means, hence the linearisation points, do not depend
    # on the observations, and one more observation can only shrink the covariance
    rng = np.random.default_rng(seed)
    inputs = random_inputs(rng, 3, n, 15, 3)
    alone = propagate(replace(inputs, mutual_visible=np.zeros_like(inputs.mutual_visible)), params(True))
    together = propagate(inputs, params(True))
    assert alone.covs is not None and together.covs is not None
    trace_alone = np.trace(alone.covs, axis1=-2, axis2=-1)
    trace_together = np.trace(together.covs, axis1=-2, axis2=-1)
    assert np.all(trace_together <= trace_alone + 1e-12)
    assert np.all(together.c_Sigma <= alone.c_Sigma + 1e-12)


def test_uncertainty_grows_monotonically_far_from_landmarks() -> None:
    rng = np.random.default_rng(11)
    inputs = random_inputs(rng, 4, 2, 30, 3)
    straight = inputs.controls.copy()
    straight[..., 0], straight[..., 1] = 0.8, 0.0  # driving straight, no observations
    # from uncorrelated initial beliefs (a correlated one may first shrink in trace)
    diagonal = np.diagonal(inputs.cov0, axis1=1, axis2=2)[:, :, None] * np.eye(inputs.cov0.shape[1])
    blind = replace(
        inputs,
        cov0=diagonal,
        controls=straight,
        lm_visible=np.zeros_like(inputs.lm_visible),
        mutual_visible=np.zeros_like(inputs.mutual_visible),
    )
    result = propagate(blind, params(False))
    assert result.covs is not None
    traces = robot_traces(result.covs)  # (B, T+1, n)
    assert np.all(np.diff(traces, axis=1) > 0)


def straight_drive(steps: int, T: int, mean0: np.ndarray) -> BatchInputs:
    controls = np.zeros((1, 1, T, 2))
    controls[0, 0, :steps, 0] = 1.0
    poses = np.zeros((1, 1, T + 1, 3))
    poses[0, 0, :, 0] = 0.1 * np.minimum(np.arange(T + 1), steps)
    return BatchInputs(
        mean0=mean0[None],
        cov0=np.diag([0.01, 0.01, 0.001])[None],
        controls=controls,
        true_poses=poses,
        active_steps=np.array([[steps]]),
        landmarks=np.zeros((0, 2)),
        lm_visible=np.zeros((1, 1, T + 1, 0), dtype=bool),
        mutual_visible=np.zeros((1, 1, 1, T + 1), dtype=bool),
        lm_noise=np.zeros((1, 1, T + 1, 0, 2)),
        mutual_noise=np.zeros((1, 1, 1, T + 1, 2)),
    )


def test_cost_terms_of_a_straight_drive_by_hand() -> None:
    # v = 1 m/s, omega = 0, dt = 0.1 s, W = diag(0.1 v², 0.05 v²): R = diag(1e-3, 0, 5e-4)
    # and F adds v dt = 0.1 times theta to y. From P0 = diag(0.01, 0.01, 0.001):
    #   P1 = xx 0.011, yy 0.01001,  yth 1e-4,   thth 0.0015  -> trace 0.02251
    #   P2 = xx 0.012, yy 0.010045, yth 2.5e-4, thth 0.002   -> trace 0.024045
    #   P3 = xx 0.013, yy 0.010115,             thth 0.0025  -> trace 0.025615
    p = FilterParams(0.1, (0.1, 0.0, 0.05, 0.0), ((0.01, 0.0), (0.0, 0.01)), ((0.01, 0.0), (0.0, 0.01)))
    result = propagate(straight_drive(3, 3, np.zeros(3)), p)
    assert result.covs is not None
    np.testing.assert_allclose(robot_traces(result.covs)[0, 1:, 0], [0.02251, 0.024045, 0.025615])
    (terms,) = result.terms(0)
    assert terms.c_u == pytest.approx(3 * 1.0 * 0.1)
    assert terms.c_Sigma == pytest.approx((0.02251 + 0.024045 + 0.025615) * 0.1)
    assert terms.c_G == pytest.approx(0.0, abs=1e-12)

    # arrived after 2 steps, then waits: neither waiting step nor its trace counts, and
    # a mean that started 0.1 m right and 0.2 m behind stays off the goal by that much
    early = propagate(straight_drive(2, 4, np.array([0.1, -0.2, 0.0])), p)
    (terms,) = early.terms(0)
    assert terms.c_u == pytest.approx(2 * 0.1)
    assert terms.c_Sigma == pytest.approx((0.02251 + 0.024045) * 0.1)
    assert terms.c_G == pytest.approx(np.hypot(0.1, 0.2))
    assert early.covs is not None  # waiting adds no noise: the belief stays put
    np.testing.assert_array_equal(early.covs[0, 2], early.covs[0, 4])


def test_zero_steps_and_bad_shapes() -> None:
    inputs = straight_drive(0, 0, np.zeros(3))
    result = propagate(inputs, params(False))
    (terms,) = result.terms(0)
    assert (terms.c_u, terms.c_G, terms.c_Sigma) == (0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="cov0"):
        propagate(replace(inputs, cov0=np.eye(3)), params(False))
    with pytest.raises(ValueError, match="lm_noise"):
        propagate(replace(inputs, lm_noise=None), params(False))
    propagate(replace(inputs, lm_noise=None, mutual_noise=None), params(True))
    with pytest.raises(ValueError, match="active_steps"):
        propagate(replace(inputs, active_steps=np.array([[1]])), params(False))
