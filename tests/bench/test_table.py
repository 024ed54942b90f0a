"""bench.csv: rows read back as written, and the summary's speed-ups and lower bounds."""

from __future__ import annotations

from pathlib import Path

import pytest

from tmpnav.bench.table import COLUMNS, PHASES, read_csv, summary_markdown, to_csv
from tmpnav.errors import InputError


def row(encoding: str, phase: str, status: str, total: str, session: int = 0) -> dict[str, str]:
    base = dict.fromkeys(COLUMNS, "")
    stages = dict.fromkeys((f"{s}_s" for s in ("roadmap", "oracle", "encode", "planner", "resimulate")), "0.1")
    return {
        **base,
        **(stages if total else {}),
        "experiment": "robots",
        "encoding": encoding,
        "robots": "4",
        "rooms": "8",
        "session": str(session),
        "phase": phase,
        "status": status,
        "total_s": total,
        "makespan": "42.5" if total else "",
    }


def test_a_timed_out_encoding_shows_a_lower_bound_cold_and_not_run_otherwise() -> None:
    table = [row("mixed", phase, "solved-optimally", "2.0") for phase in PHASES]
    table += [row("paper", phase, "timeout", "") for phase in PHASES]
    text = summary_markdown(table, "robots", default="mixed", timeout=60.0)
    lines = {tuple(c.strip() for c in line.split("|")[2:4]): line for line in text.splitlines()[2:]}
    assert "> 30x (timeout)" in lines[("paper", "cold")]
    assert "not run: the cold runs timed out" in lines[("paper", "warm")]
    assert "not run" in lines[("paper", "replan")] and "timeout |" not in lines[("paper", "replan")]


def test_read_csv_round_trips_and_rejects_other_files(tmp_path: Path) -> None:
    table = [row("mixed", phase, "solved-optimally", "2.0") for phase in PHASES]
    path = tmp_path / "bench.csv"
    path.write_text(to_csv(table))
    assert read_csv(path) == table
    other = tmp_path / "other.csv"
    other.write_text("a,b\n1,2\n")
    with pytest.raises(InputError, match=r"is not a tmpnav bench\.csv"):
        read_csv(other)
    with pytest.raises(InputError, match="cannot read"):
        read_csv(tmp_path / "missing.csv")


def test_a_stage_the_solved_runs_skipped_shows_a_dash_not_a_timeout() -> None:
    table = [row("mixed", phase, "solved-optimally", "2.0") for phase in PHASES]
    warm = next(r for r in table if r["phase"] == "warm")
    warm["oracle_s"] = warm["encode_s"] = ""  # a warm run reads the plan: no oracle, no encoding
    text = summary_markdown(table, "robots", default="mixed", timeout=60.0)
    line = next(x for x in text.splitlines() if "| warm |" in x)
    assert "timeout" not in line and [c.strip() for c in line.split("|")].count("-") == 2


def test_one_encoding_has_no_speed_up_column_and_no_empty_cell() -> None:
    table = [row("mixed", phase, "solved-optimally", "2.0") for phase in PHASES]
    text = summary_markdown(table, "robots", default="mixed", timeout=60.0)
    assert "speed-up" not in text
    for line in text.splitlines():
        assert "||" not in line.replace(" ", "") and line.count("|") == 11, line
    both = table + [row("paper", phase, "solved-optimally", "4.0") for phase in PHASES]
    lines = summary_markdown(both, "robots", default="mixed", timeout=60.0).splitlines()
    assert lines[0].endswith("| speed-up of mixed |") and all(line.count("|") == 12 for line in lines)
    assert not [line for line in lines if "| |" in line or "||" in line.replace(" ", "")]
    assert any("| 2.0x |" in line for line in lines) and any("1.0x (reference)" in line for line in lines)


def test_the_summary_shows_each_points_median_makespan() -> None:
    table = [row("mixed", "cold", "solved-optimally", "2.0", session=s) for s in range(3)]
    for r, span in zip(table, ("40", "60", "50"), strict=True):
        r["makespan"] = span
    header, _, line = summary_markdown(table, "robots", default="mixed", timeout=60.0).splitlines()
    cells = [c.strip() for c in line.split("|")]
    assert cells[[c.strip() for c in header.split("|")].index("makespan (s)")] == "50.00"


def test_a_bench_csv_written_before_the_makespan_replots(tmp_path: Path) -> None:
    """``tmpnav bench --replot`` of an older bench.csv: no makespan column, a dash in the summary."""
    from tmpnav.bench.experiment import replot, write_summary

    old = [c for c in COLUMNS if c != "makespan"]
    table = [{c: v for c, v in row("mixed", phase, "solved-optimally", "2.0").items() if c in old} for phase in PHASES]
    path = tmp_path / "bench.csv"
    path.write_text(",".join(old) + "\n" + "".join(",".join(r[c] for c in old) + "\n" for r in table))
    assert all(r["makespan"] == "" for r in read_csv(path))
    text, written = write_summary(replot(path), tmp_path, 60.0)
    assert [p.name for p in written] == ["bench.png", "summary.md"]
    header, *rows = [line for line in text.splitlines() if line.startswith("| ") and "---" not in line]
    column = [c.strip() for c in header.split("|")].index("makespan (s)")
    assert [[c.strip() for c in r.split("|")][column] for r in rows] == ["-"] * 3
    assert "makespan" in to_csv(read_csv(path)).splitlines()[0]  # written back with the column
