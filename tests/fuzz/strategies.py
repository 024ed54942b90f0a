"""Hypothesis strategies for hostile inputs: whole scenarios, ROS maps and YAML texts.

Each strategy draws a valid starting point (the base scenario of tests/scenario/helpers.py,
on a polygonal or a ROS map) and mutates it the way people and attackers do: values
replaced by extremes, wrong types, units and nested junk; keys deleted or misspelled;
the YAML text truncated, spliced with anchors, aliases and tags, or replaced by an alias
bomb, deep nesting or binary junk; map images of every bit depth, mode and size.
"""

from __future__ import annotations

import copy
import io
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import yaml
from hypothesis import strategies as st
from PIL import Image

from tests.scenario.helpers import BASE, ros_map_yaml
from tmpnav.scenario.format import ROS_MAP, SCENARIO
from tmpnav.scenario.schema import reference_rows


@dataclass
class Case:
    """Files to write (name -> bytes) before running tmpnav on ``scenario.yaml``."""

    files: dict[str, bytes] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)  # what was done, for the failure report


EXTREMES: list[Any] = [
    0, -0.0, -1, 1e-320, 1e-300, 1e-12, 1e-6, 1e6, 1e15, 1e100, 1e160, 1e300, 1e308, -1e308,
    2**31, 2**63, 2**64, 10**400, float("inf"), float("-inf"), float("nan"),
]  # fmt: skip
STRINGS = [
    "", " ", "1e-3", "5e-2", "-1e-6", "1e999", "90 deg", "400 deg", "40 cm", "3 kg", "-1 m/s", "1e300 m", "nan m",
    ".inf", "0x1F", "010", "yes", "no", "null", "~", "A", "hall", "r1", "r1-start", "é\u202e", "x" * 300,
    "{}", "[]", "*a", "&a", "!!binary aGVsbG8=", "../../../../etc/passwd", "/dev/zero",
]  # fmt: skip

scalars = st.one_of(
    st.sampled_from(EXTREMES),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.sampled_from(STRINGS),
    st.text(max_size=12),
    st.booleans(),
    st.none(),
)
nasty = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=12,
)
#: values of the right shape but extreme size: matrices, points, polygons
shaped = st.one_of(
    st.lists(st.lists(st.sampled_from(EXTREMES[:18]), min_size=3, max_size=3), min_size=3, max_size=3),
    st.lists(st.sampled_from(EXTREMES), min_size=2, max_size=4),
    st.lists(st.lists(st.floats(-1e9, 1e9), min_size=2, max_size=2), min_size=0, max_size=8),
)
values = st.one_of(nasty, shaped, st.floats(min_value=1e-9, max_value=1e9).map(lambda x: f"{x:g} cm"))


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every key path of a document, leaves and collections alike."""
    out = [prefix] if prefix else []
    if isinstance(node, dict):
        for key, value in node.items():
            out += _paths(value, (*prefix, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            out += _paths(value, (*prefix, i))
    return out


def _schema_paths(spec: Any) -> list[tuple[Any, ...]]:
    """Key paths the schema documents (``robots[].speed`` -> ("robots", 0, "speed"))."""
    out = []
    for key, *_ in reference_rows(spec):
        path: list[Any] = []
        for part in key.split("."):
            name, brackets, _ = part.partition("[]")
            path.append(name)
            if brackets:
                path.append(0)
        out.append(tuple(path))
    return out


SCENARIO_KEYS = _schema_paths(SCENARIO)
ROS_KEYS = _schema_paths(ROS_MAP)


def _set(doc: Any, path: tuple[Any, ...], value: Any) -> None:
    node = doc
    for key in path[:-1]:
        if isinstance(node, dict):
            node = node.setdefault(key, {}) if not isinstance(node.get(key), (dict, list)) else node[key]
        elif isinstance(node, list) and isinstance(key, int) and key < len(node):
            node = node[key]
        else:
            return
    last = path[-1]
    if isinstance(node, dict) or (isinstance(node, list) and isinstance(last, int) and last < len(node)):
        node[last] = value


def _delete(doc: Any, path: tuple[Any, ...]) -> None:
    node = doc
    for key in path[:-1]:
        try:
            node = node[key]
        except (KeyError, IndexError, TypeError):
            return
    if isinstance(node, dict):
        node.pop(path[-1], None)
    elif isinstance(node, list) and isinstance(path[-1], int) and path[-1] < len(node):
        del node[path[-1]]


@st.composite
def mutated_doc(draw: st.DrawFn, base: dict[str, Any], schema_keys: list[tuple[Any, ...]]) -> tuple[Any, list[str]]:
    """``base`` with one to four mutations."""
    doc = copy.deepcopy(base)
    notes = []
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["replace", "schema", "schema", "delete", "unknown", "duplicate"]))
        paths = _paths(doc)
        if op == "replace" and paths:
            path, value = draw(st.sampled_from(paths)), draw(values)
            _set(doc, path, value)
        elif op == "schema":
            path, value = draw(st.sampled_from(schema_keys)), draw(values)
            _set(doc, path, value)
        elif op == "delete" and paths:
            path, value = draw(st.sampled_from(paths)), None
            _delete(doc, path)
        elif op == "unknown":
            path, value = (draw(st.text(min_size=1, max_size=8)),), draw(scalars)
            _set(doc, path, value)
        elif op == "duplicate" and isinstance(doc, dict):
            lists = [k for k, v in doc.items() if isinstance(v, list) and v]
            if not lists:
                continue
            key = draw(st.sampled_from(lists))
            doc[key].append(copy.deepcopy(draw(st.sampled_from(doc[key]))))
            path, value = (key,), "(an item again)"
        else:
            continue
        notes.append(f"{op} {'.'.join(map(str, path))} = {value!r:.80}")
    return doc, notes


def dump(doc: Any) -> str:
    return yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, allow_unicode=True)


TOKENS = [
    "&a ", "*a", "*b", "<<: *a\n", "!!str ", "!!float ", "!!int ", "!!bool ", "!!timestamp ", "!!binary ",
    "!!set ", "!!omap ", "!!null ", "!!python/object:os.system ", "[", "]", "{", "}",
    ": ", "- ", "\t", "---\n", "...\n", "%YAML 1.1\n", "? ", "|\n", "'", '"', "#", "\x00", "\ufeff", "1e-3",
]  # fmt: skip


@st.composite
def mutated_text(draw: st.DrawFn, text: str) -> tuple[bytes, list[str]]:
    """The YAML text with zero to three splices, deletions or a truncation."""
    notes = []
    for _ in range(draw(st.integers(0, 3))):
        op = draw(st.sampled_from(["insert", "truncate", "drop-line", "repeat-line"]))
        lines = text.splitlines(keepends=True)
        if op == "insert":
            at, token = draw(st.integers(0, len(text))), draw(st.sampled_from(TOKENS))
            text = text[:at] + token + text[at:]
            notes.append(f"insert {token!r} at {at}")
        elif op == "truncate":
            at = draw(st.integers(0, len(text)))
            text = text[:at]
            notes.append(f"truncate at {at}")
        elif lines:
            i = draw(st.integers(0, len(lines) - 1))
            lines[i : i + 1] = [] if op == "drop-line" else [lines[i], lines[i]]
            text = "".join(lines)
            notes.append(f"{op} {i}")
    return text.encode("utf-8", errors="surrogatepass"), notes


@st.composite
def whole_file_attacks(draw: st.DrawFn) -> tuple[bytes, list[str]]:
    """Files that attack the reader itself rather than the schema."""
    kind = draw(st.sampled_from(["bomb", "deep", "recursive", "binary", "wide", "long-line", "not-utf8"]))
    if kind == "bomb":
        levels, width = draw(st.integers(2, 40)), draw(st.integers(2, 12))
        lines = [f"a0: &a0 [{', '.join(['x'] * width)}]"]
        lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * width)}]" for i in range(1, levels)]
        body = "\n".join(lines) + f"\nname: *a{levels - 1}\n"
    elif kind == "deep":
        depth = draw(st.integers(1, 200_000))
        body = "name: " + draw(st.sampled_from(["[", "{a: "])) * depth + "\n"
    elif kind == "recursive":
        body = "map: &m {bounds: *m}\n"
    elif kind == "binary":
        return draw(st.binary(max_size=2000)), [kind]
    elif kind == "wide":
        body = "rooms: [" + ", ".join(["0"] * draw(st.integers(1, 700_000))) + "]\n"
    elif kind == "long-line":
        body = "description: " + "x" * draw(st.integers(1, 2_000_000)) + "\n"
    else:
        return b"name: caf\xe9\n", [kind]
    return body.encode(), [f"{kind} ({len(body):,} bytes)"]


@st.composite
def scenarios(draw: st.DrawFn) -> Case:
    """A whole scenario file: mutated data, mutated text, or an attack on the reader."""
    kind = draw(st.sampled_from(["data", "data", "data", "text", "attack"]))
    if kind == "attack":
        data, notes = draw(whole_file_attacks())
        return Case({"scenario.yaml": data}, notes)
    doc, notes = draw(mutated_doc(BASE, SCENARIO_KEYS))
    text = dump(doc)
    if kind == "text":
        data, more = draw(mutated_text(text))
        return Case({"scenario.yaml": data}, notes + more)
    return Case({"scenario.yaml": text.encode()}, notes)


# ------------------------------------------------------------------- ROS maps


def _base_pixels() -> np.ndarray:
    """The base scenario's map as map_saver would draw it (0 occupied, 254 free)."""
    from tmpnav.types import PolygonMap
    from tmpnav.world.build import rasterize

    m = BASE["map"]
    grid = rasterize(PolygonMap(tuple(m["bounds"]), m["resolution"], 0.15, m["walls"], m["obstacles"]))
    return np.where(grid.occupied[::-1], 0, 254).astype(np.uint8)


BASE_PIXELS = _base_pixels()


def _encode(pixels: np.ndarray, kind: str) -> bytes:
    """Grey levels 0..255 (rows, cols) as an image file of the given kind."""
    rows, cols = pixels.shape
    if kind.startswith("pgm"):
        maxval = int(kind[3:])
        scaled = np.round(pixels.astype(float) * maxval / 255)
        data = scaled.astype(">u2" if maxval > 255 else np.uint8).tobytes()
        return f"P5\n{cols} {rows}\n{maxval}\n".encode() + data
    fmt, mode = kind.split("-")
    if mode == "L":
        image = Image.fromarray(pixels)
    elif mode == "LA":
        image = Image.fromarray(np.stack([pixels, np.where(pixels > 200, 255, 0).astype(np.uint8)], -1), mode="LA")
    elif mode in ("RGB", "RGBA"):
        image = Image.fromarray(np.stack([pixels] * len(mode), -1), mode=mode)
    elif mode == "P":
        image = Image.fromarray(pixels).convert("P")
    elif mode == "I16":
        image = Image.fromarray(pixels.astype(np.uint16) * 257)
    elif mode == "F":
        image = Image.fromarray(pixels.astype(np.float32))
    else:  # I: 32-bit integers
        image = Image.fromarray(pixels.astype(np.int32))
    out = io.BytesIO()
    image.save(out, format=fmt.upper())
    return out.getvalue()


IMAGE_KINDS = ["pgm255", "pgm65535", "pgm1023", "pgm100", "png-L", "png-LA", "png-RGB", "png-RGBA", "png-P",
               "png-I16", "tiff-F", "tiff-I"]  # fmt: skip


@st.composite
def map_image(draw: st.DrawFn) -> tuple[bytes, str]:
    kind = draw(st.sampled_from([*IMAGE_KINDS, "garbage", "truncated", "huge-header"]))
    if kind == "garbage":
        return draw(st.binary(max_size=500)), kind
    if kind == "huge-header":
        side = draw(st.integers(8000, 10**6))
        return f"P5\n{side} {side + draw(st.integers(0, 10))}\n255\n".encode(), f"{kind} {side}"
    if draw(st.booleans()):
        pixels = BASE_PIXELS.copy()
        r, c, h, w = (draw(st.integers(0, n)) for n in (59, 99, 60, 100))
        pixels[r : r + h, c : c + w] = draw(st.sampled_from([0, 128, 205, 254, 255]))
    else:
        rows, cols = draw(st.integers(1, 120)), draw(st.integers(1, 120))
        seed = draw(st.integers(0, 2**32 - 1))
        pixels = np.random.default_rng(seed).choice(np.array([0, 205, 254], dtype=np.uint8), size=(rows, cols))
    data = _encode(pixels, kind if kind != "truncated" else "pgm255")
    if kind == "truncated":
        data = data[: draw(st.integers(0, len(data) - 1))]
    return data, kind


@st.composite
def ros_scenarios(draw: st.DrawFn) -> Case:
    """The base scenario on a ROS map: its map.yaml and its image both fuzzed."""
    image, kind = draw(map_image())
    meta = ros_map_yaml("map.img", resolution=0.1)
    meta["mode"] = draw(st.sampled_from(["trinary", "scale", "raw"]))
    meta["negate"] = draw(st.sampled_from([0, 1]))
    notes = [f"image {kind}", f"mode {meta['mode']}, negate {meta['negate']}"]
    if draw(st.booleans()):
        meta, more = draw(mutated_doc(meta, ROS_KEYS))
        notes += more
    doc = copy.deepcopy(BASE)
    doc["map"] = {"ros": "map.yaml"}
    if draw(st.booleans()):
        doc, more = draw(mutated_doc(doc, SCENARIO_KEYS))
        notes += more
    return Case({"scenario.yaml": dump(doc).encode(), "map.yaml": dump(meta).encode(), "map.img": image}, notes)


# ------------------------------------------------------------------- plans

#: model values near and at the ends of their accepted ranges: what `plan` must survive
STRESS: dict[tuple[Any, ...], st.SearchStrategy[Any]] = {
    ("models", "dt"): st.sampled_from([0.01, 0.05, 1.0, 5.0, 10.0]),
    ("robots", 0, "speed"): st.sampled_from([0.01, 0.1, 2.0, 10.0, 23.0]),
    ("robots", 1, "turn_rate"): st.sampled_from([0.01, 0.1, 10.0, 1e6]),
    ("robots", 0, "covariance"): st.sampled_from([1e-12, 1e-6, 1.0, 100.0, 136.0]).flatmap(
        lambda v: st.sampled_from([1e-12, 0.1, 9.8]).map(lambda t: [[v, 0, 0], [0, v, 0], [0, 0, t]])
    ),
    ("models", "motion_noise", "alpha1"): st.sampled_from([0.0, 1e-9, 1.0]),
    ("models", "motion_noise", "alpha4"): st.sampled_from([0.0, 1e-9, 1.0]),
    ("models", "landmark_sensor", "range"): st.sampled_from([0.01, 1.0, 11.0]),
    ("models", "landmark_sensor", "sigma_range"): st.sampled_from([1e-6, 1e-5, 0.005]),
    ("models", "landmark_sensor", "sigma_bearing"): st.sampled_from([1e-6, 1e-3, 3.14]),
    ("models", "mutual_sensor", "fov"): st.sampled_from([1e-6, 1.0, 6.28]),
    ("models", "mutual_sensor", "sigma_range"): st.sampled_from([1e-6, 3.9]),
    ("models", "mutual_sensor", "sigma_bearing"): st.sampled_from([1e-6, 3.14]),
    ("robots", 1, "covariance"): st.just([[1e-300, 0, 0], [0, 1e-300, 0], [0, 0, 1e-300]]),
    ("models", "motion_noise"): st.just({"alpha1": 0, "alpha2": 0, "alpha3": 0, "alpha4": 0}),
    ("models", "observations"): st.sampled_from(["noisy", "max-likelihood"]),
    ("cost", "M_u"): st.sampled_from([0.0, 1e-6, 1e6]),
    ("cost", "M_Sigma"): st.sampled_from([0.0, 1e-6, 1e6]),
    ("planner", "encoding"): st.sampled_from(["paper", "single", "mixed"]),
    ("planner", "pair_min_gain"): st.sampled_from([0.0, 1.0]),
    ("roadmap", "instantiations"): st.sampled_from([1, 3]),
}


@st.composite
def plan_scenarios(draw: st.DrawFn) -> Case:
    """A small solvable scenario with one to four model values pushed to their extremes."""
    doc = copy.deepcopy(BASE)
    # 500 milestones: with 150 a seed can leave a door uncrossed, which is now refused as bad
    # input (tests/fuzz/RESULTS.md); the property is about the models' values, so it plans
    doc["roadmap"] = {"samples": 500, "instantiations": 2, "seed": draw(st.integers(0, 2**32 - 1))}
    keys = draw(st.lists(st.sampled_from(sorted(STRESS, key=str)), min_size=1, max_size=4, unique=True))
    notes = []
    for key in keys:
        value = draw(STRESS[key])
        _set(doc, key, value)
        notes.append(f"{'.'.join(map(str, key))} = {value!r}")
    return Case({"scenario.yaml": dump(doc).encode()}, notes)
