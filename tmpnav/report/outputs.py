"""``tmpnav plan -o DIR``: plan.json, plan.png and the PDDL files, written all or nothing.

Every file is first written in full to a hidden temporary file in the output directory, then
the temporary files are renamed over their targets one after the other (``os.replace``, atomic
on POSIX within a directory). If anything fails before the renames, the temporary files are
removed and the files of an earlier run stay as they were: a reader never sees a partial
plan.json or a plan.png of another plan than the plan.json beside it.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Any

from tmpnav.report.figures import public_mode
from tmpnav.report.plan_json import dumps, plan_document
from tmpnav.report.plan_plot import plot_plan

PLAN_JSON = "plan.json"
PLAN_PNG = "plan.png"
PDDL_FILES = ("domain.pddl", "problem.pddl")


def _temporary(directory: Path, name: str) -> Path:
    """A new empty hidden file in ``directory`` for ``name``'s content (same file system: rename is atomic)."""
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{name}.", suffix=".tmp")
    os.close(fd)
    return Path(tmp)


def stage_text(tmp: Path, text: str) -> None:
    """Write ``text`` to the temporary file ``tmp`` and flush it to disk."""
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())


def write_outputs(report: Any, out_dir: Path, pddl: tuple[str, str] | None) -> list[Path]:
    """Write plan.json, plan.png and, when ``pddl`` = (domain, problem) is given, domain.pddl and
    problem.pddl into ``out_dir`` (created if missing). Returns the paths written, in that order.

    All or nothing up to the renames: on any error no file of this run is left behind (and a
    directory created for it is removed again if still empty), and the error propagates.
    """
    out_dir = Path(out_dir)
    created = not out_dir.exists()
    out_dir.mkdir(parents=True, exist_ok=True)
    texts: list[tuple[str, str]] = [(PLAN_JSON, dumps(plan_document(report)))]
    if pddl is not None:
        texts += list(zip(PDDL_FILES, pddl, strict=True))
    staged: list[tuple[Path, Path]] = []  # (temporary file, target)
    try:
        for name, text in texts:
            tmp = _temporary(out_dir, name)
            staged.append((tmp, out_dir / name))
            stage_text(tmp, text)
        tmp = _temporary(out_dir, PLAN_PNG)
        staged.insert(1, (tmp, out_dir / PLAN_PNG))
        plot_plan(report, tmp)
        mode = public_mode()
        for tmp, _ in staged:
            os.chmod(tmp, mode)
    except BaseException:
        _discard(staged)
        if created:
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        raise
    try:
        for tmp, target in staged:
            os.replace(tmp, target)
    finally:
        _discard(staged)  # only those a failed rename left behind
    return [target for _, target in staged]


def _discard(staged: list[tuple[Path, Path]]) -> None:
    for tmp, _ in staged:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
