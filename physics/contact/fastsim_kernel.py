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

import math

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


if HAVE_NUMBA:
    from wearcast.physics.contact.kalker_kernel import kalker_coefficients_one

    @njit(cache=True, fastmath=True, error_model="numpy")
    def _march_one(xi: float, eta: float, phi_per_mm: float, a: float, b: float, f1: float,
                   f2: float, f3: float, g_peak: float, n_x: int, n_y: int,
                   spin_offset_fraction: float) -> tuple[float, float, float]:
        """The march of one patch (``march_totals``' per patch): sums P, Q and Q x - P y.
        Every strip is updated and the elements outside the ellipse are set to zero after
        the update (no branch, so the strips vectorise); the reductions may be reassociated
        (fastmath), which moves the totals by rounding only."""
        dx = 2.0 * a / n_x
        p = np.zeros(n_y)
        q = np.zeros(n_y)
        sum_p = 0.0
        sum_q = 0.0
        sum_m = 0.0
        for i in range(n_x - 1, -1, -1):
            u = (i + 0.5) / n_x * 2.0 - 1.0
            x_i = a * u
            x_spin = x_i + spin_offset_fraction * dx
            dq = -dx * (eta / f2 + phi_per_mm * x_spin / f3)
            col_q = 0.0
            for j in range(n_y):
                v = (j + 0.5) / n_y * 2.0 - 1.0
                rho2 = v * v + u * u
                inside = rho2 < 1.0
                y_j = b * v
                dp = -dx * (xi / f1 - phi_per_mm * y_j / f3)
                pk = p[j] + dp
                qk = q[j] + dq
                s = min(g_peak * (1.0 - rho2) / math.sqrt(pk * pk + qk * qk + 1e-300), 1.0)
                pn = pk * s if inside else 0.0
                qn = qk * s if inside else 0.0
                p[j] = pn
                q[j] = qn
                sum_p += pn
                col_q += qn
                sum_m -= pn * y_j
            sum_q += col_q
            sum_m += col_q * x_i
        return sum_p, sum_q, sum_m

    @njit(cache=True)
    def fastsim_totals_one(xi: float, eta: float, phi_per_mm: float, a: float, b: float,
                           normal_force_n: float, mu: float, shear_modulus_mpa: float,
                           nu: float, n_x: int, n_y: int, spin_offset_fraction: float,
                           kalker_table: NDArray[np.float64], kalker_rows: NDArray[np.float64]
                           ) -> tuple[float, float, float]:
        """FASTSIM's totals Fx, Fy [N] and Mz [N mm] of ONE patch with ``fastsim_forces``'
        defaults (parabolic bound, CONTACT's combined flexibility; ``fastsim._fastsim`` is the
        reference, same numbers to rounding): Kalker's flexibilities L1, L2, L3
        (``kalker.fastsim_flexibilities``), CONTACT's combined-flexibility rule
        (``fastsim.contact_combined_flexibilities``), the march from the leading edge. For the
        curving equilibrium's residual (``bogie_residual_kernel``), one state at a time."""
        if not normal_force_n > 0.0 or not mu > 0.0:
            return 0.0, 0.0, 0.0  # no traction bound: the march scales every traction to 0
        c11, c22, c23, _ = kalker_coefficients_one(a, b, nu, kalker_table, kalker_rows)
        g = shear_modulus_mpa
        l1 = 8.0 * a / (3.0 * c11 * g)
        l2 = 8.0 * a / (3.0 * c22 * g)
        l3 = np.pi * a * math.sqrt(a / b) / (4.0 * c23 * g)
        # CONTACT's combined flexibility
        c_xi = mu * normal_force_n / (a * b * g * c11)
        c_eta = mu * normal_force_n / (a * b * g * c22)
        num_f = xi**2 + eta**2
        den_f = c_xi**2 + c_eta**2
        if den_f > 0.0:
            f = math.sqrt(num_f / den_f)
        elif num_f > 0.0:
            f = 0.0  # +inf in numpy, set to 0 by nan_to_num(posinf=0)
        else:
            f = 0.0  # nan in numpy, set to 0
        if not math.isfinite(f):
            f = 0.0
        f = max(1e-10, f)
        w = min(1.0, f / 3.0)
        phis = phi_per_mm * (3.0 * np.pi * a / 32.0)
        num = xi**2 + eta**2 + phis**2
        den = xi**2 / l1 + eta**2 / l2 + phis**2 / l3
        lc = num / den if den > 0 else l1
        f1 = (1 - w) * l1 + w * lc
        f2 = (1 - w) * l2 + w * lc
        f3 = (1 - w) * l3 + w * lc
        dx = 2.0 * a / n_x
        dy = 2.0 * b / n_y
        peak = 2.0 * normal_force_n / (np.pi * a * b)
        sum_p, sum_q, sum_m = _march_one(xi, eta, phi_per_mm, a, b, f1, f2, f3, mu * peak,
                                         n_x, n_y, spin_offset_fraction)
        da = dx * dy
        return da * sum_p, da * sum_q, da * sum_m
else:  # pragma: no cover - exercised only without numba
    fastsim_totals_one = None  # type: ignore[assignment]
