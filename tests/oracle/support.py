"""A small world, its roadmap and a set of actions to evaluate, shared by the oracle tests."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from tmpnav.oracle.evaluate import Request
from tmpnav.oracle.executors import OracleContext
from tmpnav.oracle.table import initial_state
from tmpnav.pipeline import load_world
from tmpnav.roadmap import build_roadmap

ROOT = Path(__file__).resolve().parents[2]


def make_two_rooms() -> OracleContext:
    scenario, world = load_world(ROOT / "tests" / "fixtures" / "two_rooms.yaml")
    return OracleContext(scenario, world, build_roadmap(world, scenario.robots, scenario.roadmap))


def actions(ctx: OracleContext) -> list[Request]:
    """Single moves of both robots to every room, and both robots moving together."""
    sc, rm = ctx.scenario, ctx.roadmap
    s1, s2 = initial_state(sc, rm.starts["r1"], "r1"), initial_state(sc, rm.starts["r2"], "r2")
    rooms = [r.name for r in sc.rooms]
    out = [Request(("r1",), (s1,), (room,)) for room in rooms]
    out += [Request(("r2",), (s2,), (room,)) for room in rooms]
    out += [Request(("r1", "r2"), (s1, s2), (a, b)) for a in rooms for b in rooms]
    return out


def variant(ctx: OracleContext, **changes: object) -> OracleContext:
    return replace(ctx, scenario=replace(ctx.scenario, **changes))  # type: ignore[arg-type]
