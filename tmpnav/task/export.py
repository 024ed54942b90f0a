"""The PDDL files of an encoded task problem."""

from __future__ import annotations

from pathlib import Path

from tmpnav.atomic import write_files
from tmpnav.task.encode import EncodedTask

PDDL_FILES = ("domain.pddl", "problem.pddl")


def pddl_texts(encoded: EncodedTask) -> tuple[str, str]:
    """(domain, problem) text; the costs are the table's, scaled to integers (see encodings)."""
    return encoded.texts()


def write_pddl(directory: Path, texts: tuple[str, str]) -> list[Path]:
    """Write domain.pddl and problem.pddl into ``directory``, both or neither."""
    return write_files(directory, dict(zip(PDDL_FILES, texts, strict=True)))
