"""The user's documents: a short README, links that resolve, every exit code listed, and docs
that describe tmpnav as it is (no dates or history: those are in CHANGELOG.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tmpnav.errors import EXIT_CODES

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted((ROOT / "docs").glob("*.md"))
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


def test_the_readme_is_a_quick_start() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 120
    assert "make demo" in text and "make test" in text  # the two commands that set everything up


@pytest.mark.parametrize("doc", [ROOT / "README.md", ROOT / "CHANGELOG.md", *DOCS], ids=lambda p: p.name)
def test_relative_links_resolve(doc: Path) -> None:
    text = re.sub(r"```.*?```", "", doc.read_text(encoding="utf-8"), flags=re.S)  # not in code blocks
    for target in LINK.findall(text):
        if "://" in target or target.startswith("mailto:"):
            continue
        assert (doc.parent / target).exists(), f"{doc.name}: the link to {target} leads nowhere"


def test_usage_lists_every_exit_code() -> None:
    text = (ROOT / "docs" / "usage.md").read_text(encoding="utf-8")
    for code in EXIT_CODES:
        assert f"\n| {code} | " in text, f"exit code {code} is missing from docs/usage.md"


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_docs_hold_no_history(doc: Path) -> None:
    text = doc.read_text(encoding="utf-8")
    for pattern in (r"\b20\d\d-\d\d-\d\d\b", r"\bpreviously\b", r"\bstop \d", r"\bin (an|this|the last) session\b"):
        found = re.search(pattern, text, re.IGNORECASE)
        assert found is None, f"{doc.name}: {text[max(0, found.start() - 60) : found.end() + 60]!r}"
