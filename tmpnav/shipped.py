"""The scenarios shipped with tmpnav: the checkout's configs/, installed as the data package
``tmpnav.configs`` (like the PDDL domains in pddl/), so an installed tmpnav has them too.

On the command line a shipped scenario is named as in the checkout, ``configs/NAME.yaml``:
when no such file exists under the working directory, the shipped one is used. ``tmpnav
configs`` lists them, and ``tmpnav configs -o DIR`` copies them (with the ROS map of
``office-ros.yaml``) to edit them.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from tmpnav.atomic import write_files

PREFIX = "configs"


def configs_dir() -> Path:
    """The folder of the shipped scenarios (in the checkout for an editable install)."""
    return Path(str(files("tmpnav.configs")))


def scenarios() -> list[Path]:
    """The shipped scenario files, by name."""
    return sorted(configs_dir().glob("*.yaml"))


def resolve(path: Path) -> Path:
    """``path`` itself when it exists (or names no shipped scenario), else the shipped file it names:
    ``configs/corridor.yaml`` is the shipped corridor wherever tmpnav runs."""
    if path.exists() or path.is_absolute() or len(path.parts) < 2 or path.parts[0] != PREFIX:
        return path
    candidate = configs_dir().joinpath(*path.parts[1:])
    return candidate if candidate.is_file() else path


def data_files() -> list[Path]:
    """Every shipped file a scenario may need (scenarios, map images), relative to the folder."""
    root = configs_dir()
    return sorted(
        p.relative_to(root)
        for p in root.rglob("*")
        if p.is_file() and p.suffix in (".yaml", ".pgm", ".png") and "__pycache__" not in p.parts
    )


def copy_to(directory: Path) -> tuple[list[Path], list[Path]]:
    """Copy the shipped scenarios (and their maps) into ``directory``; files already there are
    kept as they are. Returns (written, kept)."""
    root = configs_dir()
    written: list[Path] = []
    kept: list[Path] = []
    by_folder: dict[Path, dict[str, str | bytes]] = {}
    for rel in data_files():
        target = directory / rel
        if target.exists():
            kept.append(target)
        else:
            by_folder.setdefault(target.parent, {})[target.name] = (root / rel).read_bytes()
    for folder, contents in by_folder.items():
        written += write_files(folder, contents)
    return written, kept
