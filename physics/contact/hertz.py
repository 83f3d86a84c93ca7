"""Hertz normal contact of two steel bodies: contact ellipse, peak pressure, approach.

Geometry: near the contact point the gap between the undeformed surfaces is
h(x, y) = A x^2 + B y^2 with the principal relative curvatures A (rolling direction x) and
B (lateral y) [1/mm], A = (1/R1x + 1/R2x)/2, B = (1/R1y + 1/R2y)/2. Both bodies have the
same Young's modulus E and Poisson's ratio nu, so 1/E* = 2 (1 - nu^2)/E.

With the semi-axes a >= b, k = b/a, eccentricity e^2 = m = 1 - k^2 and the complete
elliptic integrals K(m), E(m) (scipy's parameter convention):

    A = 3 F (K - E) / (2 pi E* a^3 m)
    B = 3 F (E/k^2 - K) / (2 pi E* a^3 m)
    delta = 3 F K / (2 pi E* a)          (approach of distant points)
    p0 = 3 F / (2 pi a b)

(Johnson, Contact Mechanics, 1985, §4.2, eqs. 4.39 ff.; seed 000 eqs. (9)-(11) use the same
theory through tabulated coefficients). The eccentricity follows from B/A alone and is found
by bisection on log(b/a); for a circle (A = B) the formulas reduce to a = (3 F R / 4 E*)^(1/3)
with R = 1/(2A).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

#: Young's modulus of wheel and rail steel [MPa].
STEEL_YOUNG_MPA = 210_000.0
#: Poisson's ratio of wheel and rail steel.
STEEL_POISSON = 0.28
#: Shear modulus of wheel and rail steel [MPa] (CONTACT's GG in the Manchester benchmark; E / (2
#: (1 + nu)) = 82.0 GPa).
STEEL_SHEAR_MODULUS_MPA = 82_000.0

_M_SERIES = 1e-4  # below this elliptic parameter the small-m series replace the quotients


@dataclass(frozen=True)
class HertzPatch:
    """Hertzian contact ellipse; every field is an array of the broadcast input shape.

    normal_force_n : normal load [N]
    a_mm : semi-axis in the rolling direction x [mm]
    b_mm : lateral semi-axis [mm]
    p0_mpa : peak pressure 3F/(2 pi a b) [MPa]
    approach_mm : approach (penetration) delta of distant points [mm]
    """

    normal_force_n: NDArray[np.float64]
    a_mm: NDArray[np.float64]
    b_mm: NDArray[np.float64]
    p0_mpa: NDArray[np.float64]
    approach_mm: NDArray[np.float64]

    @property
    def area_mm2(self) -> NDArray[np.float64]:
        """Contact area pi a b [mm^2]."""
        return np.pi * self.a_mm * self.b_mm


def effective_modulus_mpa(young_mpa: float = STEEL_YOUNG_MPA,
                          poisson: float = STEEL_POISSON) -> float:
    """E* [MPa] of two bodies of the same material: 1/E* = 2 (1 - nu^2) / E (Johnson §4.2)."""
    return young_mpa / (2.0 * (1.0 - poisson**2))


def _quotients(m: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """(K - E)/m, (E/(1-m) - K)/m and K for the elliptic parameter m = e^2 in [0, 1)."""
    m = np.asarray(m, dtype=float)
    small = m < _M_SERIES
    ms = np.where(small, 1.0, m)  # avoid 0/0 in the branch that is not used
    k_int = ellipk(m)
    e_int = ellipe(m)
    q_a = np.where(small, 0.5 * np.pi * (0.5 + 3.0 * m / 16.0), (k_int - e_int) / ms)
    q_b = np.where(small, 0.5 * np.pi * (0.5 + 9.0 * m / 16.0),
                   (e_int / (1.0 - m) - k_int) / ms)
    return q_a, q_b, k_int


def _ratio_excess(log_b_over_a: float, ratio: float) -> float:
    """(E/(1-m) - K) / (K - E) - ratio at m = 1 - (b/a)^2 (``_quotients`` for one value)."""
    m = -math.expm1(2.0 * log_b_over_a)
    if m < _M_SERIES:
        return (0.5 + 9.0 * m / 16.0) / (0.5 + 3.0 * m / 16.0) - ratio
    k_int = float(ellipk(m))
    e_int = float(ellipe(m))
    return (e_int / (1.0 - m) - k_int) / (k_int - e_int) - ratio


def _parameter_from_ratio(ratio: NDArray[np.float64]) -> NDArray[np.float64]:
    """Elliptic parameter m = 1 - (b/a)^2 for which B/A = ratio (>= 1), by bisection (one
    ratio: Brent's method on the same function, to the same precision, ~15 evaluations
    instead of 64 vectorised steps)."""
    if ratio.size == 1 and float(ratio.flat[0]) < 1e12:
        r = float(ratio.flat[0])
        root = 0.0
        if _ratio_excess(0.0, r) < 0.0:
            root = float(brentq(_ratio_excess, -18.0, 0.0, args=(r,), xtol=1e-20, rtol=1e-15))
        return np.full_like(ratio, -math.expm1(2.0 * root))
    lo = np.full_like(ratio, -18.0)  # log(b/a): b/a = 1.5e-8 ... 1
    hi = np.zeros_like(ratio)
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        m = -np.expm1(2.0 * mid)
        q_a, q_b, _ = _quotients(m)
        too_round = q_b / q_a < ratio  # ratio grows as b/a shrinks
        hi = np.where(too_round, mid, hi)
        lo = np.where(too_round, lo, mid)
    return -np.expm1(2.0 * 0.5 * (lo + hi))


def hertz_contact(normal_force_n: ArrayLike, curvature_a_per_mm: ArrayLike,
                  curvature_b_per_mm: ArrayLike, young_mpa: float = STEEL_YOUNG_MPA,
                  poisson: float = STEEL_POISSON) -> HertzPatch:
    """Hertzian contact ellipse for two bodies of the same steel.

    Parameters
    ----------
    normal_force_n : normal load [N], >= 0
    curvature_a_per_mm : principal relative curvature A in the rolling direction [1/mm], > 0
    curvature_b_per_mm : principal relative curvature B, lateral [1/mm], > 0
    young_mpa, poisson : Young's modulus [MPa] and Poisson's ratio of both bodies

    Returns
    -------
    HertzPatch with a (rolling direction) and b [mm], p0 [MPa], approach [mm]; the smaller
    curvature gives the longer semi-axis. A zero load gives a zero patch.

    Johnson, Contact Mechanics §4.2 (module docstring); vectorised over all inputs.
    """
    f, ca, cb = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in
                                      (normal_force_n, curvature_a_per_mm, curvature_b_per_mm)))
    if np.any(ca <= 0) or np.any(cb <= 0):
        raise ValueError("curvatures A and B must be positive (convex relative geometry)")
    if np.any(f < 0):
        raise ValueError("normal_force_n must be >= 0")
    e_star = effective_modulus_mpa(young_mpa, poisson)
    c_small = np.minimum(ca, cb)
    c_large = np.maximum(ca, cb)
    m = _parameter_from_ratio(c_large / c_small)
    q_a, _, k_int = _quotients(m)
    # Long semi-axis (along the smaller curvature) and short one.
    long_mm = np.cbrt(3.0 * f * q_a / (2.0 * np.pi * e_star * c_small))
    short_mm = long_mm * np.sqrt(1.0 - m)
    a_along_x = ca <= cb
    a_mm = np.where(a_along_x, long_mm, short_mm)
    b_mm = np.where(a_along_x, short_mm, long_mm)
    with np.errstate(divide="ignore", invalid="ignore"):
        p0 = np.where(f > 0, 3.0 * f / (2.0 * np.pi * a_mm * b_mm), 0.0)
        approach = np.where(f > 0, 3.0 * f * k_int / (2.0 * np.pi * e_star * long_mm), 0.0)
    return HertzPatch(normal_force_n=f, a_mm=a_mm, b_mm=b_mm, p0_mpa=p0, approach_mm=approach)


def _approach_per_unit_force(curvature_a_per_mm, curvature_b_per_mm, young_mpa, poisson):
    """delta(F = 1 N) [mm]; delta scales as F^(2/3) for a fixed geometry."""
    return hertz_contact(1.0, curvature_a_per_mm, curvature_b_per_mm, young_mpa,
                         poisson).approach_mm


def normal_force_from_approach(approach_mm: ArrayLike, curvature_a_per_mm: ArrayLike,
                               curvature_b_per_mm: ArrayLike,
                               young_mpa: float = STEEL_YOUNG_MPA,
                               poisson: float = STEEL_POISSON) -> NDArray[np.float64]:
    """Normal force [N] that produces the approach delta [mm]: F = (delta / delta_1)^1.5.

    delta_1 is the approach under 1 N for the same curvatures (Hertz: delta ~ F^(2/3)).
    Negative approaches (a gap) give zero force.
    """
    delta = np.asarray(approach_mm, dtype=float)
    d1 = _approach_per_unit_force(curvature_a_per_mm, curvature_b_per_mm, young_mpa, poisson)
    return np.clip(delta, 0.0, None) ** 1.5 / d1**1.5


def split_load_between_patches(total_load_n: ArrayLike, curvature_a_per_mm: ArrayLike,
                               curvature_b_per_mm: ArrayLike, gap_mm: ArrayLike = 0.0,
                               load_cosine: ArrayLike = 1.0,
                               young_mpa: float = STEEL_YOUNG_MPA,
                               poisson: float = STEEL_POISSON) -> NDArray[np.float64]:
    """Share a wheel's load between several contact patches with one common penetration.

    Each patch i (last axis) has curvatures A_i, B_i, an initial gap g_i >= 0 [mm] (measured
    along the common approach direction) and a direction cosine c_i between its normal and the
    load. The common penetration d solves sum_i c_i F_i(d - g_i) = W with the Hertz law
    F_i(delta) = (delta / delta_1,i)^1.5; it is found by bisection (the sum is monotone in d).

    Parameters
    ----------
    total_load_n : load W to be carried [N], shape (...)
    curvature_a_per_mm, curvature_b_per_mm : shape (..., n_patches) [1/mm]
    gap_mm : initial gap of each patch [mm], broadcast to (..., n_patches)
    load_cosine : component of a unit normal force along the load, > 0

    Returns
    -------
    Normal force of each patch [N], shape (..., n_patches).
    """
    w = np.asarray(total_load_n, dtype=float)[..., None]
    ca, cb, gap, cos = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in
                                             (curvature_a_per_mm, curvature_b_per_mm, gap_mm,
                                              load_cosine)))
    if np.any(cos <= 0):
        raise ValueError("load_cosine must be positive")
    if np.any(w < 0):
        raise ValueError("total_load_n must be >= 0")
    d1 = _approach_per_unit_force(ca, cb, young_mpa, poisson)
    gap = np.clip(gap, 0.0, None)

    def carried(d):
        return np.sum(cos * np.clip(d - gap, 0.0, None) ** 1.5 / d1**1.5, axis=-1,
                      keepdims=True)

    gmin = np.min(gap, axis=-1, keepdims=True)
    lo = gmin.copy()
    # Upper bound: the first patch alone carries the whole load.
    hi = gmin + np.max(d1 * (w / np.min(cos, axis=-1, keepdims=True)) ** (2.0 / 3.0),
                       axis=-1, keepdims=True)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        low = carried(mid) < w
        lo = np.where(low, mid, lo)
        hi = np.where(low, hi, mid)
    d = 0.5 * (lo + hi)
    return np.clip(d - gap, 0.0, None) ** 1.5 / d1**1.5
