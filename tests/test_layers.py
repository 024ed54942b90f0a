"""Imports follow the stages: no module of tmpnav imports a later stage, and no modules import
each other in a circle (docs/architecture.md draws the layers).

Every import counts, at the top of a module, inside a function (imported on first use) or
under ``TYPE_CHECKING`` (an annotation is a dependency too). A module's layer is that of the
longest entry of :data:`LAYERS` that names it or a package above it; a module may import its
own layer and the layers below. A new module of a new package needs a line here.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "tmpnav"

#: the layers, from the bottom: values every stage shares, the pipeline's stages in the order
#: they run, what uses a plan, the entry points
LAYERS: dict[str, int] = {
    # values and services below every stage
    "tmpnav.version": 0,
    "tmpnav.types": 0,
    "tmpnav.errors": 0,
    "tmpnav.choices": 0,
    "tmpnav.digest": 0,
    "tmpnav.atomic": 0,
    "tmpnav.lifetime": 0,
    "tmpnav.heap": 0,  # a run's long-lived objects out of Python's full collections
    "tmpnav.shipped": 0,
    "tmpnav.cachedir": 0,
    "tmpnav.java": 0,  # which Java runs ENHSP
    "tmpnav.numbers": 0,  # figures as the terminal prints them
    "tmpnav.deadline": 0,  # the run's time limit, one clock every stage looks at
    "tmpnav.beside": 0,  # work in a thread beside the main one, its result where asked for
    "tmpnav.client": 0,  # a client of tmpnav serve (the standard library only): for any layer that calls it
    "tmpnav.pddl": 0,  # the PDDL domains (data)
    "tmpnav.configs": 0,  # the shipped scenarios (data)
    # the pipeline's stages, in order
    "tmpnav.scenario": 1,
    "tmpnav.world": 2,
    "tmpnav.rooms": 3,  # a ROS map read into a scenario skeleton: scenario and world only
    "tmpnav.results": 4,  # the values runs return (stage times, task result, report)
    "tmpnav.roadmap": 5,
    "tmpnav.belief": 6,
    "tmpnav.belief.risk": 6,  # the collision bound: the belief and the map (world) only
    "tmpnav.belief.conflicts": 6,  # the independent checker: trajectories only, no plan or clock
    "tmpnav.oracle": 7,
    "tmpnav.task": 8,  # searches over tables and cost models: never the oracle
    "tmpnav.attachment": 9,  # the cost models on the oracle, for the task's searches
    "tmpnav.attachment.conflicts": 9,  # waits that keep robots out of each other's way, on the clock
    "tmpnav.attachment.passing": 9,  # detours and sidesteps past what the waits leave
    "tmpnav.planning": 10,  # stage 6 for a run: the registry of task planners
    "tmpnav.resimulate": 11,
    "tmpnav.options": 11,  # what a run is asked for, and the scenario that puts in force
    "tmpnav.pipeline": 12,
    # what uses a plan or a run
    "tmpnav.rooms_check": 13,
    "tmpnav.execution": 13,
    "tmpnav.export": 13,
    "tmpnav.bench.table": 13,  # bench.csv as data, which the report draws
    "tmpnav.report": 14,
    "tmpnav.replan": 14,  # a plan revised from the team's state: the pipeline on a plan.json document
    # entry points
    "tmpnav.bench": 15,
    "tmpnav.api": 15,
    "tmpnav.cli": 15,
    "tmpnav.serve": 15,  # `tmpnav serve`: the pipeline and replan behind HTTP
    "tmpnav": 16,  # the package itself: ``import tmpnav`` is the Python API (tmpnav.api, on first use)
    "tmpnav.__main__": 16,
}


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def layer(module: str) -> int:
    name = module
    while name not in LAYERS:
        assert "." in name, f"{module} is in no layer: add it to LAYERS"
        name = name.rsplit(".", 1)[0]
    return LAYERS[name]


def imports(module: str, path: Path, known: dict[str, Path]) -> Iterator[tuple[str, int]]:
    """The tmpnav modules ``module`` imports, anywhere in it, with the line."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join([*package.split(".")[: len(package.split(".")) - node.level + 1], base]).strip(".")
            names = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        for name in names:
            if name == "tmpnav" or name.startswith("tmpnav."):
                while name not in known and "." in name:
                    name = name.rsplit(".", 1)[0]
                yield name, node.lineno


def graph() -> dict[str, set[str]]:
    known = modules()
    return {m: {t for t, _ in imports(m, p, known) if t != m} for m, p in known.items()}


def test_every_module_is_in_a_layer() -> None:
    for module in modules():
        layer(module)


def test_no_module_imports_a_later_stage() -> None:
    known = modules()
    upward = [
        f"{path.relative_to(PACKAGE.parent)}:{line}: {module} (layer {layer(module)}) imports {target} "
        f"(layer {layer(target)})"
        for module, path in known.items()
        for target, line in imports(module, path, known)
        if layer(target) > layer(module)
    ]
    assert not upward, "imports that point up the stages:\n" + "\n".join(upward)


def test_no_modules_import_each_other_in_a_circle() -> None:
    edges = graph()
    circles = [c for c in _strongly_connected(edges) if len(c) > 1]
    assert not circles, "modules that import each other in a circle: " + "; ".join(" <-> ".join(c) for c in circles)


def test_the_check_sees_an_upward_import(tmp_path: Path) -> None:
    """The rule itself: scenario/ importing the task stage is caught."""
    known = {**modules(), "tmpnav.scenario.bad": tmp_path / "bad.py"}
    (tmp_path / "bad.py").write_text("from tmpnav.task.encodings import ENCODINGS\n")
    found = [(t, layer(t)) for t, _ in imports("tmpnav.scenario.bad", tmp_path / "bad.py", known)]
    assert found == [("tmpnav.task.encodings", LAYERS["tmpnav.task"])] and found[0][1] > layer("tmpnav.scenario.bad")


def _strongly_connected(edges: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components of the import graph."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            out.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


#: the task stage's packages: functions short enough to read in one screen
STAGE_6 = ("task", "attachment", "planning")
MAX_FUNCTION_LINES = 60


def test_no_function_of_stage_6_is_longer_than_a_screen() -> None:
    long = [
        f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {node.name} ({node.end_lineno - node.lineno + 1} lines)"
        for folder in STAGE_6
        for path in sorted((PACKAGE / folder).glob("*.py"))
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and node.end_lineno is not None
        and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES
    ]
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines:\n" + "\n".join(long)
