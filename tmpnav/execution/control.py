"""The waypoint follower of ``tmpnav simulate``: when a waypoint counts as reached, and the control
that drives towards the next one.

A moving robot follows its roadmap path with a controller that steers on its own estimate, as
the plan's motions do (tmpnav.belief.controls: turn on the spot at each node of the path, then
drive straight): at the start of each segment it turns on the spot until it points within
``ALIGN_START`` of the next waypoint; then it drives with a heading correction, turning on the
spot again only when its estimate points more than ``ALIGN`` away. Driving off with a heading
error of up to ``ALIGN`` at a bend took the robot 5-7 cm off the planned segment, enough to touch
a wall where the plan kept 2 cm (configs/depot-jobs.yaml: r2's first move hit a wall in 2 of 8
executions, its collision bound 1e-10). A waypoint counts as reached when the estimate is within ``ARRIVED`` of it
or has passed it along its segment, so that a robot that lands a few centimetres off never
turns around for it.
"""

from __future__ import annotations

import math

import numpy as np

from tmpnav.belief.models import wrap_angle

ALIGN = 0.3  # rad: beyond this heading error a driving robot turns on the spot
ALIGN_START = 0.02  # rad: at the start of a segment the robot turns until it points this close
ARRIVED = 0.05  # m: a waypoint is reached when the estimate is this close (or this close to abreast)


def reached(est: np.ndarray, previous: np.ndarray, waypoint: np.ndarray) -> bool:
    """Whether the robot (its estimate) is at ``waypoint`` or abreast of it: no more than
    ``ARRIVED`` short of the line through the waypoint perpendicular to the segment from
    ``previous``. Without the second test a robot a few centimetres to the side of a
    waypoint turns on the spot to reach it, and every such turn adds heading noise."""
    dx, dy = waypoint[0] - est[0], waypoint[1] - est[1]
    if math.hypot(dx, dy) < ARRIVED:
        return True
    sx, sy = waypoint[0] - previous[0], waypoint[1] - previous[1]
    length = math.hypot(sx, sy)
    return length > ARRIVED and (dx * sx + dy * sy) / length <= ARRIVED


def control(
    est: np.ndarray, waypoint: np.ndarray, speed: float, turn_rate: float, dt: float, align: float = ALIGN
) -> np.ndarray:
    """The waypoint controller: turn on the spot when the estimate points more than ``align`` away
    from the waypoint (:data:`ALIGN_START` at a segment's start), else drive with a heading correction."""
    dx, dy = waypoint[0] - est[0], waypoint[1] - est[1]
    err = float(wrap_angle(math.atan2(dy, dx) - est[2]))
    omega = max(-turn_rate, min(turn_rate, err / dt))
    if abs(err) > align:
        return np.array([0.0, omega])
    return np.array([min(speed, math.hypot(dx, dy) / dt), omega])
