"""The compiled EKF that runs in the oracle: many propagations that share their prefixes.

This is the production path of the belief stage; :mod:`tmpnav.belief.sequences` is its
only caller and documents the data layout (:class:`~tmpnav.belief.sequences.SequenceBatch`).
The reference it is held to (1e-9, step by step, in the tests) is the filterpy EKF of
:mod:`tmpnav.belief.ekf` driven by :func:`tmpnav.belief.reference.propagate_reference`:
the same models (paper eqs. (4), (5), (14), (15), and the range sensor of docs/models.md),
the same prediction (eqs. (8), (11), (12)) and update (eqs. (9), (13)) in the same order
within a step. The update is the
Joseph form with an explicit 2x2 inverse of S, its result mirrored from the upper triangle.
Where the collision bound is wanted, each step also carries Cov(e_t, e_{t-1}) of every robot's
position error through the same prediction and updates (e <- F e + noise, e <- (I - K H) e -
K v), which the bound's crossing terms need (:mod:`tmpnav.belief.risk`).

Simulations that start from the same belief and whose first d steps are identical (the
same controls, poses, visibility and simulated noise) have identical beliefs after step
d. Simulations arrive in trie order, each saying how many leading steps it shares with
the previous one; :func:`run_sequences` restarts it from the stored state of that step,
so every node of the trie is computed once.

Compiled with numba (cached on disk after the first call of a process). The order of the
floating-point operations is part of the contract: cached costs and recorded plans depend
on it bit for bit. Speed is part of it too: helpers of the step loop are inlined
(``inline="always"``) and the named tuples are unpacked once per simulation, because a
call or a tuple-field binding with array arguments per step or per observation cost the
oracle about a third of its throughput when measured.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from tmpnav.belief.kernel_bound import _decode, _step_bound, _step_risk
from tmpnav.world.geometry import wrap_angle_scalar


@nb.njit(cache=True)
def _predict(mean, cov, u, n, dt, alphas, work, mid=0.0):
    """Joint prediction, paper eqs. (8), (11)-(12): P = F P Fᵀ + V W Vᵀ.

    F is block-diagonal with F_i = I + E_i, where E_i has only the entries (0, 2) =
    -v dt sin(phi) and (1, 2) = v dt cos(phi); F P Fᵀ is therefore computed as
    (P + E P) + (P + E P) Eᵀ with a few multiplications per entry. phi is the heading the step
    translates along (tmpnav.belief.models.motion): th + mid omega dt / 2, ``mid`` 1 for the
    midpoint step, 0 for the Euler step.
    """
    D = 3 * n
    for r in range(D):
        for c in range(D):
            work[r, c] = cov[r, c]
    for i in range(n):
        phi = mean[3 * i + 2] + mid * 0.5 * u[i, 1] * dt
        v = u[i, 0]
        e0, e1 = -v * dt * math.sin(phi), v * dt * math.cos(phi)
        if e0 != 0.0 or e1 != 0.0:
            for c in range(D):  # rows 3i, 3i+1 of (I + E) P
                work[3 * i, c] += e0 * cov[3 * i + 2, c]
                work[3 * i + 1, c] += e1 * cov[3 * i + 2, c]
    for r in range(D):
        for c in range(D):
            cov[r, c] = work[r, c]
    for j in range(n):
        phi = mean[3 * j + 2] + mid * 0.5 * u[j, 1] * dt
        v = u[j, 0]
        e0, e1 = -v * dt * math.sin(phi), v * dt * math.cos(phi)
        if e0 != 0.0 or e1 != 0.0:
            for r in range(D):  # columns 3j, 3j+1 of (...) (I + E)ᵀ
                cov[r, 3 * j] += work[r, 3 * j + 2] * e0
                cov[r, 3 * j + 1] += work[r, 3 * j + 2] * e1
    for i in range(n):
        th = mean[3 * i + 2]
        v, w = u[i, 0], u[i, 1]
        phi = th + mid * 0.5 * w * dt
        co, sn = math.cos(phi), math.sin(phi)
        w_v = alphas[0] * v * v + alphas[1] * w * w
        w_w = alphas[2] * v * v + alphas[3] * w * w
        # R_i = V W Vᵀ with V = [[dt c, V01], [dt s, V11], [0, dt]]
        V00, V10 = dt * co, dt * sn
        cov[3 * i, 3 * i] += V00 * w_v * V00
        cov[3 * i, 3 * i + 1] += V00 * w_v * V10
        cov[3 * i + 1, 3 * i] += V10 * w_v * V00
        cov[3 * i + 1, 3 * i + 1] += V10 * w_v * V10
        cov[3 * i + 2, 3 * i + 2] += dt * w_w * dt
        if mid != 0.0 and v != 0.0:  # the midpoint step: the turn's noise moves the position too
            V01, V11 = -0.5 * v * dt * dt * sn * mid, 0.5 * v * dt * dt * co * mid
            cov[3 * i, 3 * i] += V01 * w_w * V01
            cov[3 * i, 3 * i + 1] += V01 * w_w * V11
            cov[3 * i + 1, 3 * i] += V11 * w_w * V01
            cov[3 * i + 1, 3 * i + 1] += V11 * w_w * V11
            cov[3 * i, 3 * i + 2] += V01 * w_w * dt
            cov[3 * i + 2, 3 * i] += dt * w_w * V01
            cov[3 * i + 1, 3 * i + 2] += V11 * w_w * dt
            cov[3 * i + 2, 3 * i + 1] += dt * w_w * V11
        mean[3 * i] = mean[3 * i] + v * dt * co
        mean[3 * i + 1] = mean[3 * i + 1] + v * dt * sn
        mean[3 * i + 2] = wrap_angle_scalar(th + w * dt)


@nb.njit(cache=True, inline="always")
def _update(mean, cov, H, cols, ncols, y, Q, n, work, PHt, K):
    """EKF update with a 2-D observation, paper eq. (9), in Joseph form, symmetrised.

    H (2 x D) is non-zero only in the columns ``cols[:ncols]`` (the observed robots).
    The Joseph product (I - K H) P (I - K H)ᵀ + K Q Kᵀ is evaluated as two rank-2
    corrections: M = P - K (H P), then M - (M Hᵀ) Kᵀ + K Q Kᵀ, whose upper triangle is
    mirrored (the reference symmetrises with (P + Pᵀ)/2; the two differ by rounding only).
    """
    D = 3 * n
    for r in range(D):
        for k in range(2):
            acc = 0.0
            for q in range(ncols):
                acc += cov[r, cols[q]] * H[k, cols[q]]
            PHt[r, k] = acc
    S00 = Q[0, 0]
    S01 = Q[0, 1]
    S10 = Q[1, 0]
    S11 = Q[1, 1]
    for q in range(ncols):
        cq = cols[q]
        S00 += H[0, cq] * PHt[cq, 0]
        S01 += H[0, cq] * PHt[cq, 1]
        S10 += H[1, cq] * PHt[cq, 0]
        S11 += H[1, cq] * PHt[cq, 1]
    det = S00 * S11 - S01 * S10
    i00, i11, i01, i10 = S11 / det, S00 / det, -S01 / det, -S10 / det
    for r in range(D):
        K[r, 0] = PHt[r, 0] * i00 + PHt[r, 1] * i10
        K[r, 1] = PHt[r, 0] * i01 + PHt[r, 1] * i11
        mean[r] += K[r, 0] * y[0] + K[r, 1] * y[1]
    for i in range(n):
        mean[3 * i + 2] = wrap_angle_scalar(mean[3 * i + 2])
    # M = P - K (H P), where H P = PHtᵀ (P is symmetric)
    for r in range(D):
        for c in range(D):
            work[r, c] = cov[r, c] - (K[r, 0] * PHt[c, 0] + K[r, 1] * PHt[c, 1])
    # M Hᵀ
    for r in range(D):
        for k in range(2):
            acc = 0.0
            for q in range(ncols):
                acc += work[r, cols[q]] * H[k, cols[q]]
            PHt[r, k] = acc
    # the result is symmetric: compute the upper triangle and mirror it
    for r in range(D):
        kq0 = K[r, 0] * Q[0, 0] + K[r, 1] * Q[1, 0]
        kq1 = K[r, 0] * Q[0, 1] + K[r, 1] * Q[1, 1]
        for c in range(r, D):
            v = work[r, c] - (PHt[r, 0] * K[c, 0] + PHt[r, 1] * K[c, 1]) + (kq0 * K[c, 0] + kq1 * K[c, 1])
            cov[r, c] = v
            cov[c, r] = v


@nb.njit(cache=True, inline="always")
def _update_scalar(mean, cov, g, c0, y, n, work, PHt, K):
    """EKF update with one scalar pseudo-measurement of unit noise, eq. (9) in Joseph form:
    h is ``g`` (3,) in the columns c0..c0+2 of one robot, R = 1, innovation ``y``. A range
    scan is three of them (:func:`_scan_update`)."""
    D = 3 * n
    for r in range(D):
        PHt[r, 0] = cov[r, c0] * g[0] + cov[r, c0 + 1] * g[1] + cov[r, c0 + 2] * g[2]
    S = 1.0 + g[0] * PHt[c0, 0] + g[1] * PHt[c0 + 1, 0] + g[2] * PHt[c0 + 2, 0]
    for r in range(D):
        K[r, 0] = PHt[r, 0] / S
        mean[r] += K[r, 0] * y
    for i in range(n):
        mean[3 * i + 2] = wrap_angle_scalar(mean[3 * i + 2])
    for r in range(D):  # M = P - K (h P)
        for c in range(D):
            work[r, c] = cov[r, c] - K[r, 0] * PHt[c, 0]
    for r in range(D):  # M hᵀ
        PHt[r, 0] = work[r, c0] * g[0] + work[r, c0 + 1] * g[1] + work[r, c0 + 2] * g[2]
    for r in range(D):  # M - (M hᵀ) Kᵀ + K Kᵀ, upper triangle mirrored
        for c in range(r, D):
            v = work[r, c] - PHt[r, 0] * K[c, 0] + K[r, 0] * K[c, 0]
            cov[r, c] = v
            cov[c, r] = v


@nb.njit(cache=True, inline="always")
def scan_weight(thresholds: np.ndarray, v: float, omega: float, dt: float) -> float:
    """sqrt of the share of a scan the localiser takes in a step driven at (v, omega) for dt
    (:meth:`tmpnav.types.ScanModel.update_rate`): the factor of the scan's rows G."""
    if thresholds[0] <= 0.0:
        return 1.0
    return math.sqrt(min(1.0, max(abs(v) * dt / thresholds[0], abs(omega) * dt / thresholds[1])))


@nb.njit(cache=True, inline="always")
def _scan_update(mean, cov, i, G, w, px, py, pth, e, max_likelihood, n, work, PHt, K, g, Cx, priced):
    """Robot i's range scan: three scalar updates with the rows g_k of its information's factor
    G (J = Gᵀ G, tmpnav.world.lidar) times ``w`` (:func:`scan_weight`), each a pseudo-measurement
    g_k x of unit noise. Simulated from the nominal pose (px, py, pth) and the draws ``e`` (3,):
    y_k = g_k (x_nominal - mean) + e_k, or 0 in maximum-likelihood mode. Together they are the
    update with every beam of the scan, linearised at the nominal pose: the posterior depends on the beams only through
    Hᵀ R⁻¹ H and Hᵀ R⁻¹ y (docs/models.md, "Range sensor"). ``priced``: carry Cov(e, e_prev)
    ``Cx`` through them too."""
    c0 = 3 * i
    for k in range(3):
        g[0], g[1], g[2] = w * G[k, 0], w * G[k, 1], w * G[k, 2]
        if g[0] == 0.0 and g[1] == 0.0 and g[2] == 0.0:
            continue
        y = 0.0
        if not max_likelihood:
            dth = wrap_angle_scalar(pth - mean[c0 + 2])
            y = g[0] * (px - mean[c0]) + g[1] * (py - mean[c0 + 1]) + g[2] * dth + e[k]
        _update_scalar(mean, cov, g, c0, y, n, work, PHt, K)
        if priced:
            _update_cross_scalar(Cx, g, c0, K)


@nb.njit(cache=True, inline="always")
def _predict_cross(Cx, mean, u, n, dt, mid):
    """Cov(e, e_prev) through the prediction: Cx <- F Cx (F = I + E as in :func:`_predict`,
    from the mean before it moves; the motion noise is independent of the past)."""
    for i in range(n):
        phi = mean[3 * i + 2] + mid * 0.5 * u[i, 1] * dt
        v = u[i, 0]
        e0, e1 = -v * dt * math.sin(phi), v * dt * math.cos(phi)
        if e0 != 0.0 or e1 != 0.0:
            for c in range(Cx.shape[1]):
                Cx[3 * i, c] += e0 * Cx[3 * i + 2, c]
                Cx[3 * i + 1, c] += e1 * Cx[3 * i + 2, c]


@nb.njit(cache=True, inline="always")
def _update_cross(Cx, H, cols, ncols, K):
    """Cov(e, e_prev) through an update with gain K (D x 2): Cx <- (I - K H) Cx (the error after
    it is (I - K H) e - K v, its observation noise v independent of the past)."""
    for c in range(Cx.shape[1]):
        h0 = 0.0
        h1 = 0.0
        for q in range(ncols):
            h0 += H[0, cols[q]] * Cx[cols[q], c]
            h1 += H[1, cols[q]] * Cx[cols[q], c]
        for r in range(Cx.shape[0]):
            Cx[r, c] -= K[r, 0] * h0 + K[r, 1] * h1


@nb.njit(cache=True, inline="always")
def _update_cross_scalar(Cx, g, c0, K):
    """:func:`_update_cross` for a scalar pseudo-measurement g in the columns c0..c0+2."""
    for c in range(Cx.shape[1]):
        h = g[0] * Cx[c0, c] + g[1] * Cx[c0 + 1, c] + g[2] * Cx[c0 + 2, c]
        for r in range(Cx.shape[0]):
            Cx[r, c] -= K[r, 0] * h


@nb.njit(cache=True)
def _range_bearing(px, py, th, qx, qy):
    dx, dy = qx - px, qy - py
    return math.hypot(dx, dy), wrap_angle_scalar(math.atan2(dy, dx) - th), dx, dy


@nb.njit(cache=True, inline="always")
def _landmark_observation(mean, i, lx, ly, px, py, pth, e0, e1, max_likelihood, chol, H, cols, y):
    """Robot i's observation of the landmark at (lx, ly), eq. (5): its Jacobian H (in the
    columns ``cols[:3]``) and the innovation y for the update, eq. (9).

    The observation is simulated from the nominal pose (px, py, pth) and the draws
    (e0, e1) with noise ``chol`` (the Cholesky factor of Q), or is h(mean) in
    maximum-likelihood mode (no innovation).
    """
    zp_r, zp_b, dx, dy = _range_bearing(mean[3 * i], mean[3 * i + 1], mean[3 * i + 2], lx, ly)
    d2 = dx * dx + dy * dy
    dd = math.sqrt(d2)
    H[0, 3 * i] = -dx / dd
    H[0, 3 * i + 1] = -dy / dd
    H[0, 3 * i + 2] = 0.0
    H[1, 3 * i] = dy / d2
    H[1, 3 * i + 1] = -dx / d2
    H[1, 3 * i + 2] = -1.0
    cols[0], cols[1], cols[2] = 3 * i, 3 * i + 1, 3 * i + 2
    if max_likelihood:
        y[0] = 0.0
        y[1] = 0.0
    else:
        z_r, z_b, _, _ = _range_bearing(px, py, pth, lx, ly)
        z_r = z_r + (e0 * chol[0, 0] + e1 * chol[0, 1])
        z_b = wrap_angle_scalar(z_b + (e0 * chol[1, 0] + e1 * chol[1, 1]))
        y[0] = z_r - zp_r
        y[1] = wrap_angle_scalar(z_b - zp_b)


@nb.njit(cache=True, inline="always")
def _robot_observation(mean, i, j, pi, pj, e0, e1, max_likelihood, chol, H, cols, y):
    """Robot i's observation of robot j, eqs. (14), (15): H (in the columns ``cols[:5]``)
    and the innovation y for the joint update, eqs. (9), (13); simulated from the nominal
    poses ``pi`` (x, y, theta) and ``pj`` (x, y) and the draws (e0, e1) as in
    :func:`_landmark_observation`."""
    zp_r, zp_b, dx, dy = _range_bearing(mean[3 * i], mean[3 * i + 1], mean[3 * i + 2], mean[3 * j], mean[3 * j + 1])
    d2 = dx * dx + dy * dy
    dd = math.sqrt(d2)
    H[0, 3 * i] = -dx / dd
    H[0, 3 * i + 1] = -dy / dd
    H[0, 3 * i + 2] = 0.0
    H[0, 3 * j] = dx / dd
    H[0, 3 * j + 1] = dy / dd
    H[1, 3 * i] = dy / d2
    H[1, 3 * i + 1] = -dx / d2
    H[1, 3 * i + 2] = -1.0
    H[1, 3 * j] = -dy / d2
    H[1, 3 * j + 1] = dx / d2
    cols[0], cols[1], cols[2], cols[3], cols[4] = 3 * i, 3 * i + 1, 3 * i + 2, 3 * j, 3 * j + 1
    if max_likelihood:
        y[0] = 0.0
        y[1] = 0.0
    else:
        z_r, z_b, _, _ = _range_bearing(pi[0], pi[1], pi[2], pj[0], pj[1])
        z_r = z_r + (e0 * chol[0, 0] + e1 * chol[0, 1])
        z_b = wrap_angle_scalar(z_b + (e0 * chol[1, 0] + e1 * chol[1, 1]))
        y[0] = z_r - zp_r
        y[1] = wrap_angle_scalar(z_b - zp_b)


@nb.njit(cache=True, inline="always")
def _propagate_steps(c, n, ekf, motions, lm_noise, scan_noise, groups, seqs, mutual_visible, hist, scratch):
    """Steps restart[c]+1 .. horizon[c] of simulation c, each from the stored state of the
    step before: prediction, landmark updates (robot i ascending, landmark l ascending),
    range scans (robot i ascending), mutual updates (ordered pairs (i, j), i != j,
    lexicographic); then the belief and the
    running sums are stored (c_Sigma grows by trace(Sigma_i) dt while robot i moves; its
    arrival position is its mean after its own last step). Where the bound is wanted (a reach
    of more than one sector), Cov(e_t, e_{t-1}) is carried through the step, and while robot i
    moves its (p_t, X_t) are stored and its collision bound grows by min(p_1, p_0 + X_1) at
    step 1, by X_t after (tmpnav.belief.risk.move_bound)."""
    h_mean, h_cov, h_csig, h_fxy, h_mut, mean, cov, u, h_risk, h_step = hist
    work, PHt, K, H, cols, y, g, Cx, masses, qs, support, pair = scratch
    m_off, m_T, ctrl, pose, vis, stream, reach, reach_values, reach_row, scan_row, scan_table = motions  # MotionArrays
    # EKFConstants' fields
    dt, alphas, Q_lm, chol_lm, Q_mu, chol_mu, ml, landmarks, scans, thresholds, others, lvar, lrho, hz, mid = ekf
    sim, mu_noise, row0 = seqs.motions[c], groups.mutual_noise[seqs.group[c]], seqs.mutual_offset[c]
    priced = reach.shape[1] > 1
    for k in range(seqs.restart[c], seqs.horizon[c]):
        t = k + 1
        mean[:] = h_mean[k]
        cov[:, :] = h_cov[k]
        for i in range(n):  # a robot whose motion has ended waits: u = 0
            m = sim[i]
            u[i, 0] = ctrl[m_off[m] + k, 0] if k < m_T[m] else 0.0
            u[i, 1] = ctrl[m_off[m] + k, 1] if k < m_T[m] else 0.0
        if priced:  # Cov(e_t, e_{t-1}) of every robot's position starts as Sigma_{t-1}'s columns
            for i in range(n):
                for r in range(3 * n):
                    Cx[r, 2 * i] = cov[r, 3 * i]
                    Cx[r, 2 * i + 1] = cov[r, 3 * i + 1]
            _predict_cross(Cx, mean, u, n, dt, mid)
        _predict(mean, cov, u, n, dt, alphas, work, mid)
        for i in range(n):
            m = sim[i]
            row = m_off[m] + m + (t if t <= m_T[m] else m_T[m])
            for l in range(landmarks.shape[0] if others else 0):
                if vis[row, l]:
                    e0, e1 = lm_noise[stream[m], t, l, 0], lm_noise[stream[m], t, l, 1]
                    lx, ly = landmarks[l, 0], landmarks[l, 1]
                    px, py, pth = pose[row, 0], pose[row, 1], pose[row, 2]
                    _landmark_observation(mean, i, lx, ly, px, py, pth, e0, e1, ml, chol_lm, H, cols, y)
                    _update(mean, cov, H, cols, 3, y, Q_lm, n, work, PHt, K)
                    if priced:
                        _update_cross(Cx, H, cols, 3, K)
        if scans:
            for i in range(n):
                m = sim[i]
                row = m_off[m] + m + (t if t <= m_T[m] else m_T[m])
                G = scan_table[scan_row[row]]
                w = scan_weight(thresholds, u[i, 0], u[i, 1], dt)
                if w == 0.0:
                    continue  # a localiser that updates only on the move: no update standing
                e = scan_noise[stream[m], t]
                px, py, pth = pose[row, 0], pose[row, 1], pose[row, 2]
                _scan_update(mean, cov, i, G, w, px, py, pth, e, ml, n, work, PHt, K, g, Cx, priced)
        seen = False
        for i in range(n):
            for j in range(n):
                if i == j or not others or not mutual_visible[row0 + t, i, j]:
                    continue
                seen = True
                ri = m_off[sim[i]] + sim[i] + (t if t <= m_T[sim[i]] else m_T[sim[i]])
                rj = m_off[sim[j]] + sim[j] + (t if t <= m_T[sim[j]] else m_T[sim[j]])
                e0, e1 = mu_noise[t, i, j, 0], mu_noise[t, i, j, 1]
                pi, pj = (pose[ri, 0], pose[ri, 1], pose[ri, 2]), (pose[rj, 0], pose[rj, 1])
                _robot_observation(mean, i, j, pi, pj, e0, e1, ml, chol_mu, H, cols, y)
                _update(mean, cov, H, cols, 5, y, Q_mu, n, work, PHt, K)
                if priced:
                    _update_cross(Cx, H, cols, 5, K)
        h_mean[t] = mean
        h_cov[t] = cov
        h_mut[t] = h_mut[k] + (1 if seen else 0)
        for i in range(n):
            m = sim[i]
            trace = cov[3 * i, 3 * i] + cov[3 * i + 1, 3 * i + 1] + cov[3 * i + 2, 3 * i + 2]
            h_csig[t, i] = h_csig[k, i] + trace * dt if t <= m_T[m] else h_csig[k, i]
            if priced and t <= m_T[m]:
                if lvar > 0.0:  # the error relative to the walls the robot sees (risk.local_errors)
                    a, b, d, ap, bp, dp = lvar, 0.0, lvar, lvar, 0.0, lvar
                    C00, C01, C10, C11 = lrho * lvar, 0.0, 0.0, lrho * lvar
                else:
                    a, b, d = cov[3 * i, 3 * i], cov[3 * i, 3 * i + 1], cov[3 * i + 1, 3 * i + 1]
                    ap, bp, dp = h_cov[k, 3 * i, 3 * i], h_cov[k, 3 * i, 3 * i + 1], h_cov[k, 3 * i + 1, 3 * i + 1]
                    C00, C01 = Cx[3 * i, 2 * i], Cx[3 * i, 2 * i + 1]
                    C10, C11 = Cx[3 * i + 1, 2 * i], Cx[3 * i + 1, 2 * i + 1]
                row = m_off[m] + m + t
                _decode(reach, reach_values, reach_row[row - 1], pair, 0)  # the two poses' reach
                _decode(reach, reach_values, reach_row[row], pair, 1)
                p, x = _step_risk(0, ap, bp, dp, 1, a, b, d, C00, C01, C10, C11, pair, masses, qs, support)
                if hz > 0.0:  # the localiser's failures along the step driven (risk.move_bound's hazard)
                    f = hz * math.hypot(pose[row, 0] - pose[row - 1, 0], pose[row, 1] - pose[row - 1, 1])
                    p, x = min(1.0, p + f), x + f
                h_step[t, i, 0] = p
                h_step[t, i, 1] = x
                h_risk[t, i] = h_risk[k, i] + (min(p, h_step[k, i, 0] + x) if t == 1 else x)
            else:
                h_step[t, i, 0] = 0.0
                h_step[t, i, 1] = 0.0
                h_risk[t, i] = h_risk[k, i]
            arrived = t == m_T[m]
            h_fxy[t, i, 0] = mean[3 * i] if arrived else h_fxy[k, i, 0]
            h_fxy[t, i, 1] = mean[3 * i + 1] if arrived else h_fxy[k, i, 1]


@nb.njit(cache=True)
def run_sequences(n, ekf, motions, lm_noise, scan_noise, groups, seqs, mutual_visible, out):
    """Propagate the simulations ``seqs`` of n robots; see the module docstring.

    The arguments are the fields of :class:`tmpnav.belief.sequences.SequenceBatch`, which
    documents them; ``out`` holds one row per simulation for the final belief, c_Sigma per
    robot, the arrival positions and the number of steps with a mutual observation, and
    the running c_Sigma of every step when ``out.c_sigma_history`` has a row per
    simulation. Returns the history buffers (means, covariances, and each robot's (p_t, X_t)
    of the collision bound, tmpnav.belief.risk): after a call with one simulation they hold its
    whole trajectory.
    """
    D = 3 * n
    T = 0
    for c in range(seqs.horizon.shape[0]):
        T = max(T, seqs.horizon[c])
    h_mean, h_cov, h_csig = np.zeros((T + 1, D)), np.zeros((T + 1, D, D)), np.zeros((T + 1, n))
    h_fxy, h_mut = np.zeros((T + 1, n, 2)), np.zeros(T + 1, dtype=np.int64)
    h_risk, h_step = np.zeros((T + 1, n)), np.zeros((T + 1, n, 2))
    hist = (h_mean, h_cov, h_csig, h_fxy, h_mut, np.empty(D), np.empty((D, D)), np.zeros((n, 2)), h_risk, h_step)
    K = motions.reach.shape[1]
    masses, qs, pair = np.empty(K), np.empty(K), np.empty((2, K))  # pair: two poses' reach, decoded
    scratch = (
        np.empty((D, D)),
        np.empty((D, 2)),
        np.empty((D, 2)),
        np.zeros((2, D)),
        np.zeros(6, np.int64),
        np.zeros(2),
        np.zeros(3),
        np.empty((D, 2 * n)),
        masses,
        qs,
        np.empty(K),
        pair,
    )
    C = seqs.group.shape[0]
    for c in range(C):
        if seqs.restart[c] == 0:  # step 0: the group's initial belief, nothing accumulated yet
            g = seqs.group[c]
            h_mean[0, :] = groups.mean0[g]
            h_cov[0, :, :] = groups.cov0[g]
            for i in range(n):
                h_csig[0, i] = 0.0
                h_risk[0, i] = 0.0
                h_step[0, i, 0] = 0.0  # p_0, the start's step bound, where the bound is wanted
                h_step[0, i, 1] = 0.0
                if K > 1:
                    a, b, d = (
                        groups.cov0[g, 3 * i, 3 * i],
                        groups.cov0[g, 3 * i, 3 * i + 1],
                        groups.cov0[g, 3 * i + 1, 3 * i + 1],
                    )
                    if ekf.local_var > 0.0:
                        a, b, d = ekf.local_var, 0.0, ekf.local_var
                    m = seqs.motions[c, i]
                    _decode(motions.reach, motions.reach_values, motions.reach_row[motions.offset[m] + m], pair, 0)
                    h_step[0, i, 0] = _step_bound(a, b, d, pair, 0, masses, qs)[0]
                h_fxy[0, i, 0] = groups.mean0[g, 3 * i]
                h_fxy[0, i, 1] = groups.mean0[g, 3 * i + 1]
            h_mut[0] = 0
        _propagate_steps(c, n, ekf, motions, lm_noise, scan_noise, groups, seqs, mutual_visible, hist, scratch)
        h = seqs.horizon[c]
        out.mean[c] = h_mean[h]
        out.cov[c] = h_cov[h]
        out.c_sigma[c] = h_csig[h]
        out.arrival_xy[c] = h_fxy[h]
        out.mutual_steps[c] = h_mut[h]
        out.risk[c] = h_risk[h]
        if out.c_sigma_history.shape[0] == C:
            out.c_sigma_history[c, : h + 1] = h_csig[: h + 1]
    return h_mean, h_cov, h_step
