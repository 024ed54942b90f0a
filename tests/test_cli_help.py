"""The help of every command reads without the paper: each option has a sentence and says its
default, command summaries are whole, renamed options keep their earlier names working."""

from __future__ import annotations

import click
import pytest
from click.testing import CliRunner

from tmpnav.cli import cli


def commands(group: click.Group = cli, prefix: str = "") -> list[tuple[str, click.Command]]:
    """Every command of ``tmpnav``, sub-commands of groups included, by its path."""
    found: list[tuple[str, click.Command]] = []
    for name, command in sorted(group.commands.items()):
        found.append((prefix + name, command))
        if isinstance(command, click.Group):
            found += commands(command, f"{prefix}{name} ")
    return found


def help_records(path: str, command: click.Command) -> list[tuple[click.Option, str, str]]:
    ctx = click.Context(command, info_name=path)
    records = []
    for param in command.params:
        if isinstance(param, click.Option) and not param.hidden:
            record = param.get_help_record(ctx)
            assert record is not None
            records.append((param, *record))
    return records


@pytest.mark.parametrize(("path", "command"), commands(), ids=[p for p, _ in commands()])
def test_every_option_says_what_it_does_and_its_default(path: str, command: click.Command) -> None:
    for param, names, text in help_records(path, command):
        assert len(text) > 20, f"tmpnav {path} {names}: no help sentence"
        if not param.is_flag and not param.required:  # a flag is off unless given
            assert "[default: " in text, f"tmpnav {path} {names}: no default in {text!r}"


def test_command_summaries_are_not_cut() -> None:
    result = CliRunner().invoke(cli, ["--help"], terminal_width=80)
    listed = result.output.split("Commands:")[1].split("Exit codes")[0]
    rows = [line for line in listed.splitlines() if line.strip()]
    assert len(rows) == len(cli.commands)
    assert not [row for row in rows if row.endswith("...")], listed


def test_the_two_time_limits_have_distinct_names_and_the_old_ones_still_work() -> None:
    plan = cli.commands["plan"]
    names = {n for _, names, _ in help_records("plan", plan) for n in names.replace(",", " ").split()}
    assert {"--planner-timeout", "--anytime-budget"} <= names
    assert not {"--timeout", "--time-budget"} & names  # hidden: scripts use them, help does not show them
    ctx = plan.make_context("plan", ["configs/corridor.yaml", "--timeout", "7", "--time-budget", "9"])
    assert ctx.params["timeout"] == 7.0 and ctx.params["time_budget"] == 9.0
    bench = cli.commands["bench"]
    ctx = bench.make_context("bench", ["--timeout", "60", "--time-budget", "30"])
    assert ctx.params["timeout"] == 60.0 and ctx.params["time_budget"] == 30.0


def test_simulate_offers_no_switch_for_mutual_observations() -> None:
    """simulate runs the plan with and without them itself (configs 1 and 2)."""
    options = {o for p in cli.commands["simulate"].params for o in getattr(p, "opts", [])}
    assert "--no-mutual-observations" not in options
    assert "--no-mutual-observations" in {o for p in cli.commands["plan"].params for o in getattr(p, "opts", [])}
