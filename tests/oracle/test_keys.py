"""The oracle's code version covers every module that computes a cached result."""

import ast
from pathlib import Path

import tmpnav
from tmpnav.oracle.keys import CODE_FILES, NOT_RESULT_CODE, RESULT_ENTRY_POINTS

ROOT = Path(tmpnav.__file__).resolve().parent


def _module_file(module: str) -> str | None:
    parts = module.split(".")[1:]
    for candidate in (Path(*parts).with_suffix(".py"), Path(*parts) / "__init__.py"):
        if (ROOT / candidate).is_file():
            return candidate.as_posix()
    return None


def _dependencies(node: ast.ImportFrom) -> set[str]:
    """Module files behind ``from tmpnav.x import a, b``, looking through package re-exports."""
    assert node.module is not None
    dep = _module_file(node.module)
    if dep is None:
        return set()
    if not dep.endswith("__init__.py"):
        return {dep}
    out = set()
    package = node.module
    reexports = {}
    for inner in ast.walk(ast.parse((ROOT / dep).read_text())):
        if isinstance(inner, ast.ImportFrom) and inner.module and inner.module.startswith(package + "."):
            for alias in inner.names:
                reexports[alias.asname or alias.name] = _module_file(inner.module)
    for alias in node.names:
        submodule = _module_file(f"{package}.{alias.name}")
        target = submodule or reexports.get(alias.name)
        if target is not None:
            out.add(target)
    return out


def test_every_code_file_exists():
    for rel in CODE_FILES:
        assert (ROOT / rel).is_file(), rel


def _imports(rel: str) -> set[str]:
    deps = set()
    for node in ast.walk(ast.parse((ROOT / rel).read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("tmpnav."):
            deps |= _dependencies(node)
    return deps


def test_modules_that_result_code_imports_are_in_the_code_version():
    """Editing a module the EKF or the cost depend on must change every cache key."""
    missing = set()
    for rel in CODE_FILES:
        for node in ast.walk(ast.parse((ROOT / rel).read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("tmpnav."):
                for dep in _dependencies(node):
                    if dep not in CODE_FILES and dep not in NOT_RESULT_CODE:
                        missing.add((rel, dep))
    assert not missing, f"imported by result code but not in CODE_FILES: {sorted(missing)}"


def test_the_code_version_is_exactly_the_code_results_depend_on():
    """Nothing else is hashed: the belief stage's reference and test-only code (filterpy's EKF,
    the model equations it is built from) can change without invalidating every cache."""
    reached, todo = set(), list(RESULT_ENTRY_POINTS)
    while todo:
        rel = todo.pop()
        if rel in reached or rel in NOT_RESULT_CODE:
            continue
        reached.add(rel)
        todo.extend(_imports(rel))
    # the occupancy grid's code decides landmark visibility through the World's grid object
    # (world.grid.is_occupied), not through an import of the modules above
    assert reached | {"world/grid.py"} == set(CODE_FILES)
    for reference in ("belief/ekf.py", "belief/models.py", "belief/reference.py", "belief/rollout.py"):
        assert reference not in CODE_FILES
