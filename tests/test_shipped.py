"""The shipped scenarios: package data an installed tmpnav finds, named configs/NAME.yaml anywhere."""

from __future__ import annotations

import fnmatch
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tmpnav import shipped

ROOT = Path(__file__).resolve().parent.parent


def tmpnav(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "tmpnav", *args], capture_output=True, text=True, cwd=cwd, timeout=300)


def test_every_file_of_configs_is_package_data() -> None:
    """A wheel holds configs/ only through pyproject's package-data patterns: each file must match one."""
    patterns = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    wanted = patterns["tmpnav.configs"]
    files = [p.relative_to(ROOT / "configs").as_posix() for p in (ROOT / "configs").rglob("*") if p.is_file()]
    data = [f for f in files if not f.endswith(".py") and "__pycache__" not in f]
    assert data and all(any(fnmatch.fnmatch(f, pat) for pat in wanted) for f in data), data
    assert sorted(p.as_posix() for p in shipped.data_files()) == sorted(data)


def test_configs_names_a_shipped_scenario_only_when_no_such_file_is_here(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert shipped.resolve(Path("configs/corridor.yaml")) == shipped.configs_dir() / "corridor.yaml"
    assert shipped.resolve(Path("configs/nope.yaml")) == Path("configs/nope.yaml")
    assert shipped.resolve(Path("corridor.yaml")) == Path("corridor.yaml")  # only under configs/
    (tmp_path / "configs").mkdir()
    (tmp_path / "configs" / "corridor.yaml").write_text("name: mine\n")
    assert shipped.resolve(Path("configs/corridor.yaml")) == Path("configs/corridor.yaml")  # the user's own file


def test_copy_keeps_files_already_there(tmp_path: Path) -> None:
    (tmp_path / "corridor.yaml").write_text("name: edited\n")
    written, kept = shipped.copy_to(tmp_path)
    assert kept == [tmp_path / "corridor.yaml"] and (tmp_path / "corridor.yaml").read_text() == "name: edited\n"
    assert (tmp_path / "office" / "office.pgm") in written
    assert sorted(p.relative_to(tmp_path) for p in [*written, *kept]) == sorted(shipped.data_files())


def test_commands_find_shipped_scenarios_outside_the_checkout(tmp_path: Path) -> None:
    listing = tmpnav("configs", cwd=tmp_path)
    assert listing.returncode == 0 and "configs/corridor.yaml" in listing.stdout
    ok = tmpnav("validate", "configs/office-ros.yaml", cwd=tmp_path)  # its ROS map is shipped too
    assert ok.returncode == 0 and ": ok: 7 rooms" in ok.stdout, ok.stderr
    missing = tmpnav("validate", "configs/nope.yaml", cwd=tmp_path)
    assert missing.returncode == 2 and "'tmpnav configs' lists them" in missing.stderr
    copied = tmpnav("configs", "-o", "configs", cwd=tmp_path)
    assert copied.returncode == 0 and (tmp_path / "configs" / "office" / "office.yaml").is_file()
    assert tmpnav("validate", "configs/office-ros.yaml", cwd=tmp_path).stdout.startswith("configs/office-ros.yaml: ok")


def test_every_shipped_scenario_says_what_it_is() -> None:
    """`tmpnav configs` lists each with its description: none may be blank."""
    from tmpnav.scenario import load

    blank = [p.name for p in shipped.scenarios() if not load(p).description.strip()]
    assert blank == []
