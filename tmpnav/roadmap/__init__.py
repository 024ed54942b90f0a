"""Stage 3: the probabilistic roadmap (OMPL PRM) as plain arrays, and shortest paths on it."""

from tmpnav.roadmap.graph import RoadmapGraph
from tmpnav.roadmap.prm import build_roadmap, with_starts

__all__ = ["RoadmapGraph", "build_roadmap", "with_starts"]
