"""The encoding registry: what each encoding asks of the oracle, and who reads the registry."""

from __future__ import annotations

from tmpnav.scenario.format import ENCODING_CHOICES
from tmpnav.task.encodings import ENCODINGS, MixedEncoding, scaled
from tmpnav.types import CostTable, Goals

GOALS = Goals(visit=("A", "B"), per_robot=(("r1", ("C",)),))
STARTS = {"r1": "S", "r2": "T"}


def test_the_command_line_and_the_scenario_format_offer_the_registered_encodings() -> None:
    from tmpnav.cli.options import encoding_choice

    assert list(encoding_choice().choices) == list(ENCODINGS) == list(ENCODING_CHOICES) == ["paper", "single", "mixed"]
    assert all("(define (domain" in e.domain_text() for e in ENCODINGS.values())


def test_what_each_encoding_asks_of_the_oracle() -> None:
    paper, single, mixed = (ENCODINGS[n].table_request(GOALS, STARTS, 0.05) for n in ("paper", "single", "mixed"))
    assert (paper.destinations, single.destinations, mixed.destinations) == ("all-rooms", "goals", "goals")
    assert single.pair_filter is None
    assert paper.pair_filter is not None and mixed.pair_filter is not None
    assert (paper.pair_min_gain, single.pair_min_gain, mixed.pair_min_gain) == (None, None, 0.05)
    assert ENCODINGS["mixed"].table_request(GOALS, STARTS, 0.0).pair_min_gain is None
    assert paper.filter_key != mixed.filter_key  # the cost table's cache key tells them apart
    # the paper pairs any two robots; mixed never lets two robots enter one room nobody targets
    assert paper.pair_filter(("r1", "S", "A"), ("r2", "T", "A"))
    assert not mixed.pair_filter(("r1", "S", "A"), ("r2", "T", "A"))
    assert mixed.pair_filter(("r1", "S", "A"), ("r2", "T", "B"))
    assert not mixed.pair_filter(("r1", "S", "A"), ("r1", "S", "B"))


def test_mixed_offers_only_pairs_that_save_at_least_the_gain() -> None:
    single = {("r1", "S", "A"): 10.0, ("r2", "T", "B"): 10.0, ("r2", "T", "A"): 10.0, ("r1", "S", "B"): 10.0}
    pair = {
        (("r1", "S", "A"), ("r2", "T", "B")): 15.0,  # saves 25%
        (("r1", "S", "B"), ("r2", "T", "A")): 19.5,  # saves 2.5%
    }
    table = CostTable(("r1", "r2"), ("A", "B"), ("A", "B", "S", "T"), STARTS, single, pair)
    mixed = ENCODINGS["mixed"]
    assert isinstance(mixed, MixedEncoding)
    assert list(mixed.offered_pairs(table, 0.05)) == [(("r1", "S", "A"), ("r2", "T", "B"))]
    assert len(mixed.offered_pairs(table, 0.0)) == 2
    assert scaled(10.0004) == 10000 and scaled(10.0006) == 10001


def test_a_sub_problem_keeps_the_pairs_that_save_the_largest_share() -> None:
    from tmpnav.task.encodings import strongest_pairs
    from tmpnav.task.pddl_text import write_task

    rooms = ("A", "B", "C", "D")
    single = {(r, s, x): 10.0 for r, s in STARTS.items() for x in rooms}
    saves = {("A", "B"): 0.40, ("B", "A"): 0.30, ("C", "D"): 0.30, ("D", "C"): 0.10, ("A", "C"): 0.02}
    pair = {(("r1", "S", x), ("r2", "T", y)): 20.0 * (1 - share) for (x, y), share in saves.items()}
    duration = {(m1, m2): (5.0, 6.0) for m1, m2 in pair}
    table = CostTable(("r1", "r2"), rooms, (*rooms, "S", "T"), STARTS, single, pair, pair_duration=duration)

    def kept(t: CostTable) -> list[tuple[str, str]]:
        return sorted((m1[2], m2[2]) for m1, m2 in t.pair)

    assert kept(strongest_pairs(table, 0.05, 1)) == [("A", "B")]
    # of two that save alike, the first by the moves' names
    assert kept(strongest_pairs(table, 0.05, 2)) == [("A", "B"), ("B", "A")]
    # within the limit: the table itself (the encoding leaves out what saves less than the gain)
    assert strongest_pairs(table, 0.05, 4) is table and strongest_pairs(table, 0.0, 5) is table
    # a pair below the least gain is never kept in its place
    assert ("A", "C") not in kept(strongest_pairs(table, 0.05, 3))
    assert set(strongest_pairs(table, 0.05, 2).pair_duration) == set(strongest_pairs(table, 0.05, 2).pair)
    # the PDDL text offers exactly the kept pairs
    goals = Goals(visit=rooms, per_robot=())
    assert len(set(write_task(table, goals, "mixed", "sub", 0.05, most_pairs=2).pair_actions.values())) == 2
    assert len(set(write_task(table, goals, "mixed", "sub", 0.05).pair_actions.values())) == 4
