"""The PDDL files of an encoded problem, as unified-planning writes them for ENHSP."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from tmpnav.task.encode import EncodedProblem


def pddl_texts(encoded: EncodedProblem) -> tuple[str, str]:
    """(domain, problem) text; the costs are the table's, scaled to integers (see encode)."""
    from unified_planning.io import PDDLWriter

    writer = PDDLWriter(encoded.problem)
    return writer.get_domain(), writer.get_problem()


def write_pddl(directory: Path, texts: tuple[str, str]) -> list[Path]:
    """Write domain.pddl and problem.pddl atomically (temporary files renamed at the end)."""
    directory.mkdir(parents=True, exist_ok=True)
    staged: list[tuple[str, Path]] = []
    try:
        for name, text in zip(("domain.pddl", "problem.pddl"), texts, strict=True):
            fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{name}.", suffix=".tmp")
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                fh.write(text)
            staged.append((tmp, directory / name))
        for tmp, final in staged:
            os.replace(tmp, final)
    finally:
        for tmp, _ in staged:
            if os.path.exists(tmp):
                os.unlink(tmp)
    return [final for _, final in staged]
