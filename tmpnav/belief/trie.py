"""Trie order: simulations sorted so that neighbours share the longest prefixes.

Motions from one start state follow the roadmap's shortest-path tree, so many begin with the
same controls. Sorted in lexicographic order of their step sequences, each simulation shares
the most steps with the one before it, and the compiled kernel
(:func:`tmpnav.belief.kernel.run_sequences`) restarts it from the state after those steps.
The order decides only how much is recomputed, never a result; results depend on it only
through the restarts being bit-identical to runs from scratch (tested).
"""

from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def common_prefix_matrix(ctrl, m_off, m_T, motions):
    """Leading steps in common between each pair of ``motions`` (all from one start).

    Two motions from the same start state share step k when their controls agree on
    steps 0..k-1; a motion compared with itself shares all of them (a large number).
    """
    k = motions.shape[0]
    out = np.empty((k, k), dtype=np.int64)
    for a in range(k):
        out[a, a] = 1 << 40
        for b in range(a + 1, k):
            ma, mb = motions[a], motions[b]
            T = min(m_T[ma], m_T[mb])
            d = T
            for s in range(T):
                ra, rb = m_off[ma] + s, m_off[mb] + s
                if ctrl[ra, 0] != ctrl[rb, 0] or ctrl[ra, 1] != ctrl[rb, 1]:
                    d = s
                    break
            out[a, b] = d
            out[b, a] = d
    return out


@nb.njit(cache=True)
def _before(a, b, x, y, P1, P2):
    """Is combination x before y in the lexicographic order of their joint step sequences?

    Motions are numbered in each robot's lexicographic order, and P1, P2 give the steps two
    motions share. The joint sequences first differ where the earlier-diverging robot
    does, so that robot's order decides (robot 1 on a tie).
    """
    l1 = P1[a[x], a[y]]
    l2 = P2[b[x], b[y]]
    if l2 < l1:
        return b[x] < b[y]
    if a[x] != a[y]:
        return a[x] < a[y]
    return b[x] < b[y]


@nb.njit(cache=True)
def joint_lex_order(a, b, P1, P2):
    """Permutation sorting two-robot combinations (motions a[k], b[k]) into trie order
    (a stable merge sort with :func:`_before`)."""
    n = a.shape[0]
    order = np.arange(n)
    tmp = np.empty(n, dtype=order.dtype)
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid = min(lo + width, n)
            hi = min(lo + 2 * width, n)
            i, j, k = lo, mid, lo
            while i < mid and j < hi:
                if _before(a, b, order[j], order[i], P1, P2):
                    tmp[k] = order[j]
                    j += 1
                else:
                    tmp[k] = order[i]
                    i += 1
                k += 1
            while i < mid:
                tmp[k] = order[i]
                i += 1
                k += 1
            while j < hi:
                tmp[k] = order[j]
                j += 1
                k += 1
        order[:] = tmp
        width *= 2
    return order
