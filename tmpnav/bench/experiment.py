"""``tmpnav bench`` as a whole: the experiment a command line asks for, its runs, its outputs.

An experiment with several robot counts is a robots experiment (paper, Fig. 3(c)), else a
rooms experiment (Fig. 3(b)). Bad input (a range, a scenario, too many rooms) is reported
before the first run, not after an hour of benchmarking. bench.csv is written as soon as the
runs are over; summary.md and bench.png follow, both or neither.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from tmpnav.atomic import write_file, write_files
from tmpnav.bench.runs import make_jobs, parse_counts, run_jobs, scenario_for
from tmpnav.bench.table import Row, medians, read_csv, summary_markdown, to_csv
from tmpnav.errors import InputError

BENCH_CSV, BENCH_PNG, SUMMARY_MD = "bench.csv", "bench.png", "summary.md"


def check_variant(text: str) -> str:
    """A variant of ``--encoding``: ENCODING[:COSTS[:SEARCH]], each part a known choice."""
    from tmpnav.choices import COSTS, ENCODINGS, SEARCHES

    parts = text.split(":")
    choices = (tuple(ENCODINGS), COSTS, SEARCHES)
    if len(parts) > 3 or any(p not in options for p, options in zip(parts, choices, strict=False)):
        raise InputError(
            f"--encoding {text!r}: expected ENCODING[:COSTS[:SEARCH]] with ENCODING one of "
            f"{', '.join(ENCODINGS)}, COSTS one of {', '.join(COSTS)}, SEARCH one of {', '.join(SEARCHES)}"
        )
    return text


@dataclass(frozen=True)
class BenchSpec:
    """What to run: points, sessions, encodings, seed, time limit, world, oracle workers."""

    rooms: list[int]
    robots: list[int]
    sessions: int
    encodings: list[str]
    seed: int
    timeout: float
    scenario: Path | None  # None: the shipped corridor of each robot count
    workers: int | None
    time_budget: float | None = None  # the anytime search's budget (None: the scenario's)

    @classmethod
    def parse(
        cls,
        rooms: str,
        robots: str,
        sessions: int,
        encodings: list[str],
        seed: int,
        timeout: float,
        scenario: Path | None,
        workers: int | None,
        time_budget: float | None = None,
    ) -> BenchSpec:
        """The spec of the command line's options (``--rooms 2..10``, ``--robots 2,4``)."""
        return cls(
            parse_counts(rooms, "--rooms"),
            parse_counts(robots, "--robots"),
            sessions,
            [check_variant(e) for e in encodings] or ["mixed"],
            seed,
            timeout,
            scenario,
            workers,
            time_budget,
        )

    @property
    def experiment(self) -> str:
        return "robots" if len(self.robots) > 1 else "rooms"


@dataclass(frozen=True)
class Bench:
    """The rows of an experiment (one per run and phase), run now or read from bench.csv."""

    experiment: str  # rooms | robots: the x axis
    table: list[Row]
    encodings: list[str]  # the first is the one the others are compared to
    sessions: int


def run(spec: BenchSpec, progress: Callable[[str], None] | None = None) -> Bench:
    """Run every job of the experiment, one after the other."""
    from tmpnav.scenario import load

    for n in spec.robots:  # bad input is reported before an hour of benchmarking, not after
        load(scenario_for(n, spec.scenario))
    jobs = make_jobs(
        spec.experiment,
        spec.robots,
        spec.rooms,
        spec.sessions,
        spec.encodings,
        spec.seed,
        spec.scenario,
        lambda path: [room.name for room in load(path).rooms],
    )
    table = run_jobs(jobs, spec.timeout, spec.workers, progress, spec.time_budget)
    return Bench(spec.experiment, table, spec.encodings, spec.sessions)


def replot(path: Path) -> Bench:
    """The experiment recorded in a bench.csv."""
    table = read_csv(path)
    encodings = list(dict.fromkeys(r["encoding"] for r in table))
    return Bench(table[0]["experiment"], table, encodings, len({r["session"] for r in table}))


def write_csv(bench: Bench, out_dir: Path) -> Path:
    """bench.csv, on its own: the runs are kept even if the figure fails."""
    return write_file(out_dir / BENCH_CSV, to_csv(bench.table))


def write_summary(bench: Bench, out_dir: Path, timeout: float) -> tuple[str, list[Path]]:
    """summary.md and bench.png (both or neither); returns the summary text and the paths."""
    from tmpnav.report import figures as fg
    from tmpnav.report.bench_plot import bench_figure

    axis = bench.experiment
    text = f"# tmpnav bench: {axis}\n\n" + summary_markdown(
        bench.table, axis, default=bench.encodings[0], timeout=timeout
    )
    per_point = f"{bench.sessions} session{'s' if bench.sessions != 1 else ''} per point"
    title = f"planning time against {axis} ({per_point})"
    med = medians(bench.table, axis)
    written = write_files(
        out_dir,
        {BENCH_PNG: lambda tmp: fg.render(bench_figure(med, axis, title, timeout), tmp), SUMMARY_MD: text},
    )
    return text, written
