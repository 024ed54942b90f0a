"""The compiled kernel against the filterpy reference, and its shared-prefix restarts."""

from __future__ import annotations

import numpy as np
import pytest

from tmpnav.belief.kernel import common_prefix_matrix, integrate_poses, run_sequences
from tmpnav.belief.propagate import ObservationNoise, Rollout, simulate_reference
from tmpnav.types import Belief, Models, ObservationMode, RangeBearingSensor


def _models(ml: bool) -> Models:
    sensor = RangeBearingSensor(5.0, 2 * np.pi, 0.1, 0.05)
    return Models(
        0.5,
        (0.02, 0.001, 0.03, 0.02),
        sensor,
        RangeBearingSensor(4.0, 2 * np.pi, 0.15, 0.04),
        True,
        ObservationMode.MAX_LIKELIHOOD if ml else ObservationMode.NOISY,
        0,
    )


def _random_motion(
    rng: np.random.Generator, T: int, L: int, start: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    controls = np.column_stack([rng.uniform(0.0, 0.6, T), rng.uniform(-0.5, 0.5, T)])
    controls[rng.random(T) < 0.3, 0] = 0.0  # turning on the spot
    poses = integrate_poses(start, controls, 0.5)
    vis = rng.random((T + 1, L)) < 0.4
    return controls, poses, vis


def _case(seed: int, n: int, ml: bool):  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)
    L = 4
    landmarks = rng.uniform(-8, 8, (L, 2))
    Ts = rng.integers(3, 12, n)
    motions = [
        _random_motion(rng, int(T), L, np.array([rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3)]))
        for T in Ts
    ]
    h = int(Ts.max())
    A = rng.standard_normal((3 * n, 3 * n))
    cov0 = A @ A.T * 0.01 + np.eye(3 * n) * 0.01
    mean0 = np.concatenate([m[1][0] + rng.normal(0, 0.05, 3) for m in motions])
    mvis = rng.random((h + 1, n, n)) < 0.5
    for i in range(n):
        mvis[:, i, i] = False
    lm_noise = rng.standard_normal((n, h + 1, L, 2))
    mu_noise = rng.standard_normal((h + 1, n, n, 2))
    return landmarks, motions, mean0, cov0, mvis, lm_noise, mu_noise, h


def _run_kernel(models: Models, landmarks, motions, mean0, cov0, mvis, lm_noise, mu_noise, h):  # type: ignore[no-untyped-def]
    n = len(motions)
    m_T = np.array([m[0].shape[0] for m in motions], dtype=np.int64)
    m_off = np.concatenate([[0], np.cumsum(m_T)[:-1]]).astype(np.int64)
    Q_lm, Q_mu = models.landmark_sensor.Q, models.mutual_sensor.Q
    out = (
        np.empty((1, 3 * n)),
        np.empty((1, 3 * n, 3 * n)),
        np.empty((1, n)),
        np.empty((1, n, 2)),
        np.empty(1, dtype=np.int64),
        np.empty((0, 1, n)),
    )
    hm, hc = run_sequences(
        n,
        models.dt,
        np.array(models.motion_noise),
        Q_lm,
        np.linalg.cholesky(Q_lm),
        Q_mu,
        np.linalg.cholesky(Q_mu),
        models.observations is ObservationMode.MAX_LIKELIHOOD,
        landmarks,
        m_off,
        m_T,
        np.concatenate([m[0] for m in motions]),
        np.concatenate([m[1] for m in motions]),
        np.concatenate([m[2] for m in motions]),
        np.arange(n, dtype=np.int64),
        lm_noise,
        mean0[None],
        cov0[None],
        np.zeros(1, dtype=np.int64),
        mu_noise[None],
        np.zeros(1, dtype=np.int64),
        np.arange(n, dtype=np.int64)[None],
        np.zeros(1, dtype=np.int64),
        np.array([h], dtype=np.int64),
        np.zeros(1, dtype=np.int64),
        mvis,
        *out,
    )
    return hm[: h + 1].copy(), hc[: h + 1].copy(), out


@pytest.mark.parametrize("n", [1, 2, 3])
@pytest.mark.parametrize("ml", [False, True])
@pytest.mark.parametrize("seed", range(6))
def test_kernel_matches_filterpy_step_by_step(n: int, ml: bool, seed: int) -> None:
    models = _models(ml)
    landmarks, motions, mean0, cov0, mvis, lm_noise, mu_noise, h = _case(seed * 7 + n, n, ml)
    inputs = (models, landmarks, motions, mean0, cov0, mvis, lm_noise, mu_noise, h)
    hm, hc, (_, _, csig, _, mutual, _) = _run_kernel(*inputs)

    controls = np.zeros((n, h, 2))
    poses = np.empty((n, h + 1, 3))
    lm_vis = np.empty((n, h + 1, landmarks.shape[0]), dtype=bool)
    for i, (c, p, v) in enumerate(motions):
        T = c.shape[0]
        controls[i, :T] = c
        poses[i, : T + 1], poses[i, T + 1 :] = p, p[-1]
        lm_vis[i, : T + 1], lm_vis[i, T + 1 :] = v, v[-1]
    rollout = Rollout(controls, poses, np.array([m[0].shape[0] for m in motions]), lm_vis, mvis.transpose(1, 2, 0))
    noise = ObservationNoise(lm_noise, mu_noise.transpose(1, 2, 0, 3))
    ref = simulate_reference(Belief(mean0, cov0), rollout, landmarks, models, noise)
    np.testing.assert_allclose(hm, ref.means, atol=1e-9, rtol=0)
    np.testing.assert_allclose(hc, ref.covs, atol=1e-9, rtol=0)
    np.testing.assert_allclose(csig[0], [t.c_Sigma for t in ref.terms], atol=1e-9, rtol=0)
    assert int(mutual[0]) == ref.mutual_steps


def test_restart_from_shared_prefix_is_bit_identical() -> None:
    """A simulation restarted from its predecessor's state equals one run from scratch."""
    models = _models(False)
    rng = np.random.default_rng(3)
    L, T = 3, 10
    landmarks = rng.uniform(-6, 6, (L, 2))
    base = _random_motion(rng, T, L, np.zeros(3))
    # a second motion that shares the first 6 steps and then differs
    ctrl2 = base[0].copy()
    ctrl2[6:, 1] += 0.3
    m2 = (ctrl2, integrate_poses(np.zeros(3), ctrl2, 0.5), base[2])
    m_T = np.array([T, T], dtype=np.int64)
    m_off = np.array([0, T], dtype=np.int64)
    ctrl = np.concatenate([base[0], m2[0]])
    prefix = common_prefix_matrix(ctrl, m_off, m_T, np.arange(2, dtype=np.int64))
    assert prefix[0, 1] == 6
    args = (
        1,
        models.dt,
        np.array(models.motion_noise),
        models.landmark_sensor.Q,
        np.linalg.cholesky(models.landmark_sensor.Q),
        models.mutual_sensor.Q,
        np.linalg.cholesky(models.mutual_sensor.Q),
        False,
        landmarks,
        m_off,
        m_T,
        ctrl,
        np.concatenate([base[1], m2[1]]),
        np.concatenate([base[2], m2[2]]),
        np.zeros(2, dtype=np.int64),
        rng.standard_normal((1, T + 1, L, 2)),
        np.zeros((1, 3)),
        np.eye(3)[None] * 0.01,
        np.zeros(1, dtype=np.int64),
        np.zeros((1, T + 1, 1, 1, 2)),
    )

    def run(order: list[int], starts: list[int]):  # type: ignore[no-untyped-def]
        C = len(order)
        outs = (
            np.empty((C, 3)),
            np.empty((C, 3, 3)),
            np.empty((C, 1)),
            np.empty((C, 1, 2)),
            np.empty(C, dtype=np.int64),
            np.empty((C, T + 1, 1)),
        )
        run_sequences(
            *args,
            np.zeros(C, dtype=np.int64),
            np.array(order, dtype=np.int64)[:, None],
            np.array(starts, dtype=np.int64),
            np.full(C, T, dtype=np.int64),
            np.zeros(C, dtype=np.int64),
            np.zeros((T + 1, 1, 1), dtype=bool),
            *outs,
        )
        return outs

    shared = run([0, 1], [0, 6])
    alone = run([1], [0])
    assert np.array_equal(shared[0][1], alone[0][0])
    assert np.array_equal(shared[1][1], alone[1][0])
    assert np.array_equal(shared[2][1], alone[2][0])
    assert np.array_equal(shared[5][1], alone[5][0])  # the running c_Sigma history too
    assert shared[5][1][-1, 0] == shared[2][1][0]
