"""Contact candidates of the curving model's gap table as a compiled kernel.

``candidate_slots(gap, gap2, smoothing, grid0, step, wheel_y, shifts, n_slots, prominence,
separation, share, no_contact)`` does per query shift what ``curving.ContactTable.candidates``
describes: the gap row interpolated linearly between the two table rows around the shift, its
local minima (the ``n_slots`` deepest, ties to the lower index), each refined by a parabola,
with the smoothing correction -g'' sigma^2 / 2; their gaps above the best one; their weights
(maturity from the prominence over the adjacent maxima, soft sharing with the candidates they
are merged with); the slots ordered field side first (largest wheel y; missing candidates
last). Returns wheel y [mm], gap [mm], g'' [1/mm] and weight, each (N, n_slots).

The numpy implementation (``curving_table.ContactTable._candidate_slots_numpy``) is the
reference: the two agree to rounding (``tests/physics/test_curving.py``); the kernel avoids
building (N, n_y) arrays for every query, which was 56-59 % of a curve-radius table's time
(``benchmarks/bench_wear_tables.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray


@njit(cache=True, inline="always")
def _smoothstep(x: float) -> float:
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    return x * x * (3.0 - 2.0 * x)


@njit(cache=True)
def candidate_slots(gap: NDArray[np.float64], gap2: NDArray[np.float64],
                    smoothing: NDArray[np.float64], grid0: float, step: float,
                    wheel_y: NDArray[np.float64], shifts: NDArray[np.float64], n_slots: int,
                    prominence_mm: float, separation_mm: float, share_mm: float,
                    no_contact_mm: float
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
                               NDArray[np.float64]]:
    n = shifts.shape[0]
    out_y = np.empty((n, n_slots))
    out_gap = np.empty((n, n_slots))
    out_g2 = np.empty((n, n_slots))
    out_w = np.empty((n, n_slots))
    g = np.empty(gap.shape[1])
    work = slot_workspace(n_slots)
    for q in range(n):
        slots_one(gap, gap2, smoothing, grid0, step, wheel_y, shifts[q], n_slots,
                  prominence_mm, separation_mm, share_mm, no_contact_mm, g, work, out_y[q],
                  out_gap[q], out_g2[q], out_w[q])
    return out_y, out_gap, out_g2, out_w


@njit(cache=True)
def slot_workspace(n_slots: int) -> NDArray[np.float64]:
    """Work space of :func:`slots_one` for n_slots candidates."""
    return np.empty(10 * n_slots + n_slots * n_slots)


@njit(cache=True)
def slots_one(gap: NDArray[np.float64], gap2: NDArray[np.float64],
              smoothing: NDArray[np.float64], grid0: float, step: float,
              wheel_y: NDArray[np.float64], shift: float, n_slots: int, prominence_mm: float,
              separation_mm: float, share_mm: float, no_contact_mm: float,
              g: NDArray[np.float64], work: NDArray[np.float64], out_y: NDArray[np.float64],
              out_gap: NDArray[np.float64], out_g2: NDArray[np.float64],
              out_w: NDArray[np.float64]) -> None:
    """The candidate slots of one shift into out_y, out_gap, out_g2, out_w (n_slots,) each;
    ``g`` (n_y,) and ``work`` (:func:`slot_workspace`) are work space (the interpolated gap
    row; the candidates' values)."""
    n_rows, n_y = gap.shape
    dy = wheel_y[1] - wheel_y[0]
    ns = n_slots
    yc = work[0:ns]
    gc = work[ns:2 * ns]
    g0 = work[2 * ns:3 * ns]
    g2v = work[3 * ns:4 * ns]
    mat = work[4 * ns:5 * ns]
    gapv = work[5 * ns:6 * ns]
    weight = work[6 * ns:7 * ns]
    best_v = work[7 * ns:8 * ns]
    idx_f = work[8 * ns:9 * ns]  # candidate indices (exact in float64)
    found_f = work[9 * ns:10 * ns]  # 1.0 found, 0.0 missing
    merged = work[10 * ns:10 * ns + ns * ns].reshape((ns, ns))
    pos = (shift - grid0) / step
    if pos < 0.0:
        pos = 0.0
    hi_pos = n_rows - 1.000001
    if pos > hi_pos:
        pos = hi_pos
    k = int(np.floor(pos))
    w = pos - k
    for j in range(n_y):
        g[j] = (1.0 - w) * gap[k, j] + w * gap[k + 1, j]
    # the n_slots deepest interior minima, ties to the lower index (what a repeated argmin
    # picks): one pass keeping them sorted by (gap, index)
    n_found = 0
    for j in range(1, n_y - 1):
        v = g[j]
        if v < g[j - 1] and v <= g[j + 1]:
            if n_found < n_slots:
                t = n_found
                n_found += 1
            elif v < best_v[n_slots - 1]:
                t = n_slots - 1
            else:
                continue
            while t > 0 and v < best_v[t - 1]:
                best_v[t] = best_v[t - 1]
                idx_f[t] = idx_f[t - 1]
                t -= 1
            best_v[t] = v
            idx_f[t] = j
    for s in range(n_slots):
        found_f[s] = 1.0 if s < n_found else 0.0
        if s >= n_found:
            idx_f[s] = 1
    best_gc = np.inf
    for s in range(n_slots):
        i = int(idx_f[s])
        gm, gz, gp = g[i - 1], g[i], g[i + 1]
        den = gm - 2.0 * gz + gp
        frac = 0.5 * (gm - gp) / den if den > 0 else 0.0
        if frac < -0.5:
            frac = -0.5
        elif frac > 0.5:
            frac = 0.5
        yc[s] = wheel_y[i] + frac * dy
        jj = i + 1 if frac >= 0.0 else i - 1
        f = abs(frac)
        r_i = (1.0 - w) * gap2[k, i] + w * gap2[k + 1, i]
        r_j = (1.0 - w) * gap2[k, jj] + w * gap2[k + 1, jj]
        g2v[s] = (1.0 - f) * r_i + f * r_j
        g0[s] = gz
        gc[s] = gz - 0.25 * (gm - gp) * frac - 0.5 * g2v[s] * smoothing[i] ** 2
        if s >= n_found:
            gc[s] = np.inf
        if gc[s] < best_gc:
            best_gc = gc[s]
    for s in range(n_slots):
        gapv[s] = gc[s] - best_gc if s < n_found else no_contact_mm
        if s >= n_found:
            mat[s] = 0.0  # a missing candidate has no maturity (no prominence to search)
            continue
        # prominence: rise to the lower of the two adjacent maxima (ends count as maxima)
        i = int(idx_f[s])
        left = i
        while left > 0 and not (g[left] >= g[left - 1] and g[left] > g[left + 1]):
            left -= 1
        right = i
        while right < n_y - 1 and not (g[right] >= g[right - 1] and g[right] > g[right + 1]):
            right += 1
        prom = min(g[left], g[right]) - g0[s]
        mat[s] = _smoothstep(prom / prominence_mm)
    for p in range(n_slots):
        merged[p, p] = 0.0
        for r in range(p + 1, n_slots):
            if r >= n_found:
                # a missing candidate has no maturity and no weight: its merging never enters
                # a weight (m_r c_kr = 0), so its barrier is not searched
                merged[p, r] = 0.0
                merged[r, p] = 0.0
                continue
            lo = int(min(idx_f[p], idx_f[r]))
            hi = int(max(idx_f[p], idx_f[r]))
            barrier = -np.inf
            for j in range(lo, hi + 1):
                if g[j] > barrier:
                    barrier = g[j]
            m = 1.0 - _smoothstep((barrier - max(g0[p], g0[r])) / separation_mm)
            merged[p, r] = m
            merged[r, p] = m
    for s in range(n_slots):
        if s >= n_found:
            weight[s] = 0.0
            continue
        others = 0.0
        for r in range(n_slots):
            diff = gapv[r] - gapv[s]
            if diff < -50.0 * share_mm:
                diff = -50.0 * share_mm
            others += merged[s, r] * mat[r] * np.exp(-diff / share_mm)
        weight[s] = mat[s] / (1e-9 + mat[s] + others)
    # field side first (largest y), missing candidates last, stable (insertion sort of the
    # slot numbers on the key, in best_v)
    for s in range(n_slots):
        best_v[s] = yc[s] if s < n_found else -np.inf
        idx_f[s] = s
    for s in range(1, n_slots):
        key = best_v[s]
        num = idx_f[s]
        t = s
        while t > 0 and best_v[t - 1] < key:
            best_v[t] = best_v[t - 1]
            idx_f[t] = idx_f[t - 1]
            t -= 1
        best_v[t] = key
        idx_f[t] = num
    for t in range(n_slots):
        s = int(idx_f[t])
        out_y[t] = yc[s]
        out_gap[t] = gapv[s]
        out_g2[t] = g2v[s]
        out_w[t] = weight[s]
