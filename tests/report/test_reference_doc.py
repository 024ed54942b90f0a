"""docs/scenario.md is the output of ``tmpnav reference``: it cannot drift from the schema."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from tmpnav.cli import cli
from tmpnav.report.reference import markdown
from tmpnav.scenario.format import ROS_MAP, SCENARIO
from tmpnav.scenario.schema import reference_rows

DOC = Path(__file__).resolve().parents[2] / "docs" / "scenario.md"


def test_docs_scenario_md_is_up_to_date() -> None:
    assert DOC.is_file(), "docs/scenario.md is missing: run `tmpnav reference > docs/scenario.md`"
    assert DOC.read_text(encoding="utf-8") == markdown(), (
        "docs/scenario.md differs from the schema in tmpnav/scenario/format.py: "
        "run `tmpnav reference > docs/scenario.md` and commit the result"
    )


def test_tmpnav_reference_prints_the_markdown() -> None:
    result = CliRunner().invoke(cli, ["reference"])
    assert result.exit_code == 0
    assert result.stdout == markdown()


def test_every_key_of_the_schema_has_a_row() -> None:
    text = markdown()
    for spec in (SCENARIO, ROS_MAP):
        for key, _kind, _unit, _default, meaning in reference_rows(spec):
            assert f"| `{key}` |" in text
            assert meaning, f"{key} has no description"
    # list items are documented under their list, with []
    assert "| `robots[].covariance` | 3x3 matrix | m², m², rad² |" in text
    assert "| `models.landmark_sensor.fov` | number > 0 and ≤ 6.28319 | rad | 360 deg |" in text
    assert "| `roadmap.seed` | integer ≥ 0 and ≤ 4294967295 |  | 1 |" in text


LIMITS = DOC.parent / "limits.md"


def test_docs_limits_md_is_up_to_date() -> None:
    from tmpnav.report.reference import limits_markdown

    assert LIMITS.read_text(encoding="utf-8") == limits_markdown(), (
        "docs/limits.md differs from the caps and exit codes in the code: run `python -c "
        "\"from tmpnav.report.reference import limits_markdown; print(limits_markdown(), end='')\"` "
        "> docs/limits.md` and commit the result"
    )


def test_docs_limits_md_lists_every_exit_code_and_cap() -> None:
    from tmpnav.errors import EXIT_CODES
    from tmpnav.scenario.limits import CAPS

    text = LIMITS.read_text(encoding="utf-8")
    for code in EXIT_CODES:
        assert f"\n| {code} | " in text
    for cap in CAPS:
        assert f"| {cap.default:,} | `{cap.env}` |" in text
