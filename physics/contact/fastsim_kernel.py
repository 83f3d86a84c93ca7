"""The FASTSIM march (Kalker 1982) as a compiled kernel that only sums (``fastsim_forces``).

``march_totals(dpx, dpy, shape, g_peak, x, y)`` marches every strip of every patch from the
leading edge (largest x) towards the trailing edge: the adhesion trial traction is the
previous element's traction plus the increments (``dpx`` per strip, ``dpy`` per column), and
where its magnitude exceeds the traction bound g = g_peak * shape it is scaled back onto the
bound (scale = min(g / |p|, 1); 1 where there is neither traction nor bound).  It returns
sum P, sum Q and sum (Q x - P y) per patch (forces and spin moment over dx dy) without
storing the traction fields, whose memory traffic costs more than the march itself.

Compiled with numba (a dependency); without numba ``march_totals`` is None and
``fastsim_forces`` uses the vectorised numpy march of ``fastsim`` (the reference
implementation, same numbers to rounding).  ``benchmarks/bench_fastsim.py`` prints both.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

try:  # numba is a declared dependency; the numpy march in fastsim is the fallback
    from numba import njit
    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    HAVE_NUMBA = False


def _march_totals_py(dpx: NDArray[np.float64], dpy: NDArray[np.float64],
                     shape: NDArray[np.float64], g_peak: NDArray[np.float64],
                     x: NDArray[np.float64], y: NDArray[np.float64]
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    # Layout: the innermost loop runs over the independent strips, branch-free, so that it
    # vectorises.  sqrt(n2 + 1e-300) makes 0/0 (no traction, no bound) a scale of 1 as in
    # the numpy march; it equals sqrt(n2) for any traction above 1e-150 MPa.
    n, n_y = dpx.shape
    n_x = dpy.shape[1]
    sum_p = np.zeros(n)
    sum_q = np.zeros(n)
    sum_m = np.zeros(n)
    shape_t = np.ascontiguousarray(shape.T)
    p = np.empty(n_y)
    q = np.empty(n_y)
    # per column the strips inside the ellipse (bound > 0): outside, the traction is reset to
    # zero (scale g / |p| = 0) without computing it
    j_lo = np.zeros(n_x, dtype=np.int64)
    j_hi = np.zeros(n_x, dtype=np.int64)
    for i in range(n_x):
        first = n_y
        last = -1
        for j in range(n_y):
            if shape_t[i, j] > 0.0:
                if first == n_y:
                    first = j
                last = j
        j_lo[i] = first
        j_hi[i] = last + 1 if last >= 0 else first
    for k in range(n):
        gk = g_peak[k]
        p[:] = 0.0
        q[:] = 0.0
        sp = 0.0
        sq = 0.0
        sm = 0.0
        for i in range(n_x - 1, -1, -1):
            dq = dpy[k, i]
            col_q = 0.0
            lo = j_lo[i]
            hi = j_hi[i]
            for j in range(lo):
                p[j] = 0.0
                q[j] = 0.0
            for j in range(hi, n_y):
                p[j] = 0.0
                q[j] = 0.0
            for j in range(lo, hi):
                pj = p[j] + dpx[k, j]
                qj = q[j] + dq
                s = min(gk * shape_t[i, j] / np.sqrt(pj * pj + qj * qj + 1e-300), 1.0)
                pj *= s
                qj *= s
                p[j] = pj
                q[j] = qj
                sp += pj
                col_q += qj
                sm -= pj * y[k, j]
            sq += col_q
            sm += col_q * x[k, i]
        sum_p[k] = sp
        sum_q[k] = sq
        sum_m[k] = sm
    return sum_p, sum_q, sum_m


march_totals = njit(cache=True, fastmath=True)(_march_totals_py) if HAVE_NUMBA else None
