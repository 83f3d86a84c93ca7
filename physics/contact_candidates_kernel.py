"""Contact candidates of the curving model's gap table as a compiled kernel.

``candidate_slots(gap, gap2, smoothing, grid0, step, wheel_y, shifts, n_slots, prominence,
separation, share, no_contact, fade)`` does per query shift what
``curving_table.ContactTable.candidates`` describes: the gap row interpolated linearly between
the two table rows around the shift, its local minima, each refined by a parabola (its
curvature interpolated so that the gap stays continuous where the grid minimum moves,
``_refine``), with the smoothing correction -g'' sigma^2 / 2; their gaps above the deepest
minimum; their weights
(maturity from the prominence over the adjacent maxima, soft sharing with the candidates they
are merged with); the slots ordered field side first (largest wheel y; missing candidates
last). Returns wheel y [mm], gap [mm], g'' [1/mm] and weight, each (N, n_slots).

Which minima get a slot (the selection rule)
--------------------------------------------
``N_SLOTS`` slots per wheel, the one slot count of the curving model (the bogie residual, the
curving result, the pipeline's contacts and the wear tables' contact frames): six. The
Minuetto's wheels worn by the loop (every trip forward on the example fleet's Aosta route,
D_step 0.8 mm) show up to four gap minima in one row at 2,000-4,000 km and five at 8,000 km
(wheel y 11-35 mm, the wheelset shifted ~9-10 mm towards the other rail); six slots hold them
all with one to spare. With three slots a loaded minimum was dropped whenever a deeper one
overtook it, and the bogie residual jumped by ~0.27 wheel loads (README, stop 25).
When a row has more minima than slots, they are ranked by the key

    key_k = g_k + (1 - m_k) * no_contact,

the gap g_k at the minimum's grid point plus no_contact [mm] times its immaturity (maturity
m_k in [0, 1] from the prominence, below): the deepest mature minima are kept, a minimum being
born or dying (m_k -> 0) ranks after every mature one. The ``n_slots`` lowest keys get a slot
(ties to the lower index), and each kept minimum's maturity is multiplied by a fade

    f_k = smoothstep((key_excl - key_k) / fade),

key_excl the lowest key left without a slot (f_k = 1 when every minimum has a slot). A kept
minimum whose key approaches the best excluded one fades out as that one would fade in: when
the two exchange ranks both have weight 0, so the weights -- and the normal forces and the
bogie residual built from them -- are continuous in the shift whatever the number of minima.
The fade acts on a loaded minimum only when more than ``n_slots`` minima lie within the load's
approach (plus ``fade``) of the deepest, that is more than ``n_slots`` patches at once on one
wheel; otherwise no minimum that can carry load loses weight. The gaps are measured from the
deepest minimum of the whole row (selected or not), so the approach the equilibrium solves
for keeps its meaning when the selection changes.

The numpy implementation (``curving_table.ContactTable._candidate_slots_numpy``) is the
reference: the two agree to rounding at every slot count (``tests/physics/test_curving.py``,
``tests/physics/test_contact_slots.py``, which also checks the continuity); the kernel avoids
building (N, n_y) arrays for every query, which was 56-59 % of a curve-radius table's time
(``benchmarks/bench_wear_tables.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

#: Contact candidate (patch) slots per wheel, field side first: the one slot count of the
#: curving table's candidates, the bogie residual, the curving result and the pipeline's
#: contacts. The selection rule when a gap row has more minima: module docstring.
N_SLOTS = 6


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
                    no_contact_mm: float, fade_mm: float
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
                  prominence_mm, separation_mm, share_mm, no_contact_mm, fade_mm, g, work,
                  out_y[q], out_gap[q], out_g2[q], out_w[q])
    return out_y, out_gap, out_g2, out_w


@njit(cache=True)
def slot_workspace(n_slots: int) -> NDArray[np.float64]:
    """Work space of :func:`slots_one` for n_slots candidates."""
    return np.empty(9 * n_slots + 2 + n_slots * n_slots)


@njit(cache=True)
def _maturity(g: NDArray[np.float64], i: int, prominence_mm: float) -> float:
    """Maturity of the minimum at i: smoothstep of its prominence (rise to the lower of the
    two adjacent maxima, the row's ends counting as maxima) over prominence_mm."""
    n_y = g.shape[0]
    left = i
    while left > 0 and not (g[left] >= g[left - 1] and g[left] > g[left + 1]):
        left -= 1
    right = i
    while right < n_y - 1 and not (g[right] >= g[right - 1] and g[right] > g[right + 1]):
        right += 1
    return _smoothstep((min(g[left], g[right]) - g[i]) / prominence_mm)


@njit(cache=True)
def _refine(g: NDArray[np.float64], gap2: NDArray[np.float64],
            smoothing: NDArray[np.float64], wheel_y: NDArray[np.float64], k: int, w: float,
            i: int) -> tuple[float, float, float]:
    """The minimum at i refined by a parabola: wheel y [mm], g'' there [1/mm] and the gap with
    the smoothing correction -g'' sigma^2 / 2 [mm].

    The parabola through i - 1, i, i + 1 puts the minimum at frac = (g[i-1] - g[i+1]) / (2 D)
    grid steps from i, D = g[i-1] - 2 g[i] + g[i+1], its gap g[i] - D frac^2 / 2. D is
    interpolated between i and the neighbour j on the minimum's side, like g'': where the
    grid minimum moves from i to j (frac = +-1/2 on both sides) both give the same gap, so the
    candidate's gap is continuous in the shift (the vertex of either parabola alone jumps by a
    third difference / 8, up to 5e-5 mm on a flange root)."""
    n_y = g.shape[0]
    gm, gz, gp = g[i - 1], g[i], g[i + 1]
    den = gm - 2.0 * gz + gp
    frac = 0.5 * (gm - gp) / den if den > 0 else 0.0
    if frac < -0.5:
        frac = -0.5
    elif frac > 0.5:
        frac = 0.5
    yc = wheel_y[i] + frac * (wheel_y[1] - wheel_y[0])
    jj = i + 1 if frac >= 0.0 else i - 1
    f = abs(frac)
    r_i = (1.0 - w) * gap2[k, i] + w * gap2[k + 1, i]
    r_j = (1.0 - w) * gap2[k, jj] + w * gap2[k + 1, jj]
    g2 = (1.0 - f) * r_i + f * r_j
    den_j = g[jj - 1] - 2.0 * g[jj] + g[jj + 1] if 0 < jj < n_y - 1 else den
    den_eff = (1.0 - f) * den + f * den_j
    return yc, g2, gz - 0.5 * den_eff * frac * frac - 0.5 * g2 * smoothing[i] ** 2


@njit(cache=True)
def slots_one(gap: NDArray[np.float64], gap2: NDArray[np.float64],
              smoothing: NDArray[np.float64], grid0: float, step: float,
              wheel_y: NDArray[np.float64], shift: float, n_slots: int, prominence_mm: float,
              separation_mm: float, share_mm: float, no_contact_mm: float, fade_mm: float,
              g: NDArray[np.float64], work: NDArray[np.float64], out_y: NDArray[np.float64],
              out_gap: NDArray[np.float64], out_g2: NDArray[np.float64],
              out_w: NDArray[np.float64]) -> None:
    """The candidate slots of one shift into out_y, out_gap, out_g2, out_w (n_slots,) each;
    ``g`` (n_y,) and ``work`` (:func:`slot_workspace`) are work space (the interpolated gap
    row; the candidates' values)."""
    n_rows, n_y = gap.shape
    ns = n_slots
    yc = work[0:ns]
    gc = work[ns:2 * ns]
    g0 = work[2 * ns:3 * ns]
    g2v = work[3 * ns:4 * ns]
    mat = work[4 * ns:5 * ns]
    gapv = work[5 * ns:6 * ns]
    weight = work[6 * ns:7 * ns]
    key = work[7 * ns:8 * ns + 1]  # the n_slots + 1 lowest keys, sorted
    idx_f = work[8 * ns + 1:9 * ns + 2]  # their indices (exact in float64)
    merged = work[9 * ns + 2:9 * ns + 2 + ns * ns].reshape((ns, ns))
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
    # every interior minimum: the deepest refined gap (the gaps' origin), and the n_slots + 1
    # lowest keys g + (1 - maturity) no_contact, ties to the lower index (what a repeated
    # argmin picks), kept sorted by (key, index) in one pass
    cap = ns + 1
    n_min = 0
    best_gc = np.inf
    for j in range(1, n_y - 1):
        v = g[j]
        if not (v < g[j - 1] and v <= g[j + 1]):
            continue
        _, _, gcj = _refine(g, gap2, smoothing, wheel_y, k, w, j)
        if gcj < best_gc:
            best_gc = gcj
        kv = v + (1.0 - _maturity(g, j, prominence_mm)) * no_contact_mm
        if n_min < cap:
            t = n_min
        elif kv < key[cap - 1]:
            t = cap - 1
        else:
            n_min += 1
            continue
        n_min += 1
        while t > 0 and kv < key[t - 1]:
            key[t] = key[t - 1]
            idx_f[t] = idx_f[t - 1]
            t -= 1
        key[t] = kv
        idx_f[t] = j
    n_found = min(n_min, ns)
    key_excl = key[ns] if n_min > ns else np.inf
    for s in range(n_slots):
        # a missing candidate takes the first interior point's columns (finite, unused)
        i = int(idx_f[s]) if s < n_found else 1
        yc[s], g2v[s], gc[s] = _refine(g, gap2, smoothing, wheel_y, k, w, i)
        if s >= n_found:
            # no maturity (no prominence to search), no weight, a large gap
            g0[s] = g[i]
            mat[s] = 0.0
            gapv[s] = no_contact_mm
            continue
        g0[s] = g[i]
        gapv[s] = gc[s] - best_gc
        # the maturity faded by the rank (module docstring): 0 where this minimum and the best
        # excluded one exchange their slot
        mat[s] = _maturity(g, i, prominence_mm) * _smoothstep((key_excl - key[s]) / fade_mm)
    for p in range(n_slots):
        merged[p, p] = 0.0
        for r in range(p + 1, n_slots):
            if p >= n_found or r >= n_found:
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
        for r in range(n_found):
            diff = gapv[r] - gapv[s]
            if diff < -50.0 * share_mm:
                diff = -50.0 * share_mm
            others += merged[s, r] * mat[r] * np.exp(-diff / share_mm)
        weight[s] = mat[s] / (1e-9 + mat[s] + others)
    # field side first (largest y), missing candidates last, stable (insertion sort of the
    # slot numbers on the key, in key[])
    for s in range(n_slots):
        key[s] = yc[s] if s < n_found else -np.inf
        idx_f[s] = s
    for s in range(1, n_slots):
        kv = key[s]
        num = idx_f[s]
        t = s
        while t > 0 and key[t - 1] < kv:
            key[t] = key[t - 1]
            idx_f[t] = idx_f[t - 1]
            t -= 1
        key[t] = kv
        idx_f[t] = num
    for t in range(n_slots):
        s = int(idx_f[t])
        out_y[t] = yc[s]
        out_gap[t] = gapv[s]
        out_g2[t] = g2v[s]
        out_w[t] = weight[s]
