"""nav2's AMCL parameters: their defaults, and the ``amcl:`` section of a nav2 params file.

``AmclParams()`` is nav2's AMCL at its defaults; :func:`read_nav2_params` reads a robot's nav2
params YAML (``tmpnav simulate --localiser amcl --nav2-params FILE``). Which of these the
Python bindings apply is in docs/amcl.md.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tmpnav.errors import Problem, ScenarioError
from tmpnav.scenario.load import YamlDoc
from tmpnav.scenario.schema import as_float, key_text, show

#: nav2's names of its motion models (the second pair: nav2 before Galactic)
ROBOT_MODELS = ("nav2_amcl::DifferentialMotionModel", "nav2_amcl::OmniMotionModel", "differential", "omni")
LASER_MODELS = ("likelihood_field", "beam", "likelihood_field_prob")


@dataclass(frozen=True)
class AmclParams:
    """nav2 AMCL's parameters that shape its estimate, at nav2's defaults, checked against nav2's
    configuration guide (https://docs.nav2.org/configuration/packages/configuring-amcl.html) and
    its source (nav2_amcl/src/amcl_node.cpp, whose z_short default 0.05 the guide's table gives
    as 0.005; its example file says 0.05)."""

    alpha1: float = 0.2  # rotation noise from rotation
    alpha2: float = 0.2  # rotation noise from translation
    alpha3: float = 0.2  # translation noise from translation
    alpha4: float = 0.2  # translation noise from rotation
    alpha5: float = 0.2  # translation noise (omni model only)
    min_particles: int = 500
    max_particles: int = 2000
    recovery_alpha_slow: float = 0.0  # 0: no random particles added
    recovery_alpha_fast: float = 0.0
    laser_model_type: str = "likelihood_field"
    max_beams: int = 60  # beams of a scan weighed, evenly spaced
    sigma_hit: float = 0.2  # m
    z_hit: float = 0.5
    z_short: float = 0.05
    z_max: float = 0.05
    z_rand: float = 0.5
    lambda_short: float = 0.1  # 1/m
    laser_likelihood_max_dist: float = 2.0  # m
    laser_max_range: float = 100.0  # m; <= 0: the lidar's own
    laser_min_range: float = -1.0  # m; <= 0: the lidar's own
    update_min_d: float = 0.25  # m driven before a filter update
    update_min_a: float = 0.2  # rad turned before a filter update
    resample_interval: int = 1  # filter updates per resampling
    robot_model_type: str = "nav2_amcl::DifferentialMotionModel"
    pf_err: float = 0.05  # KLD sampling: population error
    pf_z: float = 0.99  # KLD sampling: its quantile


Check = tuple[type, Callable[[Any], bool], str]
_KINDS = {float: "a number", int: "an integer", str: "a string"}


def _number(ok: Callable[[float], bool], expected: str) -> Check:
    return float, lambda v: math.isfinite(v) and ok(v), expected


def _integer(least: int) -> Check:
    return int, lambda v: v >= least, f"an integer >= {least}"


def _choice(names: tuple[str, ...]) -> Check:
    return str, lambda v: v in names, "one of " + ", ".join(names)


_SHARE = _number(lambda v: 0.0 <= v <= 1.0, "a number in [0, 1]")
_NONNEG = _number(lambda v: v >= 0.0, "a number >= 0")
_POSITIVE = _number(lambda v: v > 0.0, "a number > 0")
_ANY = _number(lambda v: True, "a number (<= 0: the lidar's own)")

CHECKS: dict[str, Check] = {
    **{f"alpha{k}": _NONNEG for k in range(1, 6)},
    "min_particles": _integer(1),
    "max_particles": _integer(1),
    "recovery_alpha_slow": _SHARE,
    "recovery_alpha_fast": _SHARE,
    "laser_model_type": _choice(LASER_MODELS),
    "max_beams": _integer(2),  # nav2 weighs no beam below 2
    "sigma_hit": _POSITIVE,
    **{k: _SHARE for k in ("z_hit", "z_short", "z_max", "z_rand")},
    "lambda_short": _POSITIVE,
    "laser_likelihood_max_dist": _NONNEG,
    "laser_max_range": _ANY,
    "laser_min_range": _ANY,
    "update_min_d": _NONNEG,
    "update_min_a": _NONNEG,
    "resample_interval": _integer(1),
    "robot_model_type": _choice(ROBOT_MODELS),
    "pf_err": _POSITIVE,
    "pf_z": _POSITIVE,
}


def read_nav2_params(path: Path) -> AmclParams:
    """AMCL's parameters from a nav2 params YAML: its ``amcl: ros__parameters:`` section (or a
    file whose top level is ``ros__parameters:`` or the keys themselves); keys it does not set
    keep nav2's defaults, keys tmpnav does not use are ignored. A missing file, a file without
    AMCL's parameters or a bad value raises :class:`ScenarioError`, one line per problem."""
    doc = YamlDoc(Path(path))
    section, raw = _section(doc)
    problems = doc.duplicate_problems()
    values: dict[str, Any] = {}
    for key, value in section.items():
        if key not in CHECKS:
            continue
        kind, ok, expected = CHECKS[key]
        if isinstance(value, bool) or not isinstance(value, (int, float) if kind is float else kind):
            wrong = f"{show(value)} is not {_KINDS[kind]}"
        elif not ok(as_float(value) if isinstance(value, int | float) else value):
            wrong = f"{show(value)} is {'not a known value' if kind is str else 'out of range'}"
        else:
            values[key] = as_float(value) if kind is float and isinstance(value, int | float) else value
            continue
        default = getattr(AmclParams(), key)
        problems.append(doc_problem(doc, (*raw, key), f"{wrong}; expected {expected} (nav2's default {default})"))
    low, high = values.get("min_particles", 500), values.get("max_particles", 2000)
    if not problems and low > high:
        wrong = f"{low} is more than max_particles {high}; expected min_particles <= max_particles"
        problems.append(doc_problem(doc, (*raw, "min_particles"), wrong))
    if problems:
        raise ScenarioError(problems)
    return dataclasses.replace(AmclParams(), **values)


def doc_problem(doc: YamlDoc, raw: tuple[str, ...], message: str) -> Problem:
    """A problem at key path ``raw`` of the file, with its line."""
    return Problem(doc.name, ".".join(key_text(k) for k in raw), message, doc.line(raw))


def _section(doc: YamlDoc) -> tuple[dict[Any, Any], tuple[str, ...]]:
    """AMCL's parameters in the file and their key path: nav2's layout or one of the shorter ones."""
    data: Any = doc.data
    raw: tuple[str, ...] = ()
    for key in ("amcl", "ros__parameters"):
        if isinstance(data, dict) and isinstance(data.get(key), dict):
            data, raw = data[key], (*raw, key)
    if isinstance(data, dict) and (raw or CHECKS.keys() & data.keys()):
        return data, raw
    expected = "expected nav2's layout amcl: ros__parameters: {alpha1: 0.2, ...} or AMCL's keys at the top"
    if isinstance(data, dict):
        raise ScenarioError([Problem(doc.name, "", f"has no amcl: section nor any AMCL parameter; {expected}", 1)])
    raise ScenarioError([Problem(doc.name, "", f"is not a mapping; {expected}", 1)])
