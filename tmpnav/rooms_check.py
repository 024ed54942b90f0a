"""Check that a proposed scenario validates and that its roadmap connects every room, growing the
roadmap until it does: the skeleton ``tmpnav rooms`` writes must plan as written.

The proposal is :mod:`tmpnav.rooms`' (a ROS map read into rooms, doors and landmarks: the step
before stage 1); the check runs stages 1-3 on it, so it sits beside the pipeline, not in rooms/.

A room reached only through a narrow doorway needs many PRM milestones before one lands in the
doorway; the number per m² that suits an office leaves such a room out. The roadmap is grown
(OMPL, seeded, as ``tmpnav plan`` grows it) with ``SAMPLES_STEPS`` times the proposed number in
turn, and the first that connects every room is kept.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from tmpnav.errors import RoadmapError, ScenarioError
from tmpnav.lifetime import scratch_folder
from tmpnav.pipeline import load_world
from tmpnav.roadmap import build_roadmap
from tmpnav.rooms.proposal import Proposal
from tmpnav.rooms.skeleton import save, skeleton_in

SAMPLES_STEPS = (1, 2, 3, 5)  # multiples of the proposed roadmap.samples to try
MAX_SAMPLES = 12000


def verify(proposal: Proposal) -> tuple[Proposal, list[str]]:
    """The proposal with a roadmap size that connects every room, and what is still wrong
    (empty when the scenario validates and its roadmap connects)."""
    with scratch_folder("rooms-") as folder:
        path = Path(folder) / "scenario.yaml"
        save(path, skeleton_in(proposal, Path(folder), "check"))
        try:
            scenario, world = load_world(path)
        except ScenarioError as err:
            return proposal, [f"the scenario does not validate: {p.path}: {p.message}" for p in err.problems]
    problem = ""
    for samples in sorted({min(MAX_SAMPLES, proposal.samples * factor) for factor in SAMPLES_STEPS}):
        try:
            build_roadmap(world, scenario.robots, replace(scenario.roadmap, samples=samples))
        except RoadmapError as err:
            problem = str(err)
            continue
        return replace(proposal, samples=samples), []
    return proposal, [problem]
