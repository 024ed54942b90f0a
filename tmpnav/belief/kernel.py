"""The compiled fast path of the oracle: many propagations that share their prefixes.

Simulations that start from the same belief and whose first d steps are identical (the
same controls, poses, visibility and simulated noise) have identical beliefs after step
d. The oracle sends its simulations in trie order and tells, for each one, how many
leading steps it shares with the previous one; :func:`run_sequences` restarts each
simulation from the stored state of that step, so every node of the trie is computed once.

The arithmetic is that of :mod:`tmpnav.belief.batch` (paper eqs. (8), (9), (11)-(15)):
the same models, the same order of updates within a step, the Joseph-form update with an
explicit 2x2 inverse, symmetrised. The tests hold it to the filterpy reference to 1e-9.
Compiled with numba (cached on disk after the first call of a process).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

PI = math.pi
TWO_PI = 2.0 * math.pi


@nb.njit(cache=True)
def _wrap(a: float) -> float:
    if -PI <= a < PI:
        return a
    w = (a + PI) % TWO_PI - PI
    if w >= PI:
        w = -PI
    return w


@nb.njit(cache=True)
def _predict(mean, cov, u, n, dt, alphas, work):
    """Joint prediction, paper eqs. (8), (11)-(12): P = F P Fᵀ + V W Vᵀ.

    F is block-diagonal with F_i = I + E_i, where E_i has only the entries (0, 2) =
    -v dt sin(th) and (1, 2) = v dt cos(th); F P Fᵀ is therefore computed as
    (P + E P) + (P + E P) Eᵀ with a few multiplications per entry.
    """
    D = 3 * n
    for r in range(D):
        for c in range(D):
            work[r, c] = cov[r, c]
    for i in range(n):
        th = mean[3 * i + 2]
        v = u[i, 0]
        e0, e1 = -v * dt * math.sin(th), v * dt * math.cos(th)
        if e0 != 0.0 or e1 != 0.0:
            for c in range(D):  # rows 3i, 3i+1 of (I + E) P
                work[3 * i, c] += e0 * cov[3 * i + 2, c]
                work[3 * i + 1, c] += e1 * cov[3 * i + 2, c]
    for r in range(D):
        for c in range(D):
            cov[r, c] = work[r, c]
    for j in range(n):
        th = mean[3 * j + 2]
        v = u[j, 0]
        e0, e1 = -v * dt * math.sin(th), v * dt * math.cos(th)
        if e0 != 0.0 or e1 != 0.0:
            for r in range(D):  # columns 3j, 3j+1 of (...) (I + E)ᵀ
                cov[r, 3 * j] += work[r, 3 * j + 2] * e0
                cov[r, 3 * j + 1] += work[r, 3 * j + 2] * e1
    for i in range(n):
        th = mean[3 * i + 2]
        v, w = u[i, 0], u[i, 1]
        co, sn = math.cos(th), math.sin(th)
        w_v = alphas[0] * v * v + alphas[1] * w * w
        w_w = alphas[2] * v * v + alphas[3] * w * w
        # R_i = V W Vᵀ with V = [[dt c, 0], [dt s, 0], [0, dt]]
        V00, V10 = dt * co, dt * sn
        cov[3 * i, 3 * i] += V00 * w_v * V00
        cov[3 * i, 3 * i + 1] += V00 * w_v * V10
        cov[3 * i + 1, 3 * i] += V10 * w_v * V00
        cov[3 * i + 1, 3 * i + 1] += V10 * w_v * V10
        cov[3 * i + 2, 3 * i + 2] += dt * w_w * dt
        mean[3 * i] = mean[3 * i] + v * dt * co
        mean[3 * i + 1] = mean[3 * i + 1] + v * dt * sn
        mean[3 * i + 2] = _wrap(th + w * dt)


@nb.njit(cache=True)
def _update(mean, cov, H, cols, ncols, y, Q, n, work, PHt, K):
    """EKF update with a 2-D observation, paper eq. (9), in Joseph form, symmetrised.

    H (2 x D) is non-zero only in the columns ``cols[:ncols]`` (the observed robots).
    The Joseph product (I - K H) P (I - K H)ᵀ + K Q Kᵀ is evaluated as two rank-2
    corrections: M = P - K (H P), then M - (M Hᵀ) Kᵀ + K Q Kᵀ, whose upper triangle is
    mirrored (the fast path averages the two triangles; they differ by rounding only).
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
        mean[3 * i + 2] = _wrap(mean[3 * i + 2])
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


@nb.njit(cache=True)
def _range_bearing(px, py, th, qx, qy):
    dx, dy = qx - px, qy - py
    return math.hypot(dx, dy), _wrap(math.atan2(dy, dx) - th), dx, dy


@nb.njit(cache=True)
def run_sequences(
    n,
    dt,
    alphas,
    Q_lm,
    chol_lm,
    Q_mu,
    chol_mu,
    max_likelihood,
    landmarks,
    m_off,
    m_T,
    ctrl,
    pose,
    vis,
    m_stream,
    lm_noise,
    g_mean0,
    g_cov0,
    g_stream,
    mu_noise,
    c_group,
    c_motion,
    c_start,
    c_horizon,
    c_mvis_off,
    mvis,
    out_mean,
    out_cov,
    out_csig,
    out_fxy,
    out_mutual,
    out_csig_hist,
):
    """Propagate C simulations of n robots; see the module docstring.

    Motions m: steps ``ctrl[m_off[m] : m_off[m] + m_T[m]]`` (v, omega), poses and landmark
    visibility ``pose/vis[m_off[m] + m + k]`` for k = 0..m_T[m]; after its last step a robot
    waits (u = 0) where it is and keeps observing. ``lm_noise[m_stream[m], k, l]`` and
    ``mu_noise[g_stream[g], k, i, j]`` are standard-normal draws. Simulation c starts from
    the initial belief of group ``c_group[c]`` (``c_start[c]`` == 0) or from the state the
    previous simulation had after step ``c_start[c]``, and runs to step ``c_horizon[c]``;
    ``mvis[c_mvis_off[c] + k, i, j]``: robot i sees robot j at step k.
    Outputs per simulation: final joint belief, c_Sigma per robot, each robot's mean
    position at its arrival, and the number of steps with a mutual observation; if
    ``out_csig_hist`` has one row per simulation, the running c_Sigma at every step. Returns the
    history buffers (means, covariances): after a call with one simulation they hold its
    whole trajectory.
    """
    D = 3 * n
    L = landmarks.shape[0]
    T_max = 0
    for c in range(c_horizon.shape[0]):
        if c_horizon[c] > T_max:
            T_max = c_horizon[c]
    h_mean = np.zeros((T_max + 1, D))
    h_cov = np.zeros((T_max + 1, D, D))
    h_csig = np.zeros((T_max + 1, n))
    h_fxy = np.zeros((T_max + 1, n, 2))
    h_mut = np.zeros(T_max + 1, dtype=np.int64)
    mean = np.empty(D)
    cov = np.empty((D, D))
    work = np.empty((D, D))
    PHt = np.empty((D, 2))
    K = np.empty((D, 2))
    u = np.zeros((n, 2))
    H = np.zeros((2, D))
    cols = np.zeros(6, dtype=np.int64)
    y = np.zeros(2)
    for c in range(c_group.shape[0]):
        d = c_start[c]
        h = c_horizon[c]
        if d == 0:
            g = c_group[c]
            h_mean[0, :] = g_mean0[g]
            h_cov[0, :, :] = g_cov0[g]
            for i in range(n):
                h_csig[0, i] = 0.0
                h_fxy[0, i, 0] = g_mean0[g, 3 * i]
                h_fxy[0, i, 1] = g_mean0[g, 3 * i + 1]
            h_mut[0] = 0
        stream_mu = g_stream[c_group[c]]
        for k in range(d, h):
            t = k + 1
            mean[:] = h_mean[k]
            cov[:, :] = h_cov[k]
            for i in range(n):
                m = c_motion[c, i]
                if k < m_T[m]:
                    u[i, 0] = ctrl[m_off[m] + k, 0]
                    u[i, 1] = ctrl[m_off[m] + k, 1]
                else:
                    u[i, 0] = 0.0
                    u[i, 1] = 0.0
            _predict(mean, cov, u, n, dt, alphas, work)
            # landmark updates: robot by robot, landmark by landmark
            for i in range(n):
                m = c_motion[c, i]
                tt = t if t <= m_T[m] else m_T[m]
                row = m_off[m] + m + tt
                for l in range(L):
                    if not vis[row, l]:
                        continue
                    px, py, pth = pose[row, 0], pose[row, 1], pose[row, 2]
                    mx, my, mth = mean[3 * i], mean[3 * i + 1], mean[3 * i + 2]
                    zp_r, zp_b, dx, dy = _range_bearing(mx, my, mth, landmarks[l, 0], landmarks[l, 1])
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
                        z_r, z_b, _, _ = _range_bearing(px, py, pth, landmarks[l, 0], landmarks[l, 1])
                        e0 = lm_noise[m_stream[m], t, l, 0]
                        e1 = lm_noise[m_stream[m], t, l, 1]
                        z_r = z_r + (e0 * chol_lm[0, 0] + e1 * chol_lm[0, 1])
                        z_b = _wrap(z_b + (e0 * chol_lm[1, 0] + e1 * chol_lm[1, 1]))
                        y[0] = z_r - zp_r
                        y[1] = _wrap(z_b - zp_b)
                    _update(mean, cov, H, cols, 3, y, Q_lm, n, work, PHt, K)
            # mutual updates: ordered pairs (i, j), i != j, lexicographic
            seen = False
            for i in range(n):
                for j in range(n):
                    if i == j or not mvis[c_mvis_off[c] + t, i, j]:
                        continue
                    seen = True
                    mi, mj = c_motion[c, i], c_motion[c, j]
                    ri = m_off[mi] + mi + (t if t <= m_T[mi] else m_T[mi])
                    rj = m_off[mj] + mj + (t if t <= m_T[mj] else m_T[mj])
                    zp_r, zp_b, dx, dy = _range_bearing(
                        mean[3 * i], mean[3 * i + 1], mean[3 * i + 2], mean[3 * j], mean[3 * j + 1]
                    )
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
                        z_r, z_b, _, _ = _range_bearing(pose[ri, 0], pose[ri, 1], pose[ri, 2], pose[rj, 0], pose[rj, 1])
                        e0 = mu_noise[stream_mu, t, i, j, 0]
                        e1 = mu_noise[stream_mu, t, i, j, 1]
                        z_r = z_r + (e0 * chol_mu[0, 0] + e1 * chol_mu[0, 1])
                        z_b = _wrap(z_b + (e0 * chol_mu[1, 0] + e1 * chol_mu[1, 1]))
                        y[0] = z_r - zp_r
                        y[1] = _wrap(z_b - zp_b)
                    _update(mean, cov, H, cols, 5, y, Q_mu, n, work, PHt, K)
            h_mean[t] = mean
            h_cov[t] = cov
            h_mut[t] = h_mut[k] + (1 if seen else 0)
            for i in range(n):
                m = c_motion[c, i]
                if t <= m_T[m]:
                    h_csig[t, i] = (
                        h_csig[k, i] + (cov[3 * i, 3 * i] + cov[3 * i + 1, 3 * i + 1] + cov[3 * i + 2, 3 * i + 2]) * dt
                    )
                else:
                    h_csig[t, i] = h_csig[k, i]
                if t == m_T[m]:
                    h_fxy[t, i, 0] = mean[3 * i]
                    h_fxy[t, i, 1] = mean[3 * i + 1]
                else:
                    h_fxy[t, i, 0] = h_fxy[k, i, 0]
                    h_fxy[t, i, 1] = h_fxy[k, i, 1]
        out_mean[c] = h_mean[h]
        out_cov[c] = h_cov[h]
        out_csig[c] = h_csig[h]
        out_fxy[c] = h_fxy[h]
        out_mutual[c] = h_mut[h]
        if out_csig_hist.shape[0] == c_group.shape[0]:  # cumulative c_Sigma at every step, when asked
            out_csig_hist[c, : h + 1] = h_csig[: h + 1]
    return h_mean, h_cov


@nb.njit(cache=True)
def integrate_poses(start, controls, dt):
    """Nominal poses (T+1, 3) from a start pose and controls (T, 2), by paper eq. (4)."""
    T = controls.shape[0]
    out = np.empty((T + 1, 3))
    out[0] = start
    for k in range(T):
        th = out[k, 2]
        v, w = controls[k, 0], controls[k, 1]
        out[k + 1, 0] = out[k, 0] + v * dt * math.cos(th)
        out[k + 1, 1] = out[k, 1] + v * dt * math.sin(th)
        out[k + 1, 2] = _wrap(th + w * dt)
    return out


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


@nb.njit(cache=True)
def _n_steps(amount, rate, dt):
    return max(1, math.ceil(amount / (rate * dt)))


@nb.njit(cache=True)
def turn_then_drive(pts, theta0, speed, turn_rate, dt, angle_eps, length_eps):
    """Controls (T, 2), nominal poses (T+1, 3) and the step reaching each point (P,) of
    :func:`tmpnav.belief.controls.path_controls`, which documents the rule."""
    P = pts.shape[0]
    bound = 1
    for k in range(1, P):
        d = math.hypot(pts[k, 0] - pts[k - 1, 0], pts[k, 1] - pts[k - 1, 1])
        bound += _n_steps(PI, turn_rate, dt) + _n_steps(d + 1e-6, speed, dt) + 2
    controls = np.zeros((bound, 2))
    poses = np.zeros((bound + 1, 3))
    node_steps = np.zeros(P, dtype=np.int64)
    poses[0, 0], poses[0, 1], poses[0, 2] = pts[0, 0], pts[0, 1], _wrap(theta0)
    T = 0
    for k in range(1, P):
        dx, dy = pts[k, 0] - poses[T, 0], pts[k, 1] - poses[T, 1]
        length = math.hypot(dx, dy)
        if length >= length_eps:
            dtheta = _wrap(math.atan2(dy, dx) - poses[T, 2])
            if abs(dtheta) >= angle_eps:
                n = _n_steps(abs(dtheta), turn_rate, dt)
                omega = dtheta / (n * dt)
                for _ in range(n):
                    controls[T, 0], controls[T, 1] = 0.0, omega
                    th = poses[T, 2]
                    poses[T + 1, 0] = poses[T, 0] + 0.0 * dt * math.cos(th)
                    poses[T + 1, 1] = poses[T, 1] + 0.0 * dt * math.sin(th)
                    poses[T + 1, 2] = _wrap(th + omega * dt)
                    T += 1
            n = _n_steps(length, speed, dt)
            v = length / (n * dt)
            for _ in range(n):
                controls[T, 0], controls[T, 1] = v, 0.0
                th = poses[T, 2]
                poses[T + 1, 0] = poses[T, 0] + v * dt * math.cos(th)
                poses[T + 1, 1] = poses[T, 1] + v * dt * math.sin(th)
                poses[T + 1, 2] = _wrap(th + 0.0 * dt)
                T += 1
        node_steps[k] = T
    return controls[:T].copy(), poses[: T + 1].copy(), node_steps
