"""ENHSP on an unfolded belief space: the exact task plan with carried-over beliefs.

:mod:`tmpnav.attachment.unfold` enumerates the contexts of a small task (where the robots
are, which rooms are visited, the team's joint belief) and the task actions between them
with their exact carried costs. This module writes that graph as a PDDL problem -- the
``goto_room`` actions of pddl/mixed.pddl, each grounded in the context it starts from,
with a predicate ``in`` that says which context the plan has reached -- and lets ENHSP
(through unified-planning's engine, :func:`tmpnav.task.solve.solve_text`) find the
cheapest plan. Entry rules and goals are the domain's own; the contexts only make each
action's cost the one it has after the steps before it.
"""

from __future__ import annotations

from dataclasses import dataclass

from tmpnav.errors import PlannerCrashError
from tmpnav.task.encodings import scaled
from tmpnav.task.names import PddlNames
from tmpnav.task.plans import Rules, Step
from tmpnav.task.solve import SolveResult, solve_text
from tmpnav.types import Goals


@dataclass(frozen=True)
class Edge:
    """A step from one context to another, at its exact carried cost."""

    source: int
    target: int
    step: Step
    cost: float


@dataclass(frozen=True)
class BeliefGraph:
    """The unfolded belief space: contexts 0..n-1 (0 is the start), edges, goal contexts."""

    n_contexts: int
    edges: tuple[Edge, ...]
    goal_contexts: tuple[int, ...]
    steps_simulated: int


@dataclass(frozen=True)
class UnfoldedTask:
    """The PDDL text of a belief graph, and the way back from its actions to the edges."""

    domain: str
    problem: str
    actions: dict[str, Edge]

    def solve(self, planner: str, timeout: float) -> SolveResult:
        return solve_text(self.domain, self.problem, planner, timeout)

    def decode(self, result: SolveResult) -> list[Edge]:
        out = []
        for name, _ in result.actions:
            edge = self.actions.get(name.lower())
            if edge is None:
                raise PlannerCrashError(f"the planner returned an action tmpnav does not know: {name}")
            out.append(edge)
        return out


def write_unfolded(
    graph: BeliefGraph, robots: tuple[str, ...], locations: tuple[str, ...], rules: Rules
) -> UnfoldedTask:
    """The belief graph as a PDDL domain and problem (one action per edge)."""
    names = PddlNames.of(robots, locations)
    rob, loc = names.robot, names.location
    actions: dict[str, Edge] = {}
    texts = []
    for k, edge in enumerate(graph.edges):
        name = f"goto_room_in_context_{k + 1}"
        actions[name] = edge
        pre = [f"(in c{edge.source})"]
        eff = [f"(not (in c{edge.source}))", f"(in c{edge.target})"]
        for r, origin, dest in edge.step:
            pre.append(f"(robot_in {rob[r]} {loc[origin]})")
            own = (r, dest) in rules.entries
            pre.append(
                f"(or (not (visited {loc[dest]})) (not (visited_by {rob[r]} {loc[dest]})))"
                if own
                else f"(not (visited {loc[dest]}))"
            )
            eff.append(f"(not (robot_in {rob[r]} {loc[origin]}))")
        for r, _, dest in edge.step:
            eff.append(f"(robot_in {rob[r]} {loc[dest]}) (visited {loc[dest]})")
            if (r, dest) in rules.entries:
                eff.append(f"(visited_by {rob[r]} {loc[dest]})")
        texts.append(
            f" (:action {name}\n  :parameters ()\n  :precondition (and {' '.join(pre)})\n"
            f"  :effect (and {' '.join(eff)} (increase (total-cost) {max(scaled(edge.cost), 0)})))\n"
        )
    contexts = " ".join(f"c{i}" for i in range(graph.n_contexts))
    domain = (
        "(define (domain tmpnav-belief-contexts)\n"
        " (:requirements :strips :typing :negative-preconditions :disjunctive-preconditions :action-costs)\n"
        " (:types robot location context)\n"
        f" (:constants\n   {' '.join(rob.values())} - robot\n   {' '.join(loc.values())} - location\n"
        f"   {contexts} - context\n )\n"
        " (:predicates (robot_in ?r - robot ?l - location) (visited ?l - location)\n"
        "   (visited_by ?r - robot ?l - location) (in ?c - context))\n"
        " (:functions (total-cost))\n" + "".join(texts) + ")\n"
    )
    init = ["(= (total-cost) 0)", "(in c0)"]
    for r, where in rules.start_location.items():
        init.append(f"(robot_in {rob[r]} {loc[where]}) (visited {loc[where]})")
        if (r, where) in rules.goals.marked_at_start(rules.start_location):
            init.append(f"(visited_by {rob[r]} {loc[where]})")
    goals = _goal(rules.goals, rules, names) + "".join(f" (in c{g})" for g in graph.goal_contexts)
    problem = (
        "(define (problem tmpnav-belief)\n (:domain tmpnav-belief-contexts)\n (:init\n  "
        + "\n  ".join(init)
        + f"\n )\n (:goal (and {goals}))\n (:metric minimize (total-cost))\n)\n"
    )
    return UnfoldedTask(domain, problem, actions)


def _goal(goals: Goals, rules: Rules, names: PddlNames) -> str:
    parts = [f"(visited {names.location[x]})" for x in goals.required]
    parts += [f"(visited_by {names.robot[r]} {names.location[x]})" for r, x in sorted(rules.targets)]
    parts += [f"(robot_in {names.robot[r]} {names.location[x]})" for r, x in goals.ends]
    return " ".join(parts)
