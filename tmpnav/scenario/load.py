"""Load a scenario YAML file into a validated :class:`~tmpnav.types.Scenario`.

Everything wrong with the file is collected and raised at once as a
:class:`~tmpnav.errors.ScenarioError`, one line per problem naming the file, the line,
the key path, the bad value and what is expected. Files are read by
:func:`~tmpnav.scenario.yamlio.read_yaml`: PyYAML's safe loader with YAML 1.2 numbers,
and bounds on size, nesting and alias expansion checked before anything is built.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import yaml

from tmpnav.choices import Objective, default_min_rooms, default_objective
from tmpnav.errors import Problem, ScenarioError
from tmpnav.scenario.format import ROS_MAP, SCENARIO, polygonal_cells
from tmpnav.scenario.limits import MAP_CELLS, YAML_BYTES
from tmpnav.scenario.references import cross_references, stations_of
from tmpnav.scenario.schema import MISSING, Ctx, Issue, key_text
from tmpnav.scenario.yamlio import YamlLimitError, YamlValueError, read_yaml
from tmpnav.types import (
    DEFAULT_MAX_RISK,
    DEFAULT_RISK_SOURCE,
    FLEET_DEFAULT,
    NAV2_AMCL,
    CostWeights,
    Door,
    Goals,
    Job,
    Landmark,
    Models,
    ObservationMode,
    PlannerOptions,
    PolygonMap,
    Pose,
    RangeBearingSensor,
    RangeSensor,
    RoadmapParams,
    RobotSpec,
    Room,
    RosMap,
    ScanModel,
    ScanModelKind,
    Scenario,
)


def display_path(path: Path) -> str:
    """A path as users typed it: relative to the working directory when possible."""
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


class YamlDoc:
    """A YAML file's data (from safe_load) and the line of every key path in it."""

    def __init__(self, path: Path):
        self.path = path
        self.name = display_path(path)
        self.lines: dict[tuple[Any, ...], int] = {}
        self.duplicates: list[tuple[tuple[Any, ...], int]] = []
        try:
            text = self._read(path)
        except FileNotFoundError:
            raise ScenarioError([Problem(self.name, "", "file not found")]) from None
        except IsADirectoryError:
            raise ScenarioError([Problem(self.name, "", "is a directory; expected a YAML file")]) from None
        except (OSError, UnicodeDecodeError) as err:
            raise ScenarioError([Problem(self.name, "", f"cannot be read: {err}")]) from None
        try:
            self.data, node = read_yaml(text)
        except yaml.YAMLError as err:
            raise ScenarioError([Problem(self.name, "", _yaml_message(err), _yaml_line(err))]) from None
        if node is not None:
            self._index(node, ())

    def _read(self, path: Path) -> str:
        """The file's text, refused unread when larger than the yaml_bytes cap. A file whose
        size says nothing (/dev/zero, a pipe) is read no further than the cap."""
        cap = YAML_BYTES.value()
        advice = "a YAML file this large is not a scenario or map file"
        size = path.stat().st_size
        if size > cap:
            raise ScenarioError([Problem(self.name, "", "is " + YAML_BYTES.refusal(size, advice))])
        with open(path, "rb") as fh:
            data = fh.read(cap + 1)
        if len(data) > cap:
            raise ScenarioError(
                [Problem(self.name, "", "is at least " + YAML_BYTES.refusal(len(data), advice, at_least=True))]
            )
        return data.decode("utf-8")

    def _index(self, node: yaml.Node, raw: tuple[Any, ...]) -> None:
        self.lines[raw] = node.start_mark.line + 1
        if isinstance(node, yaml.MappingNode):
            seen: set[Any] = set()
            for key_node, value_node in node.value:
                key = key_node.value
                if key in seen:
                    self.duplicates.append(((*raw, key), key_node.start_mark.line + 1))
                seen.add(key)
                self.lines[(*raw, key)] = key_node.start_mark.line + 1
                self._index(value_node, (*raw, key))
                self.lines[(*raw, key)] = key_node.start_mark.line + 1
        elif isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                self._index(item, (*raw, i))

    def line(self, raw: tuple[Any, ...]) -> int | None:
        """The line of a raw key path, or of its nearest ancestor that exists."""
        while raw:
            if raw in self.lines:
                return self.lines[raw]
            raw = raw[:-1]
        return self.lines.get(())

    def problem(self, issue: Issue) -> Problem:
        return Problem(self.name, issue.path, issue.message, self.line(issue.raw))

    def duplicate_problems(self) -> list[Problem]:
        return [
            Problem(self.name, _display(raw, self), "duplicate key; a key may appear once", line)
            for raw, line in self.duplicates
        ]


def _yaml_line(err: yaml.YAMLError) -> int | None:
    mark = getattr(err, "problem_mark", None)
    return mark.line + 1 if mark is not None else None


def _yaml_message(err: yaml.YAMLError) -> str:
    """One line for a YAML error: syntax errors say so; limits say what was exceeded."""
    reason = getattr(err, "problem", None) or str(err).splitlines()[0]
    if isinstance(err, (YamlLimitError, YamlValueError)):
        return f"YAML {reason}"
    context = getattr(err, "context", None)
    return f"YAML syntax error: {reason}" + (f" ({context})" if context else "")


def load(path: str | Path) -> Scenario:
    """Load and validate a scenario file; raise ScenarioError listing every problem."""
    scenario, problems = load_partial(path)
    if problems or scenario is None:
        raise ScenarioError(problems)
    return scenario


def load_partial(path: str | Path) -> tuple[Scenario | None, list[Problem]]:
    """Load as much as possible: the scenario (None if it cannot be built) and its problems.

    Optional keys with bad values are replaced by their defaults so that later checks
    (geometry, reachability) can still run and report everything in one go.
    """
    doc = YamlDoc(Path(path))
    if not isinstance(doc.data, dict):
        kind = "empty" if doc.data is None else f"a {type(doc.data).__name__}"
        return None, [Problem(doc.name, "", f"is {kind}; expected a mapping with keys {', '.join(SCENARIO.fields)}", 1)]
    ctx = Ctx()
    data = SCENARIO.check(doc.data, ctx, "", ())
    problems = doc.duplicate_problems() + [doc.problem(i) for i in ctx.issues]
    if data is MISSING or any(data.get(k) is MISSING for k in ("map", "rooms", "robots", "goals")):
        return None, problems
    ros, ros_problems = _ros_map(doc, data["map"])
    problems += ros_problems
    problems += cross_references(doc, data)
    if data["map"].get("ros") is not None and ros is None:
        return None, problems
    if ros is None and not _buildable(data["map"]):
        return None, problems  # no grid to build the world on; the schema said why
    return _build(doc, data, ros), problems


def _buildable(section: dict[str, Any]) -> bool:
    """Whether a polygonal map has bounds that make a grid of reasonable size."""
    b = section.get("bounds")
    if b is None or b[0] >= b[2] or b[1] >= b[3]:
        return False
    return polygonal_cells(b, section["resolution"]) <= MAP_CELLS.value()


def _ros_map(doc: YamlDoc, section: dict[str, Any]) -> tuple[RosMap | None, list[Problem]]:
    """Read the ROS map_server YAML named by map.ros (the image is read by the world stage)."""
    if section.get("ros") is None:
        return None, []
    map_path = (doc.path.parent / section["ros"]).resolve()
    if not map_path.is_file():
        return None, [
            Problem(
                doc.name,
                "map.ros",
                f"{section['ros']!r}: map file {_missing(map_path)} ({display_path(map_path)})",
                doc.line(("map", "ros")),
            )
        ]
    ros, problems = read_ros_map(map_path)
    return (replace(ros, despeckle=section["despeckle"]) if ros is not None else None), problems


def _missing(path: Path) -> str:
    """Why a file named by a scenario is not there to read: not found, or not a file."""
    return "is not a regular file" if path.exists() else "not found"


def read_ros_map(map_path: Path) -> tuple[RosMap | None, list[Problem]]:
    """Read and check a ROS map_server YAML file (the image is read by the world stage)."""
    try:
        map_doc = YamlDoc(map_path)
    except ScenarioError as err:
        return None, err.problems
    if not isinstance(map_doc.data, dict):
        return None, [Problem(map_doc.name, "", "is not a mapping; expected a ROS map_server YAML file", 1)]
    ctx = Ctx()
    meta = ROS_MAP.check(map_doc.data, ctx, "", ())
    problems = [map_doc.problem(i) for i in ctx.issues]
    if problems:
        return None, problems
    if abs(meta["origin"][2]) > 1e-9:
        return None, [
            Problem(
                map_doc.name,
                "origin",
                f"yaw {meta['origin'][2]:g} is not supported; expected 0 (an axis-aligned map)",
                map_doc.line(("origin",)),
            )
        ]
    if meta["free_thresh"] >= meta["occupied_thresh"]:
        return None, [
            Problem(
                map_doc.name,
                "free_thresh",
                f"{meta['free_thresh']:g} is not below occupied_thresh {meta['occupied_thresh']:g}; "
                "expected free_thresh < occupied_thresh",
                map_doc.line(("free_thresh",)),
            )
        ]
    return (
        RosMap(
            yaml_path=map_path,
            image_path=(map_path.parent / meta["image"]).resolve(),
            resolution=meta["resolution"],
            origin=meta["origin"],
            negate=bool(meta["negate"]),
            occupied_thresh=meta["occupied_thresh"],
            free_thresh=meta["free_thresh"],
            mode=meta["mode"],
        ),
        [],
    )


def _build(doc: YamlDoc, d: dict[str, Any], ros: RosMap | None) -> Scenario:
    m = d["map"]
    map_spec = ros or PolygonMap(
        bounds=m["bounds"],
        resolution=m["resolution"],
        wall_thickness=m["wall_thickness"],
        walls=m["walls"],
        obstacles=m["obstacles"],
    )
    default_thickness = m["wall_thickness"] if ros is None else 0.15
    models = d["models"]
    noise = models["motion_noise"]

    def sensor(s: dict[str, Any]) -> RangeBearingSensor:
        return RangeBearingSensor(s["range"], s["fov"], s["sigma_range"], s["sigma_bearing"])

    rooms = _rooms(d)
    stations = {r.name for r in rooms if r.place is not None}
    # a station left out (its name, place or pose reported) takes its job along: no later check
    # should read it as a room's job
    jobs = [j for j in d["goals"]["jobs"] if j.get("place") is None or j["name"] in stations]
    return Scenario(
        name=d["name"] or doc.path.stem,
        source=doc.path.resolve(),
        description=d["description"],
        map=map_spec,
        rooms=rooms,
        doors=tuple(
            Door(x["name"], x["segment"], x["state"] == "open", x["thickness"] or default_thickness) for x in d["doors"]
        ),
        landmarks=tuple(Landmark(x["name"], x["position"], x["kind"]) for x in d["landmarks"]),
        robots=tuple(
            RobotSpec(r["name"], Pose(*r["pose"]), r["covariance"], r["radius"], r["speed"], r["turn_rate"])
            for r in d["robots"]
        ),
        models=Models(
            dt=models["dt"],
            motion_noise=(noise["alpha1"], noise["alpha2"], noise["alpha3"], noise["alpha4"]),
            landmark_sensor=sensor(models["landmark_sensor"]),
            mutual_sensor=sensor(models["mutual_sensor"]),
            mutual_observations=models["mutual_observations"],
            observations=ObservationMode(models["observations"]),
            seed=models["seed"],
            range_sensor=_range_sensor(models["range_sensor"]),
            controller=models["controller"],
        ),
        cost=CostWeights(d["cost"]["M_u"], d["cost"]["M_G"], d["cost"]["M_Sigma"], d["cost"]["M_T"]),
        roadmap=RoadmapParams(
            **d["roadmap"],
            poses=tuple((j["name"], *j["pose"][:2]) for j in jobs if j["pose"] is not None),
        ),
        goals=Goals(
            visit=tuple(d["goals"]["visit"]),
            per_robot=tuple((k, tuple(v)) for k, v in d["goals"]["robots"].items()),
            jobs=tuple(
                Job(
                    j["name"],
                    j["service"],
                    tuple(j["robots"]),
                    None if j["pose"] is None else tuple(j["pose"]),
                    None if j["window"] is None else tuple(j["window"]),
                    j["penalty"],
                )
                for j in jobs
            ),
            ends=tuple(d["goals"]["ends"].items()),
        ),
        planner=_planner(d["planner"], d["models"]["range_sensor"] is not None, _objective(d), len(d["robots"])),
        key_lines={_display(raw, doc): line for raw, line in doc.lines.items()},
    )


def _rooms(d: dict[str, Any]) -> tuple[Room, ...]:
    """The map's rooms and places, then the stations (goals.jobs with a place and a pose), each
    with its place's polygon; a station whose place or pose is wrong (reported) is left out."""
    polygons = {r["name"]: r["polygon"] for r in d["rooms"]}
    rooms = tuple(Room(r["name"], r["polygon"]) for r in d["rooms"])
    stations = stations_of(d["goals"])
    poses = {j["name"]: j["pose"] for j in d["goals"]["jobs"]}
    return rooms + tuple(
        Room(name, polygons[place], place)
        for name, place in stations.items()
        if place in polygons and poses[name] is not None and name not in polygons
    )


def _objective(d: dict[str, Any]) -> Objective:
    """The scenario's objective: its own, else the default for its team and goals."""
    named: Objective | None = d["planner"]["objective"]
    if named is not None:
        return named
    goals = d["goals"]
    shift = bool(goals["ends"]) or any(j["service"] for j in goals["jobs"])
    return default_objective(len(d["robots"]), shift)


def _planner(p: dict[str, Any], range_sensor: bool, objective: Objective, robots: int) -> PlannerOptions:
    """The planner's options; a team with a range sensor plans within DEFAULT_MAX_RISK unless the
    scenario names its own threshold, and a fleet keeps its default minimum of rooms per robot
    unless it names its own."""
    if p["min_rooms"] is None:
        least = default_min_rooms(robots)
        p = {**p, "min_rooms": least, "min_rooms_from": FLEET_DEFAULT if least else ""}
    else:
        p = {**p, "min_rooms_from": "planner.min_rooms" if p["min_rooms"] else ""}
    p = {**p, "objective": objective}
    if p["max_risk"] is not None:
        return PlannerOptions(**p, max_risk_from="planner.max_risk")
    if range_sensor:
        return PlannerOptions(**{**p, "max_risk": DEFAULT_MAX_RISK}, max_risk_from=DEFAULT_RISK_SOURCE)
    return PlannerOptions(**p)


def _range_sensor(s: dict[str, Any] | None) -> RangeSensor | None:
    if s is None:
        return None
    m = s["localiser"]
    localiser = ScanModel(
        ScanModelKind(m["model"]),
        m["sigma_hit"],
        m["z_hit"],
        m["z_rand"],
        m["max_beams"],
        m["update_min_d"],
        m["update_min_a"],
        m["information"],
        m["lidar_only"],
        m["walls"],
        m["local_std"],
        m["local_time"],
        m["failure_rate"],
        _nav2_alphas(m["prediction_noise"]),
        m["heading_blur"],
        m["floor_beams"],
    )
    return RangeSensor(
        s["range"],
        s["fov"],
        s["beams"],
        s["sigma_range"],
        s["min_range"],
        s["max_incidence"],
        s["divergence"],
        localiser,
    )


def _nav2_alphas(section: dict[str, Any] | None) -> tuple[float, float, float, float] | None:
    if section is None:
        return NAV2_AMCL.prediction_noise
    return (section["alpha1"], section["alpha2"], section["alpha3"], section["alpha4"])


def _display(raw: tuple[Any, ...], doc: YamlDoc) -> str:
    """Turn a raw key path into the display path used in messages (list items by name)."""
    out, node = "", doc.data
    for key in raw:
        if isinstance(key, int) and isinstance(node, list) and key < len(node):
            item = node[key]
            name = item.get("name") if isinstance(item, dict) else None
            out = f"{out}.{key_text(name)}" if isinstance(name, str) else f"{out}[{key}]"
            node = item
        else:
            out = f"{out}.{key_text(key)}" if out else key_text(key)
            node = node.get(key) if isinstance(node, dict) else None
    return out.lstrip(".")
