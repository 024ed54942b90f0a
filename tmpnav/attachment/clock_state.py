"""The values of the team's clock (:mod:`tmpnav.attachment.clock`): what a robot does from a
step on (:class:`Leg`), a paired move's draws (:class:`Pairing`), a move on the clock
(:class:`MoveRun`), the clock at a step (:class:`ClockState`, an immutable value) and a plan
run on it (:class:`ClockRun`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tmpnav.attachment.team import Team
from tmpnav.errors import TmpnavError
from tmpnav.oracle.nominal import NominalMotion
from tmpnav.results import Schedule
from tmpnav.types import CostTerms, CostWeights, TrajectoryStep, risk_penalty


class Unreachable(TmpnavError):
    """A plan step whose robots cannot reach their rooms from where they are."""


@dataclass(frozen=True, eq=False)
class Leg:
    """What a robot does from step ``start`` until its next leg: drive ``motion`` (then stand
    at its end), or stand at ``node`` (``motion`` None) before its first move."""

    start: int
    motion: NominalMotion | None
    node: int
    heading: float
    pose: np.ndarray  # (3,) where it stands when not driving
    noise_seed: int  # its landmark-noise stream, indexed from ``start``
    #: the robot's history of legs up to this one, as a number (tmpnav.attachment.own_legs;
    #: 0 where the team runs in one joint EKF)
    key: int = 0


@dataclass(frozen=True)
class Pairing:
    """Two robots of a paired move: their mutual draws from ``start`` for ``steps`` steps."""

    robots: tuple[int, int]  # team indices, in the order of the oracle's request
    start: int
    steps: int
    seed: int


@dataclass(frozen=True, eq=False)
class MoveRun:
    """One robot's move on the clock: its plan step, when it could start, started and ends
    (control steps), its motion, and its cost terms once it has ended."""

    step: int
    robot: int  # team index
    ready: int
    start: int
    end: int
    motion: NominalMotion
    csig_start: float  # the robot's running c_Sigma when the move started
    risk_start: float = 0.0  # and its running collision bound
    terms: CostTerms | None = None  # set when the move has ended
    risk: float = 0.0  # its collision bound (docs/models.md), set when the move has ended

    def cost(self, weights: CostWeights, max_risk: float | None = None) -> float:
        """Its weighted terms, and the penalty of a collision bound over ``max_risk``
        (tmpnav.types.risk_penalty: 0 within it)."""
        assert self.terms is not None, "the move has not ended"
        return self.terms.total(weights) + risk_penalty(self.risk, max_risk)


@dataclass(frozen=True, eq=False)
class ClockState:
    """The clock at step ``t``: the team's joint belief, each robot's legs and when it is free,
    the paired moves' draws, the moves under way and those ended (with their cost)."""

    t: int
    team: Team
    legs: tuple[tuple[Leg, ...], ...]
    free: tuple[int, ...]  # the step at which each robot ends its latest move
    csig: tuple[float, ...]  # each robot's running c_Sigma over all its steps
    risk: tuple[float, ...] = ()  # each robot's collision bound summed over its driving steps
    pairings: tuple[Pairing, ...] = ()
    open: tuple[MoveRun, ...] = ()  # moves under way
    closed: tuple[MoveRun, ...] = ()  # moves ended, in the order they ended
    closed_cost: float = 0.0  # the sum of their costs
    late: bool = False  # a move started so far arrives after its target's window closes (goals.jobs)

    def where(self, i: int) -> tuple[int, float]:
        """Robot i's node and heading at the end of its latest leg (where its next move starts)."""
        leg = self.legs[i][-1]
        return leg.node, leg.heading


@dataclass
class ClockRun:
    """A plan run on the team's clock: its moves (in plan order), the schedule, the state at the
    end, and (when recorded) each robot's belief at every control step."""

    moves: list[MoveRun]
    schedule: Schedule
    end: ClockState
    trajectories: dict[str, list[TrajectoryStep]] | None = None
    #: (when recorded) each robot's positions (T, 2) and position stds (T,) at the steps of its
    #: trajectory, as arrays (tmpnav.belief.conflicts.find_conflicts' ``tracks``)
    tracks: dict[str, tuple[np.ndarray, np.ndarray]] | None = field(default=None, repr=False, compare=False)

    @property
    def makespan(self) -> float:
        return self.schedule.makespan

    def step_costs(self, steps: int, weights: CostWeights, max_risk: float | None = None) -> list[float]:
        """Each plan step's cost: the weighted terms of its robots' moves (with the penalty of
        a collision bound over ``max_risk``), summed."""
        costs = [0.0] * steps
        for move in self.moves:
            costs[move.step] += move.cost(weights, max_risk)
        return costs

    @property
    def risk(self) -> float:
        """The plan's collision bound: its moves' bounds summed (Boole's inequality), at most 1."""
        return min(1.0, sum(m.risk for m in self.moves))
