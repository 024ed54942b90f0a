"""Resource caps: how big an input may be before tmpnav refuses it, and the estimates.

Each cap bounds one quantity that grows a run's memory or time without bound: the size
of a YAML file, its values after alias expansion, the cells of the occupancy grid, the
control steps of one move, goal rooms x robots, and the entries of the cost table. The
quantity is estimated from the scenario *before* the work that it would blow up starts,
and a refusal is one line with the estimate and the cap (docs/limits.md).

Every cap can be lifted for one run with an environment variable, ``TMPNAV_MAX_<NAME>``
(``TMPNAV_MAX_MAP_CELLS=100000000 tmpnav plan big.yaml``): the same mechanism for every
cap, and a scenario file stays valid on every machine it is copied to. The defaults let
a 60-room, 8-robot building through, and keep a 2-core, 24 GB machine from running out
of memory.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from tmpnav.choices import ENCODINGS
from tmpnav.errors import InputError


@dataclass(frozen=True)
class Cap:
    """One resource cap: its name, default and what it bounds (for messages and docs)."""

    name: str
    default: int
    quantity: str  # what is counted
    reason: str  # what the default protects, measured

    @property
    def env(self) -> str:
        """The environment variable that replaces the default."""
        return f"TMPNAV_MAX_{self.name.upper()}"

    def value(self) -> int:
        """The cap in force: the environment variable when set, else the default."""
        text = os.environ.get(self.env)
        if text is None or not text.strip():
            return self.default
        try:
            number = float(text.replace("_", ""))
        except ValueError:
            number = math.nan
        if not (math.isfinite(number) and number >= 1 and number == int(number)):
            raise InputError(
                f"environment variable {self.env}={text!r} is not a positive whole number; "
                f"expected a cap such as {self.default} (the default)"
            )
        return int(number)

    def refusal(self, estimate: float, advice: str, at_least: bool = False) -> str:
        """The end of a refusal: the estimate (a lower bound when ``at_least``), the cap,
        what to change and, when the estimate is not astronomical, how to lift the cap."""
        text = f"{_count(estimate)} {self.quantity}; the cap is {self.value():,} ({advice}"
        if at_least:
            text += f", or raise the cap above {_count(estimate)} with {self.env}"
        elif _finite(estimate) and estimate < ASTRONOMICAL:
            text += f", or raise the cap: {self.env}={math.ceil(estimate)}"
        return text + ")"


#: estimates beyond this are not worth lifting a cap for (no machine has the memory)
ASTRONOMICAL = 1e15


def _finite(x: float) -> bool:
    try:
        return math.isfinite(x)
    except OverflowError:  # an int too large for a float
        return False


def _count(x: float) -> str:
    """A count as people read it: 1,234,567, or about 1.2e+21 when it is astronomical."""
    if not _finite(x):
        return "more than 1e308"
    if x >= ASTRONOMICAL:
        return f"about {float(x):.2g}"
    return f"{math.ceil(x):,}"


YAML_BYTES = Cap(
    "yaml_bytes",
    16_000_000,
    "bytes of YAML",
    "a YAML file is read whole into memory before it is parsed (a device or a pipe no further than the cap)",
)
YAML_NODES = Cap(
    "yaml_nodes",
    500_000,
    "values (aliases expanded)",
    "nested anchors expand exponentially (an alias bomb); 500,000 values load in about 2 s",
)
MAP_CELLS = Cap(
    "map_cells",
    64_000_000,
    "grid cells",
    "about 35 bytes per cell to build and check the world: 1.7 GB at 49 million cells",
)
MOVE_STEPS = Cap(
    "move_steps",
    100_000,
    "control steps for a move across the map",
    "the oracle keeps each move's controls, poses and visibility per step: 6-9 GB at dt 1e-6",
)
GOAL_ASSIGNMENTS = Cap(
    "goal_assignments",
    5_000,
    "goal rooms x robots",
    "60 rooms and 8 robots are 480",
)
TABLE_ENTRIES = Cap(
    "table_entries",
    5_000_000,
    "cost-table entries",
    "the exact search with table costs lists every candidate move and pair of moves in memory, hundreds of "
    "bytes each (the other searches count their single moves only)",
)

#: every cap, in the order of docs/limits.md
CAPS: tuple[Cap, ...] = (YAML_BYTES, YAML_NODES, MAP_CELLS, MOVE_STEPS, GOAL_ASSIGNMENTS, TABLE_ENTRIES)

#: nesting deeper than this is refused outright (no scenario needs more than 6 levels)
YAML_MAX_DEPTH = 32


def encoding_table(encoding: str) -> tuple[str, bool]:
    """(where a robot may move: goals | all-rooms, whether pairs are costed) of an encoding."""
    spec = ENCODINGS.get(encoding, ENCODINGS["mixed"])
    return spec.destinations, spec.pairs


def grid_cells(width: float, height: float, resolution: float) -> float:
    """Cells of a grid covering width x height metres, as a float (never overflows)."""
    cols, rows = width / resolution, height / resolution
    if not (math.isfinite(cols) and math.isfinite(rows)):
        return math.inf
    return float(math.ceil(cols - 1e-9)) * float(math.ceil(rows - 1e-9))


def move_steps(width: float, height: float, speed: float, turn_rate: float, dt: float) -> tuple[float, float]:
    """Estimated control steps of a long move: (driving steps, turning steps).

    The move crosses the map's width plus height at ``speed`` (a roadmap path rarely
    goes farther) and turns twice on the spot, 4 pi rad at ``turn_rate``; the controls
    take one step per dt (tmpnav.belief.controls.path_controls).
    """
    try:
        return (width + height) / (speed * dt), 4 * math.pi / (turn_rate * dt)
    except (ZeroDivisionError, OverflowError):
        return math.inf, math.inf


def table_entries(destinations: list[int], encoding: str) -> float:
    """Estimated entries of the cost table for robots that may each move to
    ``destinations[i]`` rooms.

    Mirrors the oracle's enumeration (tmpnav.oracle.table): d single moves out of the
    start and d (d - 1) between destinations per robot, so about d² each; with pairs,
    every single move of one robot against every single move of another, before the
    encoding's filter (an upper bound: the filter drops a share that shrinks like 1/d,
    about 10% at 30 rooms).
    """
    singles = [float(d) * float(d) for d in destinations]
    total = sum(singles)
    if encoding_table(encoding)[1]:
        running = 0.0
        for s in singles:
            total += running * s
            running += s
    return total
