"""Kalker's creepage coefficients, and the creep forces of his linear theory saturated by
Shen-Hedrick-Elkins, as compiled kernels (one pass per contact).

``kalker_coefficients_flat(a, b, nu, table, row_shape)`` does per contact what
``kalker.kalker_coefficients`` describes (Kalker's table E.3 with CONTACT's interpolation:
linear between the rows in the shape parameter, quadratic Lagrange in 1/C through
nu = 0, 0.25, 0.5; Kalker's slender-ellipse asymptotes for g < 0.1 [Kalker 1967]) and returns
C11, C22, C23, C33 as an (N, 4) array. The numpy implementation
(``kalker._kalker_coefficients_numpy``) is the reference: the two agree to rounding
(``tests/physics/test_kalker.py``). The kernel replaces some twenty numpy passes over small
arrays: the curving equilibrium calls it for every residual evaluation, most of them one
state (MINPACK's fallback) whose cost was the passes' overhead
(``benchmarks/bench_vehicle_wear_aosta.py``). ``saturated_creep_flat`` adds the linear forces
and the saturation of ``creep.creep_forces`` (reference ``creep._creep_forces_numpy``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray


@njit(cache=True, inline="always")
def _interpolated(table: NDArray[np.float64], row: int, frac: float, j: int, w0: float,
                  w1: float, w2: float) -> float:
    """Coefficient j: linear between the table's rows, quadratic Lagrange in 1/C over nu."""
    c0 = (1.0 - frac) * table[row, j, 0] + frac * table[row + 1, j, 0]
    c1 = (1.0 - frac) * table[row, j, 1] + frac * table[row + 1, j, 1]
    c2 = (1.0 - frac) * table[row, j, 2] + frac * table[row + 1, j, 2]
    return 1.0 / (w0 / c0 + w1 / c1 + w2 / c2)


@njit(cache=True)
def kalker_coefficients_one(ai: float, bi: float, nu: float, table: NDArray[np.float64],
                            row_shape: NDArray[np.float64]
                            ) -> tuple[float, float, float, float]:
    """C11, C22, C23, C33 of one contact (``kalker_coefficients_flat``'s body)."""
    n_rows = row_shape.size
    w0 = (nu - 0.25) * (nu - 0.5) / ((0.0 - 0.25) * (0.0 - 0.5))
    w1 = (nu - 0.0) * (nu - 0.5) / ((0.25 - 0.0) * (0.25 - 0.5))
    w2 = (nu - 0.0) * (nu - 0.25) / ((0.5 - 0.0) * (0.5 - 0.25))
    k_b = 3.0 - math.log(4.0)
    a_le_b = ai <= bi
    g = ai / bi if a_le_b else bi / ai
    s = g - 1.0 if a_le_b else 1.0 - g
    s = min(max(s, row_shape[0]), row_shape[n_rows - 1])
    pos = (s - row_shape[0]) / 0.1
    row = int(math.floor(pos + 1e-9))
    row = min(max(row, 0), n_rows - 2)
    frac = min(max(pos - row, 0.0), 1.0)
    c11 = _interpolated(table, row, frac, 0, w0, w1, w2)
    c22 = _interpolated(table, row, frac, 1, w0, w1, w2)
    c23 = _interpolated(table, row, frac, 2, w0, w1, w2)
    c33 = _interpolated(table, row, frac, 3, w0, w1, w2)
    if g < 0.1:
        gg = max(g, 1e-12)
        if a_le_b:  # a << b (thin in the rolling direction)
            c11 = np.pi**2 / 4.0 / (1.0 - nu)
            c22 = np.pi**2 / 4.0
            c23 = (np.pi * math.sqrt(gg) / 3.0 / (1.0 - nu)
                   * (1.0 + nu * (math.log(16.0 / gg) - 5.0)))
        else:  # a >> b
            al = math.log(16.0 / gg**2)
            c11 = 2.0 * np.pi / (al - 2.0 * nu) / gg * (1.0 + k_b / (al - 2.0 * nu))
            den = (1.0 - nu) * al + 2.0 * nu
            c22 = 2.0 * np.pi / gg * (1.0 + (1.0 - nu) * k_b / den) / den
            c23 = 2.0 * np.pi / 3.0 / gg**1.5 / ((1.0 - nu) * al - 2.0 + 4.0 * nu)
    return c11, c22, c23, c33


@njit(cache=True)
def kalker_coefficients_flat(a: NDArray[np.float64], b: NDArray[np.float64], nu: float,
                             table: NDArray[np.float64], row_shape: NDArray[np.float64]
                             ) -> NDArray[np.float64]:
    n = a.size
    out = np.empty((n, 4))
    for i in range(n):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = kalker_coefficients_one(
            a[i], b[i], nu, table, row_shape)
    return out


@njit(cache=True)
def saturated_creep_one(xi: float, eta: float, phi_per_mm: float, a: float, b: float,
                        normal_force_n: float, mu: float, shear_modulus_mpa: float, nu: float,
                        table: NDArray[np.float64], row_shape: NDArray[np.float64]
                        ) -> tuple[float, float, float, float]:
    """Fx [N], Fy [N], Mz [N mm] and the saturation ratio of one contact
    (``saturated_creep_flat``'s body)."""
    c11, c22, c23, c33 = kalker_coefficients_one(a, b, nu, table, row_shape)
    g = shear_modulus_mpa
    ab = a * b
    fx = -g * ab * c11 * xi
    fy = -g * ab * c22 * eta - g * ab**1.5 * c23 * phi_per_mm
    mz = g * ab**1.5 * c23 * eta - g * ab**2 * c33 * phi_per_mm
    f_lin = math.hypot(fx, fy)
    limit = mu * normal_force_n
    if f_lin > 0:
        u = f_lin / limit if limit > 0 else np.inf
        if u < 3.0:
            ratio = 1.0 - u / 3.0 + u**2 / 27.0
        else:
            ratio = 1.0 / u
    else:
        ratio = 1.0 if limit > 0 else 0.0
    return ratio * fx, ratio * fy, ratio * mz, ratio


@njit(cache=True)
def saturated_creep_flat(xi: NDArray[np.float64], eta: NDArray[np.float64],
                         phi_per_mm: NDArray[np.float64], a: NDArray[np.float64],
                         b: NDArray[np.float64], normal_force_n: NDArray[np.float64],
                         mu: NDArray[np.float64], shear_modulus_mpa: float, nu: float,
                         table: NDArray[np.float64], row_shape: NDArray[np.float64]
                         ) -> NDArray[np.float64]:
    """Kalker's linear creep forces saturated by Shen-Hedrick-Elkins per contact
    (``creep.creep_forces``, whose numpy form is ``creep._creep_forces_numpy``): columns Fx [N],
    Fy [N], Mz [N mm] and the saturation ratio, shape (N, 4); 1-D inputs of one length."""
    n = a.size
    out = np.empty((n, 4))
    for i in range(n):
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = saturated_creep_one(
            xi[i], eta[i], phi_per_mm[i], a[i], b[i], normal_force_n[i], mu[i],
            shear_modulus_mpa, nu, table, row_shape)
    return out
