"""Stage 4: the multi-robot EKF in belief space (paper, section Problem Definition).

What runs, and what it is checked against:

- :mod:`~tmpnav.belief.sequences` is the stage's entry point for the oracle: a
  :class:`~tmpnav.belief.sequences.SequenceBatch` of simulations in, a
  :class:`~tmpnav.belief.sequences.SequenceResults` out, computed by the compiled EKF of
  :mod:`~tmpnav.belief.kernel` (numba). This is the production path, and with
  :mod:`~tmpnav.belief.controls` and :mod:`~tmpnav.belief.trie` the only belief code
  that decides the oracle's results (and its cache keys).
- :mod:`~tmpnav.belief.ekf` is the reference: filterpy's EKF on immutable beliefs, built
  from the equations of :mod:`~tmpnav.belief.models` (one function per equation);
  :mod:`~tmpnav.belief.reference` propagates a whole simulation through it, and the tests
  hold the kernel to it step by step.
- :mod:`~tmpnav.belief.rollout` describes one simulation as arrays and runs it through
  either path.

The maths, units and cost definition are written out in docs/models.md.
"""
