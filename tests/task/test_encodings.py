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
