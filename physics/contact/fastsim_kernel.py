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
    # Layout: the normalised ellipse (``shape``) is the same for every patch, so the
    # innermost loops run over the patches of the batch: long, branch-free and independent,
    # they compile to SIMD (with error_model="numpy": no Python ZeroDivisionError check).
    # Each patch still sums in the march order (columns from the leading edge, strips in
    # order), so the totals equal the per-patch march bit for bit.  sqrt(n2 + 1e-300) makes
    # 0/0 (no traction, no bound) a scale of 1 as in the numpy march; it equals sqrt(n2) for
    # any traction above 1e-150 MPa.
    n, n_y = dpx.shape
    n_x = dpy.shape[1]
    dpx_t = np.ascontiguousarray(dpx.T)  # (n_y, n): per strip, the patches
    dpy_t = np.ascontiguousarray(dpy.T)  # (n_x, n): per column, the patches
    x_t = np.ascontiguousarray(x.T)
    y_t = np.ascontiguousarray(y.T)
    shape_t = np.ascontiguousarray(shape.T)
    p = np.zeros((n_y, n))
    q = np.zeros((n_y, n))
    sum_p = np.zeros(n)
    sum_q = np.zeros(n)
    sum_m = np.zeros(n)
    col_q = np.empty(n)
    for i in range(n_x - 1, -1, -1):
        col_q[:] = 0.0
        dq = dpy_t[i]
        for j in range(n_y):
            bound = shape_t[i, j]
            p_j = p[j]
            q_j = q[j]
            if bound > 0.0:
                dp = dpx_t[j]
                for k in range(n):
                    pk = p_j[k] + dp[k]
                    qk = q_j[k] + dq[k]
                    s = min(g_peak[k] * bound / np.sqrt(pk * pk + qk * qk + 1e-300), 1.0)
                    p_j[k] = pk * s
                    q_j[k] = qk * s
                # separate loops: fewer arrays written per loop, so it still vectorises
                for k in range(n):
                    sum_p[k] += p_j[k]
                    col_q[k] += q_j[k]
                y_j = y_t[j]
                for k in range(n):
                    sum_m[k] -= p_j[k] * y_j[k]
            else:  # outside the ellipse (no bound): the traction is reset to zero
                p_j[:] = 0.0
                q_j[:] = 0.0
        x_i = x_t[i]
        for k in range(n):
            sum_q[k] += col_q[k]
            sum_m[k] += col_q[k] * x_i[k]
    return sum_p, sum_q, sum_m


march_totals = njit(cache=True, fastmath=True, error_model="numpy")(_march_totals_py) \
    if HAVE_NUMBA else None
