"""Micro-benchmark of the belief layer: a joint two-robot propagation over a 100-step path.

Times evaluations per second of the fast path (batch of 1, batch of 1000, without
history as the oracle runs it) and of the filterpy reference, and prints one JSON line.
Run it by hand: ``.venv/bin/python benchmarks/bench_belief.py [--repeat N]``; it is not a test.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from collections.abc import Callable

import numpy as np

from tmpnav.belief.batch import BatchInputs
from tmpnav.belief.controls import path_controls
from tmpnav.belief.propagate import Rollout, simulate_batch, simulate_reference, stack_paths
from tmpnav.types import Belief, Models, ObservationMode, RangeBearingSensor

LANDMARKS = np.array([[1.0, 2.0], [4.0, -2.0], [7.0, 2.0], [10.0, -2.0], [2.0, 8.0]])


def scene() -> tuple[Belief, Rollout, Models]:
    """Two robots driving 10 m towards each other at 1 m/s, dt = 0.1 s: 100 steps."""
    r1 = path_controls(np.array([[0.0, 0.0], [10.0, 0.0]]), 0.0, 1.0, 1.0, 0.1)
    r2 = path_controls(np.array([[10.0, 1.0], [0.0, 1.0]]), np.pi, 1.0, 1.0, 0.1)
    controls, poses, steps = stack_paths([r1, r2])
    lm_visible = np.linalg.norm(poses[:, :, None, :2] - LANDMARKS, axis=-1) < 3.0
    close = np.linalg.norm(poses[0, :, :2] - poses[1, :, :2], axis=-1) < 4.0
    mutual = np.zeros((2, 2, poses.shape[1]), dtype=bool)
    mutual[0, 1] = mutual[1, 0] = close
    models = Models(
        dt=0.1,
        motion_noise=(0.05, 0.01, 0.02, 0.05),
        landmark_sensor=RangeBearingSensor(3.0, 2 * np.pi, 0.1, 0.05),
        mutual_sensor=RangeBearingSensor(4.0, 2 * np.pi, 0.1, 0.05),
        mutual_observations=True,
        observations=ObservationMode.NOISY,
        seed=0,
    )
    belief = Belief(poses[:, 0].reshape(-1), np.diag([0.02, 0.02, 0.005] * 2))
    return belief, Rollout(controls, poses, steps, lm_visible, mutual), models


def batched(belief: Belief, rollout: Rollout, B: int) -> BatchInputs:
    def rep(a: np.ndarray) -> np.ndarray:
        return np.repeat(np.asarray(a)[None], B, axis=0)

    return BatchInputs(
        mean0=rep(belief.mean),
        cov0=rep(belief.cov),
        controls=rep(rollout.controls),
        true_poses=rep(rollout.true_poses),
        active_steps=rep(rollout.active_steps),
        landmarks=LANDMARKS,
        lm_visible=rep(rollout.lm_visible),
        mutual_visible=rep(rollout.mutual_visible),
    )


def kernel_run(belief: Belief, rollout: Rollout, models: Models, B: int) -> Callable[[], object]:
    """The oracle's compiled kernel on B copies of the scene, each from scratch (no shared
    prefixes): the raw propagation speed the oracle's trie ordering then multiplies."""
    from tmpnav.belief.kernel import run_sequences

    n, T = 2, rollout.n_steps
    m_T = np.array([int(s) for s in rollout.active_steps], dtype=np.int64)
    ctrl = np.concatenate([rollout.controls[i, : m_T[i]] for i in range(n)])
    pose = np.concatenate([rollout.true_poses[i, : m_T[i] + 1] for i in range(n)])
    vis = np.ascontiguousarray(np.concatenate([rollout.lm_visible[i, : m_T[i] + 1] for i in range(n)]))
    m_off = np.array([0, m_T[0]], dtype=np.int64)
    rng = np.random.default_rng(0)
    lm_noise = rng.standard_normal((2, T + 1, len(LANDMARKS), 2))
    mu_noise = rng.standard_normal((1, T + 1, n, n, 2))
    mvis = np.ascontiguousarray(np.tile(np.transpose(rollout.mutual_visible, (2, 0, 1)), (B, 1, 1)))
    Q_lm, Q_mu = models.landmark_sensor.Q, models.mutual_sensor.Q
    outs = (
        np.empty((B, 6)),
        np.empty((B, 6, 6)),
        np.empty((B, 2)),
        np.empty((B, 2, 2)),
        np.empty(B, dtype=np.int64),
        np.zeros((0, 1, 2)),
    )
    args = (
        n,
        models.dt,
        np.array(models.motion_noise),
        Q_lm,
        np.linalg.cholesky(Q_lm),
        Q_mu,
        np.linalg.cholesky(Q_mu),
        False,
        LANDMARKS,
        m_off,
        m_T,
        ctrl,
        pose,
        vis,
        np.arange(2, dtype=np.int64),
        lm_noise,
        belief.mean[None],
        belief.cov[None],
        np.zeros(1, dtype=np.int64),
        mu_noise,
        np.zeros(B, dtype=np.int64),
        np.tile(np.arange(2, dtype=np.int64), (B, 1)),
        np.zeros(B, dtype=np.int64),
        np.full(B, T, dtype=np.int64),
        np.arange(B, dtype=np.int64) * (T + 1),
        mvis,
        *outs,
    )
    return lambda: run_sequences(*args)


def evals_per_second(run: Callable[[], object], evals_per_run: int, repeat: int) -> float:
    run()  # warm-up
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return evals_per_run / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=5, help="timed runs (best is kept)")
    args = parser.parse_args()
    belief, rollout, models = scene()
    one, thousand = batched(belief, rollout, 1), batched(belief, rollout, 1000)
    n_updates = int(rollout.lm_visible[:, 1:].sum() + rollout.mutual_visible[:, :, 1:].sum())
    print(
        json.dumps(
            {
                "benchmark": "belief-joint-2-robots",
                "steps": rollout.n_steps,
                "updates_per_eval": n_updates,
                "batch1_evals_per_s": round(evals_per_second(lambda: simulate_batch(one, models), 1, args.repeat), 1),
                "kernel_batch1000_evals_per_s": round(
                    evals_per_second(kernel_run(belief, rollout, models, 1000), 1000, args.repeat), 1
                ),
                "batch1000_evals_per_s": round(
                    evals_per_second(lambda: simulate_batch(thousand, models), 1000, args.repeat), 1
                ),
                "filterpy_reference_evals_per_s": round(
                    evals_per_second(
                        lambda: simulate_reference(belief, rollout, LANDMARKS, models),
                        1,
                        args.repeat,
                    ),
                    1,
                ),
                "python": platform.python_version(),
                "numpy": np.__version__,
            }
        )
    )


if __name__ == "__main__":
    main()
