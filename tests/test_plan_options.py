"""PlanOptions from flat keywords: every keyword lands where it belongs."""

from __future__ import annotations

import pytest

from tmpnav.pipeline import PlanOptions


def test_the_search_reporter_and_the_search_override_are_told_apart() -> None:
    def told(*_: object) -> None:
        return None

    options = PlanOptions.of(search_progress=told, search="anytime", progress=told, max_risk=0.1, use_cache=False)
    assert options.reporters.search is told and options.reporters.oracle is told
    assert options.overrides.search == "anytime" and options.overrides.max_risk == 0.1
    assert options.execution.use_cache is False
    assert options.but(search="exact").reporters.search is told


def test_an_unknown_keyword_is_refused() -> None:
    with pytest.raises(TypeError, match="unknown plan options: colour"):
        PlanOptions.of(colour="red")
