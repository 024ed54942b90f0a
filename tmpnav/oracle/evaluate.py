"""The semantic attachment: the cost of a task action, computed by the motion planner.

For an action (its robots, their start states, their target rooms) the oracle plans each
robot's motion to every pose instantiation of its target room (all combinations for a
pair, two robots never ending on the same pose), propagates the beliefs along the motions
(jointly, with mutual observations, for a pair) and keeps the combination of minimum cost
(paper, section Approach). Its goal nodes are where the robots end up; they start the
robots' next moves.

:func:`evaluate` ties the parts together:

* :mod:`~tmpnav.oracle.motionsets`: the motions of each robot and start, laid out for the
  compiled EKF (:mod:`tmpnav.belief.sequences`);
* :mod:`~tmpnav.oracle.singles`: every motion simulated with its robot alone;
* :mod:`~tmpnav.oracle.pairs`: the combinations of pair requests, their mutual visibility,
  factorisation and joint simulation;
* :mod:`~tmpnav.oracle.bounds`: the lower bound that prunes pairs not worth simulating.

Two arguments keep the work small without changing any result:

* Factorisation. If the two robots of a combination never see each other and their start
  beliefs are uncorrelated, the joint EKF stays block-diagonal (paper eqs. (10), (12)):
  each robot's belief, hence its cost, is the one it has moving alone, because each
  robot's simulated observations come from its own stream. The joint cost is then the sum
  of two single-robot costs, computed once and shared by every pair that contains them.
* Shared prefixes. Motions from one start state follow the shortest-path tree of the
  roadmap, so many simulations begin with identical steps, and the simulated noise of a
  step depends only on the robot's start and the step index. Simulations are run in
  lexicographic order of their controls and each restarts from the state after the steps
  it shares with the previous one (:mod:`tmpnav.belief.trie`, :mod:`tmpnav.belief.kernel`).

A result depends only on its own request, never on the batch it was computed in.
"""

from __future__ import annotations

from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.motionsets import SetKey, motion_sets
from tmpnav.oracle.pairs import PairCombos
from tmpnav.oracle.requests import EvalStats, Request, StartState, mutual_seed
from tmpnav.oracle.singles import SingleRuns
from tmpnav.types import MotionResult

__all__ = ["EvalStats", "Request", "StartState", "evaluate", "mutual_seed"]


def evaluate(lib: MotionLibrary, requests: list[Request]) -> tuple[list[MotionResult | None], EvalStats]:
    """Evaluate actions; None for an action whose robots cannot reach their rooms."""
    stats = EvalStats()
    lib.prepare([s.node for r in requests for s in r.starts])
    wanted: dict[SetKey, set[int]] = {}
    for req in requests:
        for robot, start, room in zip(req.robots, req.starts, req.rooms, strict=True):
            wanted.setdefault((robot, start), set()).update(lib.roadmap.instantiations[room])
    sets = motion_sets(lib, wanted)
    # the collision bound only where a threshold chooses by it; a request without one has no
    # bound in its result, whatever the batch it comes in (tmpnav.oracle.motionsets.MotionTable)
    priced = any(req.max_risk is not None for req in requests)
    pairs = PairCombos(lib, sets, requests, priced)
    singles = SingleRuns(lib, sets, priced)
    for req in requests:
        if req.n == 1 and (req.robots[0], req.starts[0]) in sets:
            ms = sets[(req.robots[0], req.starts[0])]
            singles.need(ms, ms.goals_in(lib, req.rooms[0]))
    for ms, local in pairs.singles_needed():
        singles.need(ms, local)
    singles.run(stats)
    pairs.run(stats, singles)
    return [singles.best(req) if req.n == 1 else pairs.best(i, singles) for i, req in enumerate(requests)], stats
