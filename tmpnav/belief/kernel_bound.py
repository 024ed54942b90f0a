"""The compiled collision bound of :mod:`tmpnav.belief.kernel`'s propagations.

The step bound p_t and the crossing bound X_t of :mod:`tmpnav.belief.risk` (docs/models.md,
"Collision bound"), computed the same way from a step's position covariance, Cov(e_t, e_{t-1})
and the sector reach of the nominal poses, while the kernel propagates the beliefs. The numpy
functions of :mod:`tmpnav.belief.risk` are the reference they are held to in the tests; as in
the kernel, the order of the floating-point operations is part of the contract.
"""

from __future__ import annotations

import math

import numba as nb

from tmpnav.belief.risk import CONE_COS, EDGE_COS, EDGE_SIN, ESCAPE, SIGNIFICANT, SQRT2, WIDTH
from tmpnav.belief.risk import DET_FLOOR as RISK_DET_FLOOR
from tmpnav.belief.risk import TINY as RISK_TINY
from tmpnav.world.reach import SECTORS


@nb.njit(cache=True)
def _sector_masses(a, b, c, det, lam, reach, row, masses, qs):
    """The sector terms m_k of the step bound and each sector's least q_k (tmpnav.belief.risk,
    :func:`~tmpnav.belief.risk.step_bound`) into ``masses`` and ``qs`` (K,); returns their sum."""
    K = reach.shape[1]
    major = 0.5 * math.atan2(2.0 * b, a - c)
    root = math.sqrt(det)
    s0, c0 = EDGE_SIN[0], EDGE_COS[0]
    q0 = (a * s0 * s0 - 2.0 * b * s0 * c0 + c * c0 * c0) / det
    total = 0.0
    for k in range(K):
        s1, c1 = EDGE_SIN[k + 1], EDGE_COS[k + 1]
        q1 = (a * s1 * s1 - 2.0 * b * s1 * c1 + c * c1 * c1) / det
        q = 1.0 / lam if (major - WIDTH * k) % math.pi <= WIDTH else min(q0, q1)
        m = WIDTH * math.exp(-reach[row, k] * reach[row, k] * q / 2.0) / (2.0 * math.pi * root * q)
        masses[k] = m
        qs[k] = q
        total += m
        q0 = q1
    return total


@nb.njit(cache=True)
def _foot(reach, row, k):
    """tmpnav.belief.risk._foot: where the reach followed downhill from sector k is least (the
    middle of a level stretch there)."""
    K = reach.shape[1]
    at = k
    if min(reach[row, (k - 1) % K], reach[row, (k + 1) % K]) < reach[row, k]:
        step = -1 if reach[row, (k - 1) % K] < reach[row, (k + 1) % K] else 1
        for _ in range(K // 4):
            nxt = (at + step) % K
            if reach[row, nxt] > reach[row, at]:
                break
            at = nxt
    lo, hi = at, at
    for _ in range(K // 4):
        if reach[row, (lo - 1) % K] != reach[row, at]:
            break
        lo = (lo - 1) % K
    for _ in range(K // 4):
        if reach[row, (hi + 1) % K] != reach[row, at]:
            break
        hi = (hi + 1) % K
    return (lo + ((hi - lo) % K + 1) // 2) % K


@nb.njit(cache=True)
def _support(reach, row, ball, n):
    """tmpnav.belief.risk._support: how far the star of reaches of ``row``, cut to the ball of
    radius ``ball``, reaches along edge n's direction."""
    K = reach.shape[1]
    out = 0.0
    for o in range(-(K // 4), K // 4):
        d = o if o >= 0 else -o - 1
        out = max(out, min(reach[row, (n + o) % K], ball) * CONE_COS[d])
    return out


@nb.njit(cache=True)
def _passage(R, q, c, b, s, tail):
    """tmpnav.belief.risk._passage: int_R^inf rho exp(-q rho²/2) Phi((b - c rho)/s) d rho,
    ``tail`` = exp(-q R²/2)."""
    if s <= 0.0 or c > 1e8 * s:
        top = max(R, b / c)
        return max(tail - math.exp(-q * top * top / 2.0), 0.0) / q
    z = c / s
    P = q + z * z
    m = b * z / (s * P)
    first = tail * 0.5 * math.erfc((c * R - b) / (s * SQRT2))
    second = z / math.sqrt(P) * math.exp(-q * b * b / (2.0 * (q * s * s + c * c)))
    second *= 0.5 * math.erfc(math.sqrt(P) * (R - m) / SQRT2)
    return max(first - second, 0.0) / q


@nb.njit(cache=True, inline="always")
def _decode(codes, values, row, out, at):
    """Row ``row`` of a reach table kept as codes (:class:`tmpnav.world.reach.SectorReach`) into
    row ``at`` of ``out`` (., K) m."""
    for k in range(codes.shape[1]):
        out[at, k] = values[codes[row, k]]


@nb.njit(cache=True)
def _step_bound(a, b, c, reach, row, masses, qs):
    """p_t of tmpnav.belief.risk.step_bound at ``row`` for the position covariance
    [[a, b], [b, c]], and the sum of its sector terms (left in ``masses`` and ``qs``), or -1
    where the sectors are not used (the disc's bound, or 1 where a sector has no reach)."""
    K = reach.shape[1]
    r_min = reach[row, 0]
    for k in range(1, K):
        r_min = min(r_min, reach[row, k])
    if r_min <= 0.0:
        return 1.0, -1.0
    lam = 0.5 * (a + c) + math.sqrt(0.25 * (a - c) * (a - c) + b * b)
    if lam <= 0.0:
        return 0.0, -1.0
    disc = math.exp(-r_min * r_min / (2.0 * lam))
    det = a * c - b * b
    if K != SECTORS or disc < RISK_TINY or not det > RISK_DET_FLOOR * lam * lam:
        return disc, -1.0
    total = _sector_masses(a, b, c, det, lam, reach, row, masses, qs)
    return min(disc, total, 1.0), total


@nb.njit(cache=True)
def _step_risk(prev, ap, bp, cp, row, a, b, c, C00, C01, C10, C11, reach, masses, qs, support):
    """(p_t, X_t) of tmpnav.belief.risk: the step bound at ``row`` (position covariance
    [[a, b], [b, c]]) and the crossing bound from ``prev`` (covariance [[ap, bp], [bp, cp]]),
    with Cov(e_t, e_{t-1}) = [[C00, C01], [C10, C11]], computed the same way
    (:func:`~tmpnav.belief.risk.step_bound`, :func:`~tmpnav.belief.risk.crossing_bound`)."""
    p, total = _step_bound(a, b, c, reach, row, masses, qs)
    if total < 0.0:
        return p, p
    K = reach.shape[1]
    det = a * c - b * b
    rp_min = reach[prev, 0]
    for k in range(1, K):
        rp_min = min(rp_min, reach[prev, k])
    escape = ESCAPE * total
    if rp_min <= 0.0 or escape >= p:
        return p, p
    lam_p = 0.5 * (ap + cp) + math.sqrt(0.25 * (ap - cp) * (ap - cp) + bp * bp)
    ball = math.sqrt(-2.0 * math.log(escape) * max(lam_p, 0.0))
    G00, G01 = (c * C00 - b * C10) / det, (c * C01 - b * C11) / det
    G10, G11 = (a * C10 - b * C00) / det, (a * C11 - b * C01) / det
    L00 = ap - (C00 * G00 + C10 * G10)
    L01 = bp - (C00 * G01 + C10 * G11)
    L11 = cp - (C01 * G01 + C11 * G11)
    scale = WIDTH / (2.0 * math.pi * math.sqrt(det))
    for k in range(K):
        support[k] = -1.0
    out = escape
    for k in range(K):
        best = masses[k]
        if best >= SIGNIFICANT * total:
            foot, pick, z_pick, c_pick, s_pick = _foot(reach, row, k), -1, math.inf, 0.0, 0.0
            for o in range(-1, 3):
                n = (foot + o) % K
                nx, ny = EDGE_COS[n], EDGE_SIN[n]
                gx, gy = G00 * nx + G01 * ny, G10 * nx + G11 * ny
                lo = min(gx * EDGE_COS[k] + gy * EDGE_SIN[k], gx * EDGE_COS[k + 1] + gy * EDGE_SIN[k + 1])
                if lo <= 0.0:
                    continue
                if support[n] < 0.0:
                    support[n] = _support(reach, prev, ball, n)
                s = math.sqrt(max(L00 * nx * nx + 2.0 * L01 * nx * ny + L11 * ny * ny, 0.0))
                gap = support[n] - lo * reach[row, k]
                z = gap / s if s > 0.0 else (math.inf if gap > 0.0 else -math.inf)
                if pick < 0 or z < z_pick:
                    pick, z_pick, c_pick, s_pick = n, z, lo, s
            if pick >= 0:
                tail = best * qs[k] / scale
                best = min(best, scale * _passage(reach[row, k], qs[k], c_pick, support[pick], s_pick, tail))
        out += best
    return p, min(p, out)
