"""Kalker's linear theory of rolling contact: creepage coefficients C11, C22, C23, C33.

The table is Kalker's table E.3 (C11, C22, C23 for Poisson's ratio 0, 0.25, 0.5), as held in
CONTACT's ``linrol`` (E.A.H. Vollebregt, Apache-2.0), plus C33 from a second public table;
both from [Kalker 1967] (see docs/references.md).
One deliberate difference from CONTACT's source: for a/b = 0.8, nu = 0.25 CONTACT holds
C23 = 1.15, which breaks the monotone column; Kalker's printed value 1.25 is used here.

Interpolation follows CONTACT's rules:

* rows: linear in g = a/b (a <= b) or g = b/a (a > b) between the tabulated rows 0.1 ... 1.0;
* Poisson's ratio: quadratic (Lagrange) in 1/C through nu = 0, 0.25, 0.5.

Outside the table (g < 0.1) C11, C22 and C23 follow Kalker's asymptotic expressions for very
slender ellipses, exactly as CONTACT does; C33, for which no asymptote is implemented, is held
at its g = 0.1 row value. Poisson's ratios outside [0, 0.5] are refused.

Linear creep forces (README; Kalker 1967, seed 000 §III):
Fx = -G a b C11 xi;  Fy = -G a b C22 eta - G (ab)^1.5 C23 phi;
Mz = G (ab)^1.5 C23 eta - G (ab)^2 C33 phi.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.kalker_kernel import kalker_coefficients_flat

# Rows in order of increasing "shape parameter" s: s = g - 1 in [-0.9, 0] for a <= b
# (g = a/b = 0.1 ... 1.0), s = 1 - g in (0, 0.9] for a > b (g = b/a = 0.9 ... 0.1).
# Columns per coefficient: nu = 0, 0.25, 0.5.
_TABLE_A_LE_B = np.array(
    [
        # C11 (3)            C22 (3)             C23 (3)               C33 (3)
        [2.51, 3.31, 4.85, 2.51, 2.52, 2.53, 0.334, 0.473, 0.731, 6.42, 8.28, 11.7],
        [2.59, 3.37, 4.81, 2.59, 2.63, 2.66, 0.483, 0.603, 0.809, 3.46, 4.27, 5.66],
        [2.68, 3.44, 4.80, 2.68, 2.75, 2.81, 0.607, 0.715, 0.889, 2.49, 2.96, 3.72],
        [2.78, 3.53, 4.82, 2.78, 2.88, 2.98, 0.720, 0.823, 0.977, 2.02, 2.32, 2.77],
        [2.88, 3.62, 4.83, 2.88, 3.01, 3.14, 0.827, 0.929, 1.07, 1.74, 1.93, 2.22],
        [2.98, 3.72, 4.91, 2.98, 3.14, 3.31, 0.930, 1.03, 1.18, 1.56, 1.68, 1.86],
        [3.09, 3.81, 4.97, 3.09, 3.28, 3.48, 1.03, 1.14, 1.29, 1.43, 1.50, 1.60],
        [3.19, 3.91, 5.05, 3.19, 3.41, 3.65, 1.13, 1.25, 1.40, 1.34, 1.37, 1.42],
        [3.29, 4.01, 5.12, 3.29, 3.54, 3.82, 1.23, 1.36, 1.51, 1.27, 1.27, 1.27],
        [3.40, 4.12, 5.20, 3.40, 3.67, 3.98, 1.33, 1.47, 1.63, 1.21, 1.19, 1.16],
    ]
)
_TABLE_A_GT_B = np.array(
    [
        # b/a = 0.9 ... 0.1
        [3.51, 4.22, 5.30, 3.51, 3.81, 4.16, 1.44, 1.59, 1.77, 1.16, 1.11, 1.06],
        [3.65, 4.36, 5.42, 3.65, 3.99, 4.39, 1.58, 1.75, 1.94, 1.10, 1.04, 0.95],
        [3.82, 4.54, 5.58, 3.82, 4.21, 4.67, 1.76, 1.95, 2.18, 1.05, 0.97, 0.85],
        [4.06, 4.78, 5.80, 4.06, 4.50, 5.04, 2.01, 2.23, 2.50, 1.01, 0.89, 0.75],
        [4.37, 5.10, 6.11, 4.37, 4.90, 5.56, 2.35, 2.62, 2.96, 0.96, 0.82, 0.65],
        [4.84, 5.57, 6.57, 4.84, 5.48, 6.31, 2.88, 3.24, 3.70, 0.91, 0.75, 0.55],
        [5.57, 6.34, 7.34, 5.57, 6.40, 7.51, 3.79, 4.32, 5.01, 0.87, 0.67, 0.45],
        [6.96, 7.78, 8.82, 6.96, 8.14, 9.79, 5.72, 6.63, 7.89, 0.83, 0.60, 0.34],
        [10.7, 11.7, 12.9, 10.7, 12.8, 16.0, 12.2, 14.6, 18.0, 0.80, 0.53, 0.23],
    ]
)
#: The whole table, shape (19 rows, 4 coefficients, 3 Poisson ratios).
KALKER_TABLE = np.concatenate([_TABLE_A_LE_B, _TABLE_A_GT_B]).reshape(19, 4, 3)
#: Shape parameter of each row: g - 1 for a <= b, 1 - g for a > b (monotone, -0.9 ... 0.9).
KALKER_ROW_SHAPE = np.concatenate([np.linspace(0.1, 1.0, 10) - 1.0, 1.0 - np.linspace(0.9, 0.1, 9)])
#: Poisson ratios of the table columns.
KALKER_NU = (0.0, 0.25, 0.5)


@dataclass(frozen=True)
class KalkerCoefficients:
    """Kalker's linear-theory creepage coefficients (dimensionless), arrays of one shape."""

    c11: NDArray[np.float64]
    c22: NDArray[np.float64]
    c23: NDArray[np.float64]
    c33: NDArray[np.float64]


def _asymptotes(g: NDArray[np.float64], a_le_b: NDArray[np.bool_], nu: float):
    """Kalker's slender-ellipse asymptotes (g -> 0) for C11, C22, C23, as used in CONTACT."""
    g = np.clip(g, 1e-12, None)
    # a << b (thin in the rolling direction)
    c11_a = np.full_like(g, np.pi**2 / 4.0 / (1.0 - nu))
    c22_a = np.full_like(g, np.pi**2 / 4.0)
    c23_a = np.pi * np.sqrt(g) / 3.0 / (1.0 - nu) * (1.0 + nu * (np.log(16.0 / g) - 5.0))
    # a >> b
    al = np.log(16.0 / g**2)
    k = 3.0 - np.log(4.0)
    c11_b = 2.0 * np.pi / (al - 2.0 * nu) / g * (1.0 + k / (al - 2.0 * nu))
    den = (1.0 - nu) * al + 2.0 * nu
    c22_b = 2.0 * np.pi / g * (1.0 + (1.0 - nu) * k / den) / den
    c23_b = 2.0 * np.pi / 3.0 / g**1.5 / ((1.0 - nu) * al - 2.0 + 4.0 * nu)
    return (
        np.where(a_le_b, c11_a, c11_b),
        np.where(a_le_b, c22_a, c22_b),
        np.where(a_le_b, c23_a, c23_b),
    )


def kalker_coefficients(a_mm: ArrayLike, b_mm: ArrayLike, poisson: float = 0.28
                        ) -> KalkerCoefficients:
    """Kalker's C11, C22, C23, C33 for an elliptic contact with semi-axes a, b.

    Parameters
    ----------
    a_mm : semi-axis in the rolling direction [mm] (or any length unit; only a/b matters)
    b_mm : lateral semi-axis [mm]
    poisson : Poisson's ratio of the (common) material, 0 <= nu <= 0.5

    Returns
    -------
    KalkerCoefficients, broadcast over a and b.

    Kalker's table E.3 with CONTACT's interpolation (module docstring), evaluated by the
    compiled kernel ``kalker_kernel.kalker_coefficients_flat`` (``_kalker_coefficients_numpy``
    is its numpy reference).
    """
    a, b = _checked_semi_axes(a_mm, b_mm, poisson)
    c = kalker_coefficients_flat(np.ascontiguousarray(a.reshape(-1)),
                                 np.ascontiguousarray(b.reshape(-1)), float(poisson),
                                 KALKER_TABLE, KALKER_ROW_SHAPE)
    c11, c22, c23, c33 = (c[:, i].reshape(a.shape) for i in range(4))
    return KalkerCoefficients(c11=c11, c22=c22, c23=c23, c33=c33)


def _checked_semi_axes(a_mm: ArrayLike, b_mm: ArrayLike, poisson: float
                       ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """a, b as float arrays broadcast together; refuses nu outside [0, 0.5] and a, b <= 0."""
    if not 0.0 <= poisson <= 0.5:
        raise ValueError(f"poisson must lie in [0, 0.5] for Kalker's table, got {poisson}")
    a = np.asarray(a_mm, dtype=float)
    b = np.asarray(b_mm, dtype=float)
    if np.any(a <= 0) or np.any(b <= 0):
        raise ValueError("semi-axes a_mm and b_mm must be positive")
    a, b = np.broadcast_arrays(a, b)
    return a, b


def _kalker_coefficients_numpy(a_mm: ArrayLike, b_mm: ArrayLike, poisson: float = 0.28
                               ) -> KalkerCoefficients:
    """Reference (numpy) implementation of :func:`kalker_coefficients` (same arguments and
    result), the check of the compiled kernel."""
    a, b = _checked_semi_axes(a_mm, b_mm, poisson)
    a_le_b = a <= b
    g = np.where(a_le_b, a / b, b / a)
    shape = np.where(a_le_b, g - 1.0, 1.0 - g)
    s = np.clip(shape, KALKER_ROW_SHAPE[0], KALKER_ROW_SHAPE[-1])
    # Linear interpolation between rows (uniform spacing 0.1 in s).
    pos = (s - KALKER_ROW_SHAPE[0]) / 0.1
    row = np.clip(np.floor(pos + 1e-9).astype(int), 0, len(KALKER_ROW_SHAPE) - 2)
    frac = np.clip(pos - row, 0.0, 1.0)
    lo = KALKER_TABLE[row]  # (..., 4, 3)
    hi = KALKER_TABLE[row + 1]
    c_nu = (1.0 - frac)[..., None, None] * lo + frac[..., None, None] * hi
    # Quadratic Lagrange interpolation of 1/C through nu = 0, 0.25, 0.5.
    nu = poisson
    w0 = (nu - 0.25) * (nu - 0.5) / ((0.0 - 0.25) * (0.0 - 0.5))
    w1 = (nu - 0.0) * (nu - 0.5) / ((0.25 - 0.0) * (0.25 - 0.5))
    w2 = (nu - 0.0) * (nu - 0.25) / ((0.5 - 0.0) * (0.5 - 0.25))
    inv = w0 / c_nu[..., 0] + w1 / c_nu[..., 1] + w2 / c_nu[..., 2]
    c = 1.0 / inv  # (..., 4)
    c11, c22, c23, c33 = (c[..., i] for i in range(4))
    slender = g < 0.1
    if np.any(slender):
        a11, a22, a23 = _asymptotes(g, a_le_b, nu)
        c11 = np.where(slender, a11, c11)
        c22 = np.where(slender, a22, c22)
        c23 = np.where(slender, a23, c23)
    return KalkerCoefficients(c11=c11, c22=c22, c23=c23, c33=c33)


@dataclass(frozen=True)
class LinearCreepForces:
    """Creep forces of Kalker's linear theory: Fx, Fy [N], Mz [N*mm]."""

    fx_n: NDArray[np.float64]
    fy_n: NDArray[np.float64]
    mz_nmm: NDArray[np.float64]


def linear_creep_forces(xi: ArrayLike, eta: ArrayLike, phi_per_mm: ArrayLike, a_mm: ArrayLike,
                        b_mm: ArrayLike, shear_modulus_mpa: float = 82_000.0,
                        poisson: float = 0.28) -> LinearCreepForces:
    """Kalker's linear creep forces (no saturation).

    Parameters
    ----------
    xi, eta : longitudinal and lateral creepage [-]
    phi_per_mm : spin creepage [1/mm]
    a_mm, b_mm : contact semi-axes, a in the rolling direction [mm]
    shear_modulus_mpa : combined shear modulus G [MPa]
    poisson : Poisson's ratio

    Returns
    -------
    LinearCreepForces: Fx = -G a b C11 xi; Fy = -G a b C22 eta - G (ab)^1.5 C23 phi;
    Mz = G (ab)^1.5 C23 eta - G (ab)^2 C33 phi (README, Kalker's linear theory).
    """
    c = kalker_coefficients(a_mm, b_mm, poisson)
    xi, eta, phi = (np.asarray(v, dtype=float) for v in (xi, eta, phi_per_mm))
    ab = np.asarray(a_mm, dtype=float) * np.asarray(b_mm, dtype=float)
    g = shear_modulus_mpa
    fx = -g * ab * c.c11 * xi
    fy = -g * ab * c.c22 * eta - g * ab**1.5 * c.c23 * phi
    mz = g * ab**1.5 * c.c23 * eta - g * ab**2 * c.c33 * phi
    return LinearCreepForces(fx_n=fx, fy_n=fy, mz_nmm=mz)


def fastsim_flexibilities(a_mm: ArrayLike, b_mm: ArrayLike, shear_modulus_mpa: float = 82_000.0,
                          poisson: float = 0.28):
    """Kalker's three FASTSIM flexibilities L1, L2, L3 [mm/MPa].

    L1 = 8a/(3 C11 G), L2 = 8a/(3 C22 G), L3 = pi a sqrt(a/b)/(4 C23 G) (Kalker 1982; README).
    Returns a tuple (L1, L2, L3) of arrays.
    """
    a = np.asarray(a_mm, dtype=float)
    b = np.asarray(b_mm, dtype=float)
    c = kalker_coefficients(a, b, poisson)
    g = shear_modulus_mpa
    l1 = 8.0 * a / (3.0 * c.c11 * g)
    l2 = 8.0 * a / (3.0 * c.c22 * g)
    l3 = np.pi * a * np.sqrt(a / b) / (4.0 * c.c23 * g)
    return l1, l2, l3
