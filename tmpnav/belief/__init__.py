"""Stage 4: the multi-robot EKF in belief space (paper, section Problem Definition).

- :mod:`~tmpnav.belief.models`: one function per model equation (motion, observations,
  their Jacobians), vectorised over leading batch axes;
- :mod:`~tmpnav.belief.controls`: a roadmap path -> turn-then-drive controls;
- :mod:`~tmpnav.belief.ekf`: the reference EKF on immutable beliefs (wraps filterpy);
- :mod:`~tmpnav.belief.batch`: the vectorised fast path and the cost terms;
- :mod:`~tmpnav.belief.propagate`: the entry points used by the rest of tmpnav.

The maths, units and cost definition are written out in docs/models.md.
"""

from tmpnav.belief.batch import BatchInputs, BatchResult, FilterParams, propagate
from tmpnav.belief.controls import PathControls, pad, path_controls
from tmpnav.belief.ekf import predict, update_landmark, update_mutual
from tmpnav.belief.models import (
    landmark_obs,
    landmark_obs_jacobian,
    motion,
    motion_jacobians,
    motion_noise_cov,
    mutual_obs,
    mutual_obs_jacobian,
    wrap_angle,
)
from tmpnav.belief.propagate import (
    ObservationNoise,
    Propagation,
    Rollout,
    filter_params,
    simulate,
    simulate_batch,
    simulate_reference,
    stack_paths,
)

__all__ = [
    "BatchInputs",
    "BatchResult",
    "FilterParams",
    "ObservationNoise",
    "PathControls",
    "Propagation",
    "Rollout",
    "filter_params",
    "landmark_obs",
    "landmark_obs_jacobian",
    "motion",
    "motion_jacobians",
    "motion_noise_cov",
    "mutual_obs",
    "mutual_obs_jacobian",
    "pad",
    "path_controls",
    "predict",
    "propagate",
    "simulate",
    "simulate_batch",
    "simulate_reference",
    "stack_paths",
    "update_landmark",
    "update_mutual",
    "wrap_angle",
]
