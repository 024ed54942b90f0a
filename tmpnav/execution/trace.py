"""What one session of ``tmpnav simulate`` draws and records: its random numbers
(:class:`Draws`, shared by both configurations), the true start poses drawn from them
(:func:`free_start`), and its trace (:class:`SessionTrace`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from tmpnav.execution.consistency import ConsistencyTrace
from tmpnav.results import Schedule, TimedMove

if TYPE_CHECKING:
    from tmpnav.world import World


@dataclass
class HitEvent:
    """Where and when a robot's true pose hit a wall or touched another robot's: the first control
    step of one contact (``kind`` ``wall`` or ``robot``), the plan step of the move under way, the
    true position (m), the localiser's position error and its own std (m) there, and how many
    control steps in a row the contact lasted."""

    robot: str
    step: int
    kind: str
    t: float  # s
    x: float
    y: float
    error: float
    own_std: float
    steps: int = 1


@dataclass
class SessionTrace:
    """One session in one configuration: robot -> the position error (m) at each point of its
    paths and when it got there (s, nan for a point never reached), and the moves as executed;
    robot -> the control steps after which its true pose hit a wall (``wall_hits``) and touched
    another robot's (``contacts``)."""

    errors: dict[str, list[float]] = field(default_factory=dict)
    times: dict[str, list[float]] = field(default_factory=dict)
    moves: list[TimedMove] = field(default_factory=list)
    truncated: bool = False
    wall_hits: dict[str, int] = field(default_factory=dict)
    contacts: dict[str, int] = field(default_factory=dict)
    #: robot -> the position NEES (true - estimated position against the plan's covariance) at
    #: each point of its paths (nan where the plan has no covariance or the point was not reached)
    planned_nees: dict[str, list[float]] = field(default_factory=dict)
    #: robot -> the position NEES against the filter's own covariance at each control step
    own_nees: dict[str, list[float]] = field(default_factory=dict)
    #: robot -> range beams used by its filter and rejected by the innovation gate
    beams: dict[str, list[int]] = field(default_factory=dict)
    #: (robot, plan step of the move under way, or of its last one when it stands; -1 before its
    #: first) -> control steps its true pose hit a wall / touched another robot's
    move_hits: dict[tuple[str, int], int] = field(default_factory=dict)
    move_contacts: dict[tuple[str, int], int] = field(default_factory=dict)
    #: every contact's first step, in the order they began (:class:`HitEvent`)
    hit_events: list[HitEvent] = field(default_factory=list)
    #: robot -> the cost terms as executed (docs/models.md): c_u = sum (v² + omega²) dt of the
    #: commands, c_Sigma = sum trace(Sigma) dt of the filter's covariance while it drives, c_G the
    #: distances between the estimate and the path's end at the end of each move
    c_u: dict[str, float] = field(default_factory=dict)
    c_sigma: dict[str, float] = field(default_factory=dict)
    c_goal: dict[str, float] = field(default_factory=dict)
    #: the moves of ``moves`` that were cut (out of budget or of draws): they never reached their room
    cut: list[TimedMove] = field(default_factory=list)
    #: every driving step's actual error, the localiser's covariance and the plan's (consistency.py)
    consistency: ConsistencyTrace = field(default_factory=ConsistencyTrace)
    #: nav2's recovery behaviours run, by name (tmpnav.execution.recovery), and the moves of
    #: ``cut`` whose navigation nav2 failed after its last retry
    recoveries: dict[str, int] = field(default_factory=dict)
    given_up: list[TimedMove] = field(default_factory=list)

    def reached(self) -> list[TimedMove]:
        """The moves that reached their room (not cut), in the order they ended."""
        return [m for m in sorted(self.moves, key=lambda m: m.end) if m not in self.cut]

    def schedule(self, robots: tuple[str, ...]) -> Schedule:
        """The moves as executed, in plan order: a schedule like the plan's."""
        moves = sorted(self.moves, key=lambda m: (m.step, robots.index(m.robot)))
        return Schedule(robots, tuple(moves))


@dataclass(frozen=True)
class Draws:
    """A session's random numbers, indexed so that both configurations share them."""

    initial: np.ndarray  # (N, 3)
    motion: np.ndarray  # (N, S, 2)
    landmark: np.ndarray  # (N, S, L, 2)
    mutual: np.ndarray  # (N, N, S, 2)
    scan: np.ndarray  # (N, S, B): the range beams' noise (B = 0 without a range sensor)

    @staticmethod
    def draw(seed: int, session: int, n: int, steps: int, landmarks: int, beams: int = 0) -> Draws:
        """The draws of session ``session`` for ``n`` robots, ``steps`` control steps, ``landmarks``
        and ``beams`` per range scan (drawn last: the others do not depend on them)."""
        rng = np.random.default_rng([seed, session])
        return Draws(
            initial=rng.standard_normal((n, 3)),
            motion=rng.standard_normal((n, steps, 2)),
            landmark=rng.standard_normal((n, steps, landmarks, 2)),
            mutual=rng.standard_normal((n, n, steps, 2)),
            scan=rng.standard_normal((n, steps, beams)),
        )

    @property
    def steps(self) -> int:
        """Control steps drawn: a session that needs more is cut there."""
        return int(self.motion.shape[1])


def nees(error: np.ndarray, cov: np.ndarray | None) -> float:
    """The normalised estimation error squared eᵀ Σ⁻¹ e of a position error e (2,) against its
    covariance Σ (2, 2): 2 on average for a consistent filter; nan without a usable Σ."""
    if cov is None:
        return math.nan
    a, b, c, d = float(cov[0, 0]), float(cov[0, 1]), float(cov[1, 0]), float(cov[1, 1])
    det = a * d - b * c
    if det == 0.0:
        return math.nan
    e0, e1 = float(error[0]), float(error[1])
    return (d * e0 * e0 - (b + c) * e0 * e1 + a * e1 * e1) / det  # eᵀ Σ⁻¹ e, Σ⁻¹ = [[d, -b], [-c, a]] / det


#: redraws of a true start that a robot's disc would find in collision with the map
START_REDRAWS = 64


def free_start(mean: np.ndarray, cov: np.ndarray, z: np.ndarray, world: World, radius: float) -> np.ndarray:
    """A true start pose (3,) drawn from the belief N(mean, cov) with the standard normal draw
    ``z`` (3,), conditioned on the robot's disc being free of the map: a robot cannot stand in a
    wall, however wide its initial belief. Where mean + L z (L L^T = cov) is free, that pose;
    else the first free one of up to :data:`START_REDRAWS` redraws from a stream seeded by the
    bits of ``z`` (the same in every process), or the last of them."""
    root = np.linalg.cholesky(cov)
    pose = mean + root @ z
    if world.is_free(pose[None, :2], radius)[0]:
        return pose
    rng = np.random.default_rng(np.frombuffer(np.ascontiguousarray(z, dtype=float).tobytes(), dtype=np.uint32))
    for _ in range(START_REDRAWS):
        pose = mean + root @ rng.standard_normal(3)
        if world.is_free(pose[None, :2], radius)[0]:
            break
    return pose
