"""The simulated observations' draws (belief/sequences.py): kept streams give what fresh ones do."""

from __future__ import annotations

import numpy as np

from tmpnav.belief.sequences import NoiseStreams, standard_normal_draws


def test_kept_streams_give_the_draws_of_fresh_ones_bit_for_bit() -> None:
    """Asked for more rows than it holds, a stream is drawn again longer; asked for fewer, it
    gives the first rows of what it holds: either way the draws of a fresh stream of that size."""
    streams = NoiseStreams()
    for rows in (5, 3, 64, 65, 200, 7, 1000):
        for tail in ((4, 2), (2, 2, 2)):
            want = standard_normal_draws([11, 12], (rows, *tail))
            assert np.array_equal(streams.draws([11, 12], (rows, *tail)), want)


def test_kept_streams_stay_within_their_bytes() -> None:
    """Past its limit the least recently used stream goes first, and is drawn again when asked for."""
    streams = NoiseStreams(limit=3 * 64 * 2 * 8)  # three streams of 64 rows of 2 draws
    for seed in (1, 2, 3):
        streams.rows(seed, 64, (2,))
    streams.rows(1, 64, (2,))  # 1 is used again: 2 is now the least recently used
    streams.rows(4, 64, (2,))
    assert set(streams._have) == {(1, (2,)), (3, (2,)), (4, (2,))}
    assert streams._bytes <= streams.limit
    assert np.array_equal(streams.rows(2, 10, (2,))[:10], standard_normal_draws([2], (10, 2))[0])
