"""The PDDL files of an encoded problem, as unified-planning writes them for ENHSP."""

from __future__ import annotations

from pathlib import Path

from tmpnav.atomic import write_files
from tmpnav.task.encode import EncodedProblem

PDDL_FILES = ("domain.pddl", "problem.pddl")


def pddl_texts(encoded: EncodedProblem) -> tuple[str, str]:
    """(domain, problem) text; the costs are the table's, scaled to integers (see encodings)."""
    from unified_planning.io import PDDLWriter

    writer = PDDLWriter(encoded.problem)
    return str(writer.get_domain()), str(writer.get_problem())


def write_pddl(directory: Path, texts: tuple[str, str]) -> list[Path]:
    """Write domain.pddl and problem.pddl into ``directory``, both or neither."""
    return write_files(directory, dict(zip(PDDL_FILES, texts, strict=True)))
