"""The belief space of a small task, unfolded: every plan prefix with the beliefs it leaves.

With ``--costs carried`` an action's cost depends on the beliefs its robots bring into it,
so the same ``goto_room`` costs differently after different plan prefixes. For a small task
tmpnav enumerates them all: starting from the robots' initial beliefs, every step the entry
rules allow (each robot into each room it may enter, and each paired move that saves at
least ``pair_min_gain`` over the same two moves made alone from the same beliefs) is run on
the team's joint belief (:meth:`CarriedCosts.advance_many`), and each resulting *context*
-- where the robots are, which rooms are visited, the team's joint belief -- is expanded in
turn. Prefixes that end in the same context are merged: single moves of robots whose
beliefs are uncorrelated commute exactly, so their orders lead to one context.

The result is a graph whose edges are task actions with their exact carried costs, and
ENHSP searches it (:func:`tmpnav.task.stage.plan_unfolded`): its optimal plan is the plan
of least executed cost among all plans of singles and such pairs. This is the paper's
semantic attachment taken literally -- each action costed from the belief the search has
reached -- made finite by enumerating the beliefs first. It grows quickly with rooms and
robots; :func:`unfold` gives up (returns None) past ``max_contexts``.
"""

from __future__ import annotations

import hashlib

import numpy as np

from tmpnav.attachment.canonical import _offered
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.team import Team
from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.plans import Rules, State, Step
from tmpnav.task.unfolded import BeliefGraph, Edge
from tmpnav.types import Goals

#: contexts beyond which unfolding gives up (the anytime search takes over)
MAX_CONTEXTS = 6000


def unfold(
    carried: CarriedCosts, goals: Goals, min_gain: float, max_contexts: int = MAX_CONTEXTS
) -> BeliefGraph | None:
    """Every context reachable from the start (see the module docstring); None when there
    are more than ``max_contexts`` of them."""
    rules = Rules(carried.start_location, goals)
    keep = ENCODINGS["mixed"].pair_filter(goals, carried.start_location)
    assert keep is not None
    rooms = tuple(dict.fromkeys(goals.all_rooms))
    start = (carried.start, rules.start())
    ids = {_key(*start): 0}
    frontier = [start]
    edges: list[Edge] = []
    done: list[int] = []
    before = carried.steps_simulated
    while frontier:
        team, state = frontier.pop()
        here = ids[_key(team, state)]
        if rules.done(state):
            done.append(here)
            continue
        singles = _singles(rules, state, carried.robots, rooms)
        pairs = [
            (a[0], b[0])
            for i, a in enumerate(singles)
            for b in singles[i + 1 :]
            if a[0][0] != b[0][0] and keep(a[0], b[0])
        ]
        pairs = [p for p in pairs if _may_both_enter(rules, state, p)]
        outcomes = carried.advance_many(team, [*singles, *pairs], min_gain)
        alone = {s[0]: o.cost for s, o in zip(singles, outcomes, strict=False) if o is not None}
        for step, outcome in zip([*singles, *pairs], outcomes, strict=True):
            if outcome is None:
                continue
            if len(step) == 2 and not (
                step[0] in alone
                and step[1] in alone
                and _offered(outcome.cost, alone[step[0]] + alone[step[1]], min_gain)
            ):
                continue
            nxt = (outcome.team, rules.apply(state, step))
            key = _key(*nxt)
            if key not in ids:
                if len(ids) >= max_contexts:
                    return None
                ids[key] = len(ids)
                frontier.append(nxt)
            edges.append(Edge(here, ids[key], step, outcome.cost))
    return BeliefGraph(len(ids), tuple(edges), tuple(sorted(done)), carried.steps_simulated - before)


def _singles(rules: Rules, state: State, robots: tuple[str, ...], rooms: tuple[str, ...]) -> list[Step]:
    out: list[Step] = []
    for r in robots:
        here = state.at[r]
        out.extend(((r, here, x),) for x in rooms if x != here and _wanted(rules, state, r, x))
    return out


def _wanted(rules: Rules, state: State, robot: str, room: str) -> bool:
    """May ``robot`` enter ``room``, and is there a reason to (a goal not yet achieved)?"""
    if not rules.may_enter(state, robot, room):
        return False
    target = (robot, room) in rules.targets
    return room not in state.visited or target


def _may_both_enter(rules: Rules, state: State, pair: Step) -> bool:
    try:
        rules.apply(state, pair)
    except ValueError:
        return False
    return True


def _key(team: Team, state: State) -> bytes:
    """A context's identity: the team's joint belief and the task state."""
    h = hashlib.blake2b(digest_size=20)
    h.update(np.array(team.node, dtype=np.int64).tobytes())
    h.update(np.array(team.heading, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(team.mean).tobytes())
    h.update(np.ascontiguousarray(team.cov).tobytes())
    h.update(repr((sorted(state.at.items()), sorted(state.visited), sorted(state.visited_by))).encode())
    return h.digest()
