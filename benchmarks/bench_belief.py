"""Micro-benchmark of the belief layer: a joint two-robot propagation over a 100-step path.

Times evaluations per second of the compiled kernel the oracle runs (one simulation with
its history, as the re-simulation of a plan uses it; 1,000 simulations from scratch in one
call, without the shared prefixes the oracle's trie order adds) and of the filterpy
reference, and prints one JSON line. Run it by hand:
``.venv/bin/python benchmarks/bench_belief.py [--repeat N]``; it is not a test.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from collections.abc import Callable

import numpy as np

from tmpnav.belief.controls import path_controls
from tmpnav.belief.reference import propagate_reference
from tmpnav.belief.rollout import ObservationNoise, Rollout, observed_mutually, propagate_rollout, stack_paths
from tmpnav.belief.sequences import (
    EKFConstants,
    MotionArrays,
    SequenceBatch,
    Sequences,
    StartGroups,
    propagate_sequences,
)
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


def kernel_batch(belief: Belief, rollout: Rollout, models: Models, B: int) -> SequenceBatch:
    """B copies of the scene as one batch, each simulated from scratch (no shared prefixes):
    the raw propagation speed that the oracle's trie ordering then multiplies."""
    n, T = 2, rollout.n_steps
    steps = [int(s) for s in rollout.active_steps]
    noise = ObservationNoise.draw(0, n, T, len(LANDMARKS))
    motions = MotionArrays.of(
        [rollout.controls[i, : steps[i]] for i in range(n)],
        [rollout.true_poses[i, : steps[i] + 1] for i in range(n)],
        [rollout.lm_visible[i, : steps[i] + 1] for i in range(n)],
        np.arange(n),
        len(LANDMARKS),
    )
    visible = np.ascontiguousarray(observed_mutually(rollout, models).transpose(2, 0, 1))
    return SequenceBatch(
        n=n,
        ekf=EKFConstants.of(models, LANDMARKS),
        motions=motions,
        landmark_noise=noise.landmark,
        groups=StartGroups(
            belief.mean[None], belief.cov[None], np.ascontiguousarray(noise.mutual.transpose(2, 0, 1, 3))[None]
        ),
        sequences=Sequences(
            group=np.zeros(B, dtype=np.int64),
            motions=np.tile(np.arange(n, dtype=np.int64), (B, 1)),
            restart=np.zeros(B, dtype=np.int64),
            horizon=np.full(B, T, dtype=np.int64),
            mutual_offset=np.arange(B, dtype=np.int64) * (T + 1),
        ),
        mutual_visible=np.ascontiguousarray(np.tile(visible, (B, 1, 1))),
    )


def evals_per_second(run: Callable[[], object], evals_per_run: int, repeat: int) -> float:
    run()  # warm-up (and the kernel's compilation or cache load)
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
    batch = kernel_batch(belief, rollout, models, 1000)
    n_updates = int(rollout.lm_visible[:, 1:].sum() + rollout.mutual_visible[:, :, 1:].sum())
    one = round(evals_per_second(lambda: propagate_rollout(belief, rollout, LANDMARKS, models), 1, args.repeat), 1)
    many = round(evals_per_second(lambda: propagate_sequences(batch), 1000, args.repeat), 1)
    reference = round(
        evals_per_second(lambda: propagate_reference(belief, rollout, LANDMARKS, models), 1, args.repeat), 1
    )
    print(
        json.dumps(
            {
                "benchmark": "belief-joint-2-robots",
                "steps": rollout.n_steps,
                "updates_per_eval": n_updates,
                "kernel_batch1_evals_per_s": one,
                "kernel_batch1000_evals_per_s": many,
                "filterpy_reference_evals_per_s": reference,
                "python": platform.python_version(),
                "numpy": np.__version__,
            }
        )
    )


if __name__ == "__main__":
    main()
