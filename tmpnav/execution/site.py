"""The building ``tmpnav simulate`` scans: the map's walls a few centimetres off, unmapped clutter
and people walking (docs/site.md).

The planner knows the map; a real site differs from it. :class:`SiteNoise` says how (the
command line's ``--site``, :meth:`SiteNoise.parse`); a :class:`Site` is one draw of such a
building for one session: its own signed distance field (the map's, warped, with clutter boxes),
which :func:`tmpnav.world.lidar.scan` ray casts as it does the map's, and people who walk
straight lines and hide what is behind them, placed at the time of each scan.

    site = Site(world, SiteNoise.parse("typical"), session_seed=7, keep_clear=path_xy)
    r = site.ranges(pose, sensor.beam_angles(), sensor, t=12.5)   # (B,) m, nan: no return
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace

import numba as nb
import numpy as np

from tmpnav.execution.site_draws import (
    box_field,
    keep_points,
    offset_lattice,
    place_clutter,
    shifted_walls,
    walks,
)
from tmpnav.types import RangeSensor
from tmpnav.world import World
from tmpnav.world.lidar import cast, scan, sensor_params

#: each term of :class:`SiteNoise`: what it means and what values it takes, for messages
TERMS = {
    "clutter": "unmapped objects per 100 m² of free floor, a number >= 0",
    "clutter_size": "the side of a clutter box in m, a number > 0",
    "wall_offset": "the std of a wall's offset from the map in m, a number from 0 to 0.5",
    "people": "people walking at once per 1000 m² of free floor, a number >= 0",
    "person_radius": "a person's radius in m, a number > 0",
    "person_speed": "a person's walking speed in m/s, a number >= 0",
    "seed": "an integer >= 0",
}


@dataclass(frozen=True)
class SiteNoise:
    """How the site differs from the map; the defaults describe a typical indoor site.
    A bad value raises ``ValueError`` with one line naming its key."""

    # furniture that stood there when the map was made is in the map; what is not is what moved
    # since: a cart, a box, a chair or a bin, about one per 50 m² of free floor
    clutter: float = 2.0  # unmapped objects per 100 m² of free floor
    # the footprint of a chair, a bin, a box or a small cart
    clutter_size: float = 0.4  # m, side of a square box
    # a 5 cm map places a wall to +-2.5 cm (1.4 cm std) and SLAM's scan matching bends a map by
    # a few centimetres more; AMCL's sigma_hit of 0.2 m is there to absorb it and the rest
    wall_offset: float = 0.03  # m, std of a wall's offset along its normal
    # an occupied office holds about one person per 15 m² of free floor, of whom about 5% walk
    # at any moment; a site with any people has at least one walking, however small
    people: float = 3.0  # people walking at once per 1000 m² of free floor
    # the ring a lidar at knee height sees of a person: legs apart, a bag, a coat
    person_radius: float = 0.25  # m
    # indoor walking: 1.0-1.4 m/s along corridors, slower among desks
    person_speed: float = 1.0  # m/s
    seed: int = 0  # with the session's seed, draws the walls, the clutter and the people

    def __post_init__(self) -> None:
        for term in fields(self):
            value = getattr(self, term.name)
            if term.name == "seed":
                ok = isinstance(value, int | np.integer) and value >= 0
            else:
                low_ok = value > 0 if term.name in ("clutter_size", "person_radius") else value >= 0
                ok = math.isfinite(value) and low_ok and (term.name != "wall_offset" or value <= 0.5)
            if not ok:
                raise ValueError(f"site: {term.name}={value!r} is out of range: expected {TERMS[term.name]}")

    @classmethod
    def none(cls) -> SiteNoise:
        """The map exactly: no clutter, every wall where the map has it, nobody walking."""
        return cls(clutter=0.0, wall_offset=0.0, people=0.0)

    @classmethod
    def parse(cls, text: str) -> SiteNoise:
        """The command line's form: ``none``, ``typical`` (the defaults) or comma-separated
        ``key=value`` overrides of the defaults (``clutter=1,people=0``), optionally after ``none``
        or ``typical`` (``none,people=5``). A bad key or value raises ``ValueError``, one line."""
        parts = [p.strip() for p in text.split(",")]
        if not text.strip() or "" in parts:
            raise ValueError(f"site: {text!r} has an empty term: expected none, typical or key=value,key=value")
        base = {"none": cls.none(), "typical": cls()}.get(parts[0])
        if base is not None:
            parts = parts[1:]
        changes: dict[str, float | int] = {}
        for part in parts:
            key, eq, value = (s.strip() for s in part.partition("="))
            if key in TERMS and not eq:
                raise ValueError(f"site: {key} has no value: expected {key}=VALUE, {TERMS[key]}")
            if key not in TERMS:
                raise ValueError(
                    f"site: unknown term {part!r}: expected none or typical first, then key=value with the key "
                    f"one of {', '.join(TERMS)}"
                )
            try:
                changes[key] = int(value) if key == "seed" else float(value)
            except ValueError:
                raise ValueError(f"site: {key}={value!r} is not a number: expected {TERMS[key]}") from None
        return replace(base if base is not None else cls(), **changes)  # type: ignore[arg-type]

    @property
    def exact(self) -> bool:
        """Whether the site is the map itself."""
        return self.clutter == 0 and self.wall_offset == 0 and self.people == 0

    def text(self) -> str:
        """One line for reports: ``clutter 2 per 100 m² (40 cm boxes), walls off by 3 cm (std), ...``."""
        if self.exact:
            return "the map exactly (no clutter, walls where mapped, nobody walking)"
        return ", ".join(
            [
                f"clutter {self.clutter:g} per 100 m² ({100 * self.clutter_size:g} cm boxes)"
                if self.clutter
                else "no clutter",
                f"walls off by {100 * self.wall_offset:g} cm (std)" if self.wall_offset else "walls where mapped",
                f"{self.people:g} people per 1000 m² walking at {self.person_speed:g} m/s"
                if self.people
                else "nobody walking",
            ]
        )


class Site:
    """The true building of one simulation session (see the module docstring).

    ``field`` (rows, cols) m is its signed distance field on the map's grid; ``boxes`` (N, 3) the
    clutter's centres and turns (x, y m, theta rad); people walk back and forth along straight
    lines, ``people_at(t)`` (P, 2) m. Walls and clutter change what the lidar sees only: the robots
    still collide with the map's walls. No clutter box comes within 0.6 m (``site_draws.KEEP_CLEAR``)
    of ``keep_clear``: points (K, 2+), or polylines (a sequence of (n, 2+) arrays, kept clear all
    along their segments); pass the robots' planned paths so that no box stands in their way."""

    def __init__(
        self,
        world: World,
        noise: SiteNoise,
        session_seed: int,
        keep_clear: np.ndarray | Sequence[np.ndarray] | None = None,
    ):
        self.world, self.noise = world, noise
        grid = world.grid
        self.origin = (float(grid.origin[0]), float(grid.origin[1]))
        self.res = float(grid.resolution)
        seeds = np.random.SeedSequence([noise.seed, session_seed]).spawn(3)
        walls, clutter, people = (np.random.default_rng(s) for s in seeds)
        sdf = world.signed_distance
        self.free_area = float(np.count_nonzero(sdf > 0)) * self.res**2  # m²
        self._offsets = offset_lattice(sdf.shape, self.res, noise.wall_offset, walls)
        count = round(noise.clutter * self.free_area / 100.0)
        keep = keep_points(keep_clear)
        self.boxes = place_clutter(sdf, self.origin, self.res, count, noise.clutter_size, keep, clutter)
        self.field = self._field_of(sdf)
        walkers = 0 if noise.people == 0 else max(1, round(noise.people * self.free_area / 1000.0))
        self._walk_start, self._walk_dir, self._walk_length, self._walk_phase = walks(
            self.field, self.origin, self.res, noise.person_radius, walkers, people
        )
        self._params: dict[RangeSensor, np.ndarray] = {}

    def with_world(self, world: World) -> Site:
        """This site around another world of the same grid (a door closed): its walls moved as
        here, the same clutter and the same people."""
        other = copy.copy(self)
        other.world = world
        other.field = self._field_of(world.signed_distance)
        return other

    def walls(self) -> np.ndarray:
        """The signed distance field (rows, cols) m of the site's walls alone, without the clutter."""
        sdf = self.world.signed_distance
        return sdf if self._offsets is None else shifted_walls(sdf, self.res, self._offsets)

    @property
    def walk_lines(self) -> np.ndarray:
        """The straight line each person walks back and forth along: its ends (P, 2, 2) m."""
        ends = self._walk_start + self._walk_length[:, None] * self._walk_dir
        return np.stack([self._walk_start, ends], axis=1)

    def _field_of(self, sdf: np.ndarray) -> np.ndarray:
        """The site's signed distance field around the map's field ``sdf``: its walls moved, with the clutter."""
        field = sdf if self._offsets is None else shifted_walls(sdf, self.res, self._offsets)
        if len(self.boxes):
            field = np.minimum(field, box_field(sdf.shape, self.origin, self.res, self.boxes, self.noise.clutter_size))
        return np.ascontiguousarray(field, dtype=float)

    def text(self) -> str:
        """One line: what this draw holds (``7 clutter boxes, walls off by 3 cm (std), 1 person walking``)."""
        walkers = len(self._walk_length)
        return ", ".join(
            [
                f"{len(self.boxes)} clutter boxes",
                f"walls off by {100 * self.noise.wall_offset:g} cm (std)"
                if self.noise.wall_offset
                else "walls where mapped",
                f"{walkers} {'person' if walkers == 1 else 'people'} walking",
            ]
        )

    def people_at(self, t: float) -> np.ndarray:
        """Where each person stands at time ``t`` (s): (P, 2) m. Each walks its line at the noise's
        speed and turns back at its ends (a triangle wave along it)."""
        out = np.empty((len(self._walk_length), 2))
        _people_at(
            self._walk_start, self._walk_dir, self._walk_length, self._walk_phase, self.noise.person_speed, t, out
        )
        return out

    def ranges(self, pose: np.ndarray, angles: np.ndarray, sensor: RangeSensor, t: float) -> np.ndarray:
        """The true noise-free ranges (B,) m of the beams at ``angles`` (rad from the heading) from
        ``pose`` (3,) at time ``t`` (s); nan where a beam returns nothing. A beam returns from the
        first surface it meets, a wall, a box or a person, within range, beyond the blind zone and
        at most the sensor's largest incidence from head-on (as :func:`tmpnav.world.lidar.scan`)."""
        pose = np.asarray(pose, dtype=float)
        angles = np.asarray(angles, dtype=float)
        if sensor not in self._params:
            self._params[sensor] = sensor_params(sensor)
        params = self._params[sensor]
        B = angles.shape[0]
        r, H, var = np.empty(B), np.empty((B, 3)), np.empty(B)
        scan(self.field, *self.origin, self.res, pose, angles, params, r, H, var)
        if len(self._walk_length):
            people = self.people_at(t)
            _occlude(r, pose, angles, people, self.noise.person_radius, params, self.field, *self.origin, self.res)
        return r


@nb.njit(cache=True)
def _people_at(start, direction, length, phase, speed, t, out):
    """out (P, 2) m: each person's place at time t (s), a triangle wave along its line (:meth:`Site.people_at`)."""
    for p in range(length.shape[0]):
        lap = 2.0 * length[p]
        s = (phase[p] + speed * t) % lap if lap > 0.0 else 0.0
        along = s if s <= length[p] else lap - s
        out[p, 0] = start[p, 0] + along * direction[p, 0]
        out[p, 1] = start[p, 1] + along * direction[p, 1]


@nb.njit(cache=True)
def _occlude(r, pose, angles, people, radius, params, field, x0, y0, res):
    """Beams ``r`` (B,) that meet a person before the walls take the person's range, or nan where
    that return fails (blind zone, largest incidence). From p along unit d, the disc of centre c and
    radius R is met at s = -b - sqrt(b² - |f|² + R²), f = p - c, b = d.f, where the cosine of the
    incidence is sqrt(b² - |f|² + R²) / R. From inside a disc a person is not seen."""
    for b in range(angles.shape[0]):
        psi = pose[2] + angles[b]
        dx, dy = math.cos(psi), math.sin(psi)
        first, cos_first = math.inf, 0.0
        for p in range(people.shape[0]):
            fx, fy = pose[0] - people[p, 0], pose[1] - people[p, 1]
            c = fx * fx + fy * fy - radius * radius
            proj = dx * fx + dy * fy
            disc = proj * proj - c
            if c <= 0.0 or proj >= 0.0 or disc < 0.0:  # inside, behind or beside: both roots ahead need c > 0, proj < 0
                continue
            root = math.sqrt(disc)
            if -proj - root < first:
                first, cos_first = -proj - root, root / radius
        if first == math.inf or first > params[1]:
            continue
        wall = r[b]
        if math.isnan(wall):  # the walls returned nothing: where are they?
            wall = cast(field, x0, y0, res, pose[0], pose[1], psi, params[1])[0]
        if first < wall:
            r[b] = first if first >= params[0] and cos_first >= params[2] else math.nan
