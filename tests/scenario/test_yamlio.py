"""YAML reading: the YAML 1.2 core schema, and the bounds checked before anything is built."""

from __future__ import annotations

import math
import time

import pytest
import yaml

from tmpnav.scenario.yamlio import YamlLimitError, check_expansion, read_yaml


@pytest.mark.parametrize(
    ("scalar", "value"),
    [
        ("1e-3", 0.001),  # YAML 1.1: the string '1e-3'
        ("5E+2", 500.0),
        ("1.", 1.0),
        (".5", 0.5),
        ("-2.5e-1", -0.25),
        ("010", 10),  # YAML 1.1: octal 8
        ("0o17", 15),
        ("0x1F", 31),
        ("+12", 12),
        ("true", True),
        ("False", False),
        ("~", None),
        ("null", None),
        ("yes", "yes"),  # YAML 1.1: True
        ("no", "no"),  # YAML 1.1: False (the Norway problem)
        ("on", "on"),
        ("1:30", "1:30"),  # YAML 1.1: sexagesimal 90
        ("1_000", "1_000"),  # YAML 1.1: 1000
        ("2024-01-01", "2024-01-01"),  # YAML 1.1: a date
        ("=", "="),
    ],
)
def test_plain_scalars_follow_the_yaml_1_2_core_schema(scalar: str, value: object) -> None:
    data, _ = read_yaml(f"x: {scalar}\n")
    assert data["x"] == value
    assert type(data["x"]) is type(value)


def test_special_floats_and_huge_integers() -> None:
    data, _ = read_yaml("a: .inf\nb: -.Inf\nc: .NaN\nd: 1e999\ne: " + "9" * 5000 + "\n")
    assert (data["a"], data["b"], data["d"], data["e"]) == (math.inf, -math.inf, math.inf, math.inf)
    assert math.isnan(data["c"])


def test_merge_keys_still_work_and_the_node_tree_keeps_the_file_shape() -> None:
    data, node = read_yaml("base: &b {x: 1, y: 2}\nc:\n  <<: *b\n  y: 3\n")
    assert data["c"] == {"x": 1, "y": 3}
    c = next(v for k, v in node.value if k.value == "c")
    assert [k.value for k, _ in c.value] == ["<<", "y"]  # not flattened: no false duplicate 'y'


def test_empty_documents_are_none() -> None:
    assert read_yaml("") == (None, None)
    assert read_yaml("# only a comment\n") == (None, None)


def bomb(levels: int, width: int = 9) -> str:
    lines = [f"a0: &a0 [{', '.join(['x'] * width)}]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * width)}]" for i in range(1, levels)]
    return "\n".join(lines) + "\n"


def test_the_expansion_is_counted_exactly() -> None:
    # a mapping (1) with three keys (3) and values: [x, y] (3), [*a, *a] (1 + 2 x 3), *b (7)
    text = "p: &a [x, y]\nq: &b [*a, *a]\nr: *b\n"
    check_expansion(text)  # 21 values: far below the cap
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("TMPNAV_MAX_YAML_NODES", "20")
        with pytest.raises(YamlLimitError, match=r"^expands to at least 21 values"):
            check_expansion(text)
        mp.setenv("TMPNAV_MAX_YAML_NODES", "21")
        check_expansion(text)


@pytest.mark.parametrize("levels", [9, 30, 300])
def test_an_alias_bomb_is_refused_in_time_proportional_to_the_file(levels: int) -> None:
    start = time.monotonic()
    with pytest.raises(YamlLimitError) as info:
        read_yaml(bomb(levels))
    assert time.monotonic() - start < 5
    assert info.value.problem_mark.line == 5  # 0-based: a5, whose 9^6 values pass the cap


def test_counting_stops_at_the_cap() -> None:
    """The refusal comes at the first value past the cap, however large the rest."""
    with pytest.raises(YamlLimitError) as info:
        read_yaml(bomb(300))
    assert "expands to at least 5" in str(info.value)  # a5 passes 500,000 with its first aliases


@pytest.mark.parametrize("loader", ["C", "Python"])
def test_a_large_plain_file_under_the_cap_is_read(loader: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A file just under the cap of values is read whole, by libyaml and by the pure-Python
    reader (under a cap lowered for the test: the pure-Python reader is some twenty times
    slower). How long each takes is measured in benchmarks/bench_yaml.py, not here."""
    from tmpnav.scenario import yamlio

    monkeypatch.setenv("TMPNAV_MAX_YAML_NODES", "10000")
    if loader == "Python":
        monkeypatch.setattr(yamlio, "Yaml12CLoader", None)
    walls = 3_300  # 9,903 values
    text = "walls: [" + ", ".join(["[0, 1]"] * walls) + "]\n"
    data, _ = read_yaml(text)
    assert len(data["walls"]) == walls
    with pytest.raises(YamlLimitError):
        read_yaml("walls: [" + ", ".join(["[0, 1]"] * (walls + 100)) + "]\n")  # 10,203 values: past it


def test_errors_are_explained_by_the_pure_python_reader() -> None:
    with pytest.raises(yaml.YAMLError) as info:
        read_yaml("a: [1, 2\nb: 3\n")
    assert info.value.problem == "expected ',' or ']', but got ':'"  # libyaml: "did not find expected ',' or ']'"


@pytest.mark.parametrize("depth", [33, 1000, 100_000])
def test_deep_nesting_is_refused_without_recursion(depth: int) -> None:
    block = "x:\n" + "".join(" " * i + "-\n" for i in range(min(depth, 1000)))  # indentation grows
    for text in ("x: " + "[" * depth + "]" * depth, block):
        with pytest.raises(YamlLimitError, match="nested deeper than 32 levels"):
            read_yaml(text)


def test_32_levels_are_fine() -> None:
    data, _ = read_yaml("[" * 32 + "]" * 32)
    for _ in range(31):
        data = data[0]
    assert data == []


@pytest.mark.parametrize("text", ["a: &x [1, *x]\n", "a: &x {b: *x}\n"])
def test_a_recursive_alias_is_refused(text: str) -> None:
    with pytest.raises(YamlLimitError, match=r"alias \*x refers to a collection that contains it"):
        read_yaml(text)


@pytest.mark.parametrize(
    "text",
    ["a: *nothing\n", "a: [1\n", "a: !!python/object:os.system ls\n", "? [1, 2]\n: 3\n", "a: 1\n---\nb: 2\n"],
    ids=["undefined-alias", "syntax", "python-tag", "unhashable-key", "two-documents"],
)
def test_other_yaml_errors_stay_yaml_errors(text: str) -> None:
    with pytest.raises(yaml.YAMLError):
        read_yaml(text)


@pytest.mark.parametrize("tagged", ["!!int abc", "!!int 0x", "!!float 1e", "!!timestamp noon", "!!bool maybe"])
def test_an_unreadable_tagged_value_is_a_yaml_error(tagged: str) -> None:
    from tmpnav.scenario.yamlio import YamlValueError

    with pytest.raises(YamlValueError, match=r"tagged !!\w+ is not a valid"):
        read_yaml(f"a: [{tagged}]\n")
