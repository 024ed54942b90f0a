"""A :class:`~tmpnav.rooms.proposal.Proposal` -> the text of a scenario YAML file, with comments
that say what the user must check. The file validates and plans as written: the robot is a
placeholder at the roomiest spot of the best-connected room and the goals are pre-filled."""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from tmpnav.atomic import write_file
from tmpnav.rooms.proposal import DEEP_DOOR, ROBOT_RADIUS, Proposal, RoomProposal
from tmpnav.version import __version__
from tmpnav.world.rosmap import SPECK_WIDTH, speck_count

WIDTH = 100  # characters per line of a wrapped polygon

#: the robots' sensors: a typical 2D lidar against the map (docs/scenario.md, models.range_sensor)
MODELS = (
    "models:",
    "  # a typical 2D lidar: put your robots' (range, field of view, range noise, spot divergence).",
    "  # The robots localise as nav2's AMCL does at its defaults (localiser: docs/models.md); give",
    "  # localiser its parameters, or `tmpnav calibrate` them. Delete the line for the paper's model:",
    "  # landmarks and other robots only",
    "  range_sensor: {range: 12, fov: 360 deg, beams: 60, sigma_range: 0.03, divergence: 0.01}",
)


def scenario_yaml(proposal: Proposal, name: str, map_ref: str, map_shown: str) -> str:
    """The scenario file; ``map_ref`` is the map YAML's path relative to the scenario file and
    ``map_shown`` the path to mention in the header."""
    parts = [
        _header(proposal, map_shown),
        f"name: {json.dumps(name)}",
        f"description: {json.dumps(f'Rooms segmented from {map_shown} by tmpnav rooms; check them (see above)')}",
        "map:",
        f"  ros: {json.dumps(map_ref)}",
        *_despeckle(proposal),
        "",
        *_rooms(proposal),
        "",
        *_doors(proposal),
        "",
        *_landmarks(proposal),
        "",
        *_robots(proposal),
        "",
        *MODELS,
        "",
        "roadmap:",
        f"  samples: {proposal.samples}  # PRM milestones: tmpnav rooms checked that every room connects with these",
        "  instantiations: 4  # goal poses sampled in each room",
        "  seed: 1",
        "",
        "goals:",
        f"  visit: [{', '.join(proposal.goals)}]  # pre-filled so that `tmpnav plan` runs as written: put yours",
    ]
    if proposal.halls:
        parts[-1] += " (more goals take longer to plan: see `tmpnav plan --help`, --search)"
    parts += _stations_example(proposal)
    return "\n".join(parts) + "\n"


def _despeckle(p: Proposal) -> list[str]:
    """map.despeckle where the map has specks (tmpnav.world.rosmap.specks), with how many."""
    n = speck_count(p.grid.occupied, SPECK_WIDTH, p.grid.resolution)
    if not n:
        return []
    return [
        f"  despeckle: {SPECK_WIDTH:g}  # {n} speck{'s' * (n > 1)} of occupied cells alone in free space: map noise,"
        " cleared (0 if they are real obstacles)"
    ]


def _stations_example(p: Proposal) -> list[str]:
    """Commented lines that show how to give a room or place several stations (docs/scenario.md)."""
    place = p.goals[0] if p.goals else p.usable_rooms[0].name
    x, y = next(r.spot for r in p.usable_rooms if r.name == place)
    return [
        "  # stations: a room or place may hold several named goal poses, each a goal of its own with its",
        "  # job (service, window, robots, penalty); name them in visit, goals.robots or goals.ends (a dock)",
        "  # in place of the room. Put x, y (inside the place, clear of walls) and the heading to stop at:",
        f"  # visit: [{place}-a, {place}-b]",
        "  # jobs:",
        f"  #   - {{name: {place}-a, place: {place}, pose: [{x:.2f}, {y:.2f}, 0 deg], service: 20 s}}  # roomiest spot",
        f"  #   - {{name: {place}-b, place: {place}, pose: [x, y, 90 deg], window: [0 s, 300 s]}}",
    ]


def summary(p: Proposal) -> str:
    """What was found, in one line: rooms (and places from halls), doors, landmark candidates."""
    rooms = sum(1 for r in p.usable_rooms if r.hall is None)
    if not p.halls:
        return f"{rooms} rooms, {len(p.doors)} doors, {len(p.landmarks)} landmark candidates"
    places = len(p.usable_rooms) - rooms
    links = len(p.connections)
    return (
        f"{_count(rooms, 'room')}, {_count(places, 'place')} from splitting {_count(len(p.halls), 'hall')} "
        f"larger than {p.max_area:g} m², {_count(len(p.doors) - links, 'door')}, "
        f"{_count(links, 'connection')}, {_count(len(p.landmarks), 'landmark candidate')}"
    )


def _count(n: int, what: str) -> str:
    return f"{n} {what}" if n == 1 else f"{n} {what}s"


def _header(p: Proposal, map_shown: str) -> str:
    usable = p.usable_rooms
    if p.halls:
        return _comment(_hall_header(p, map_shown))
    text = f"""\
Scenario skeleton written by `tmpnav rooms` (tmpnav {__version__}) from the ROS map {map_shown}.
Found {len(usable)} rooms, {len(p.doors)} doors, {len(p.landmarks)} landmark candidates. Coordinates: metres, map frame.
`tmpnav show THIS_FILE -o world.png` draws it. Check before you plan:

1. rooms: R1..R{len(p.rooms)} are numbered in reading order (top row of the map first, left to right).
   Rename them (a name starts with a letter, then letters, digits, '_' or '-'), delete those
   nobody needs to visit, and fix outlines that split or join rooms wrongly (or run
   `tmpnav rooms` again with --min-area or --max-rooms).
2. doors: all open. Set `state: closed` on doors that are shut: a closed door is a wall.
3. landmarks: candidates (isolated pillars and obstacles, door frames, room corners). Keep
   those your robots' sensors really recognise, and add the ones you know of. The robots
   also carry a 2D lidar (models.range_sensor): give your robots' figures.
4. robots: r1 is a placeholder (radius {ROBOT_RADIUS:g} m) at the roomiest spot of {p.robot_room}. Put your
   robots with their real start poses, radii and speeds.
5. goals: pre-filled with the rooms nearest to r1 so that `tmpnav plan` runs as written.
   Replace them with the rooms your robots must visit, or with stations: named poses inside
   a room, several to a room (the comments under goals show how)."""
    return _comment(text)


def _hall_header(p: Proposal, map_shown: str) -> str:
    """The header of a map with halls: places, connections, two robots."""
    names = " and ".join(r.name for r in p.robots)
    robots = f"{names} are placeholders" if len(p.robots) > 1 else f"{names} is a placeholder"
    spots = "spots" if len(p.robots) > 1 else "spot"
    where = " and ".join(r.room for r in p.robots)
    return f"""\
Scenario skeleton written by `tmpnav rooms` (tmpnav {__version__}) from the ROS map {map_shown}.
Found {summary(p)}.
Coordinates: metres, map frame. `tmpnav show THIS_FILE -o world.png` draws it. Check before you plan:

1. rooms: R1.. are rooms, P1.. places in halls (aisles between racks, the fronts of aisles,
   parts of open floor), both numbered in reading order (top of the map first, left to right).
   Rename them (a name starts with a letter, then letters, digits, '_' or '-'), delete those
   nobody needs to visit, join or redraw places as your site names them (or run `tmpnav rooms`
   again with --max-area: smaller gives more, smaller places; --min-area, --max-rooms).
2. doors: all open. Set `state: closed` on doors that are shut: a closed door is a wall. A
   connection between two places is open floor: leave it open, or delete it.
3. landmarks: candidates (isolated pillars and obstacles: pallets, short racks; door frames,
   room corners). Keep those your robots' sensors really recognise, and add the ones you know of.
   The robots also carry a 2D lidar (models.range_sensor): give your robots' figures.
4. robots: {robots} (radius {ROBOT_RADIUS:g} m) at the roomiest {spots} of {where}.
   Put your robots with their real start poses, radii and speeds; add more as r3, r4, ...
5. goals: pre-filled with the {len(p.goals)} places nearest to the robots so that `tmpnav plan` runs as
   written. Replace them with the places your robots must visit, or with stations: named poses
   inside a place, several to a place (the comments under goals show how)."""


def _comment(text: str) -> str:
    return "\n".join(f"# {line}".rstrip() for line in text.splitlines()) + "\n"


def _rooms(p: Proposal) -> list[str]:
    lines = ["rooms:"]
    hidden = [r for r in p.rooms if not r.reachable]
    for room in p.usable_rooms:
        hall = next((h for h in p.halls if h.places[:1] == (room.name,)), None)
        if hall is not None:
            lines.append(
                f"  # {hall.name}: a hall of {hall.area:.1f} m² (larger than --max-area {p.max_area:g} m²), "
                f"split into places {hall.places[0]}..{hall.places[-1]}"
            )
        lines.append(f"  - name: {room.name}  # {_room_note(p, room)}")
        lines += _wrap("    polygon: ", room.polygon)
    if hidden:
        lines.append(
            f"  # Not reachable by a robot of radius {ROBOT_RADIUS:g} m from r1's start (a passage narrower than "
            f"{2 * ROBOT_RADIUS + 2 * p.map.resolution:.2f} m?), left out:"
        )
        for room in hidden:
            lines.append(f"  # - name: {room.name}  # {_room_note(p, room)}")
            lines += ["  # " + line for line in _wrap("    polygon: ", room.polygon)]
    return lines


def _room_note(p: Proposal, room: RoomProposal) -> str:
    doors = [
        f"{name} to {p.room(d.rooms[1] if d.rooms[0] == room.label else d.rooms[0]).name}"
        for name, d in p.doors.items()
        if room.label in d.rooms
    ]
    if room.hall:  # a place's widest disc reaches into its neighbours: its width says little
        return f"a place of {room.hall}: {room.area:.1f} m²; doors: {', '.join(doors) or 'none'}"
    return f"{room.area:.1f} m², {room.width:.1f} m wide; doors: {', '.join(doors) or 'none'}"


def _doors(p: Proposal) -> list[str]:
    if not p.doors:
        return ["doors: []  # no passage between two rooms was found"]
    lines = ["doors:  # from jamb to jamb; open doors are carved free, closed ones become walls"]
    for name, d in p.doors.items():
        a, b = p.room(d.rooms[0]).name, p.room(d.rooms[1]).name
        note = f"{a} - {b}, {d.width:.2f} m wide"
        if name in p.connections:
            note += f"; a connection across the open floor of {p.room(d.rooms[0]).hall}: keep it open"
        deep = ""
        if name in p.deep_doors:
            deep = f", thickness: {DEEP_DOOR:g}"
            note += f"; carved {DEEP_DOOR:g} m deep: noise in the map blocks the doorway (if closed: 0.15)"
        lines.append(f"  - {{name: {name}, segment: {_points(d.segment)}, state: open{deep}}}  # {note}")
    return lines


def _landmarks(p: Proposal) -> list[str]:
    if not p.landmarks:
        return ["landmarks: []  # none found: add the ones you know of"]
    lines = ["landmarks:  # candidates: keep those your robots recognise"]
    for name, lm in p.landmarks.items():
        x, y = lm.position
        room = p.room(lm.room).name
        lines.append(f"  - {{name: {name}, kind: {lm.kind}, position: [{x:.2f}, {y:.2f}]}}  # {room}: {lm.note}")
    return lines


def _robots(p: Proposal) -> list[str]:
    lines = ["robots:"]
    for k, robot in enumerate(p.robots):
        x, y, theta = robot.pose
        note = "give your robots' start poses" if k == 0 else "a second robot: the team shares the goals"
        lines += [
            f"  - name: {robot.name}  # a placeholder in {robot.room}: {note}",
            f"    pose: [{x:.2f}, {y:.2f}, {theta:.2f}]  # x, y (m), heading (rad)",
            f"    radius: {ROBOT_RADIUS:g}",
        ]
    return lines


def _points(points: Iterable[Iterable[float]]) -> str:
    return "[" + ", ".join(f"[{_num(x)}, {_num(y)}]" for x, y in np.asarray(list(points), dtype=float)) + "]"


def _num(v: float) -> str:
    text = f"{v:.2f}"
    return "0.00" if text == "-0.00" else text


def _wrap(prefix: str, points: np.ndarray) -> list[str]:
    """``prefix`` and a flow sequence of points, broken between points to fit ``WIDTH``."""
    items = [f"[{_num(x)}, {_num(y)}]" for x, y in np.asarray(points, dtype=float)]
    lines, line = [], prefix + "["
    for k, item in enumerate(items):
        piece = item + ("]" if k == len(items) - 1 else ",")
        if len(line) + len(piece) + 1 > WIDTH and not line.endswith("["):
            lines.append(line)
            line = " " * (len(prefix) + 1) + piece
        else:
            line += ("" if line.endswith("[") else " ") + piece
    return [*lines, line]


def skeleton(proposal: Proposal, target: Path | None) -> str:
    """The scenario text to write to ``target`` (None: to print, paths relative to the working
    directory), named after ``target`` or the map, the map referred to relative to it."""
    name = scenario_name(target.stem if target is not None else f"{proposal.map.yaml_path.stem}-rooms")
    return skeleton_in(proposal, target.parent if target is not None else Path.cwd(), name)


def skeleton_in(proposal: Proposal, folder: Path, name: str) -> str:
    """The scenario text for a file in ``folder`` (the map path is relative to it)."""
    import os

    from tmpnav.scenario import display_path

    map_path = proposal.map.yaml_path
    return scenario_yaml(proposal, name, os.path.relpath(map_path, folder.absolute()), display_path(map_path))


def scenario_name(stem: str) -> str:
    """``stem`` made a valid scenario name: a letter first, then letters, digits, '_' or '-'."""
    name = "".join(c if c.isalnum() or c in "_-" else "-" for c in stem).strip("-_")
    return name if name[:1].isalpha() else f"map-{name}".rstrip("-")


def save(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` all or nothing (:func:`tmpnav.atomic.write_file`)."""
    write_file(path, text)
