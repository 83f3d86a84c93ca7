"""S1002 wheel profile (EN 13715) from its analytic piecewise definition.

Coordinates follow the wheel frame of docs/conventions.md: ``y`` [mm] lateral from the tape circle,
negative towards the flange (flange back at y = -70, flange tip at y = -55); ``z`` [mm] radius
increase over the tape circle, positive towards the flange tip.

Source: the Netter (DLR) piecewise definition of S1002 as listed in
EN 13715 (checked in the tests against CONTACT's MBench_S1002_v3.prw).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Lateral validity range of the definition [mm].
S1002_Y_MIN_MM = -70.0
S1002_Y_MAX_MM = 60.0

# Section bounds (y from the tape circle, mm), from field side to flange back.
_BOUND_AB = 32.15796
_BOUND_BC = -26.0
_BOUND_CD = -35.0
_BOUND_DE = -38.426669071
_BOUND_EF = -39.764473993
_BOUND_FG = -49.662510381
_BOUND_GH = -62.764705882

_A = (1.364323640, 0.066666667)
_B = (0.0, 3.358537058e-02, 1.565681624e-03, 2.810427944e-05, 5.844240864e-08,
      1.562379023e-08, 5.309217349e-15, 5.957839843e-12, 2.646656573e-13)
_C = (4.320221063e03, 1.038384026e03, 1.065501873e02, 6.051367875, 2.054332446e-01,
      4.169739389e-03, 4.687195829e-05, 2.252755540e-07)
_D = (16.446, 13.0, 26.210665)
_E = (93.576667419, 2.747477419)
_F = (8.834924130, 20.0, 58.558326413)
_G = (16.0, 12.0, 55.0)
_H = (9.519259302, 20.5, 49.5)


def _section_b(y: NDArray[np.float64]) -> NDArray[np.float64]:
    # F = AB - BB*S + CB*S^2 - DB*S^3 + EB*S^4 - FB*S^5 + GB*S^6 - HB*S^7 + IB*S^8
    signs = np.array([1, -1, 1, -1, 1, -1, 1, -1, 1], dtype=float)
    coefficients = signs * np.asarray(_B)
    return np.polynomial.polynomial.polyval(y, coefficients)


def _section_c(y: NDArray[np.float64]) -> NDArray[np.float64]:
    # F = -AC - BC*S - CC*S^2 - ... - HC*S^7
    return -np.polynomial.polynomial.polyval(y, np.asarray(_C))


def _arc_below(y: NDArray[np.float64], a: float, r: float, c: float) -> NDArray[np.float64]:
    return a - np.sqrt(np.clip(r**2 - (y + c) ** 2, 0.0, None))


def _arc_above(y: NDArray[np.float64], a: float, r: float, c: float) -> NDArray[np.float64]:
    return a + np.sqrt(np.clip(r**2 - (y + c) ** 2, 0.0, None))


def s1002_height_mm(y_mm: ArrayLike) -> NDArray[np.float64]:
    """Height z(y) of the S1002 wheel profile over the tape circle.

    Parameters
    ----------
    y_mm : lateral position(s) from the tape circle [mm], -70 <= y <= 60, negative
        towards the flange

    Returns
    -------
    z [mm], radius increase over the tape circle (positive towards the flange tip);
    NaN outside the validity range.

    Source: EN 13715 S1002 (docs/references.md) in the Netter (DLR) piecewise form.
    """
    y = np.asarray(y_mm, dtype=float)
    conditions = [
        y > _BOUND_AB,
        y > _BOUND_BC,
        y >= _BOUND_CD,
        y > _BOUND_DE,
        y > _BOUND_EF,
        y > _BOUND_FG,
        y > _BOUND_GH,
        y >= S1002_Y_MIN_MM,
    ]
    choices = [
        _A[0] - _A[1] * y,
        _section_b(y),
        _section_c(y),
        _arc_below(y, *_D),
        -_E[0] - _E[1] * y,
        _arc_above(y, *_F),
        _arc_above(y, *_G),
        _arc_above(y, *_H),
    ]
    z = np.select(conditions, choices, default=np.nan)
    return np.where(y <= S1002_Y_MAX_MM, z, np.nan)


def s1002_profile(step_mm: float = 0.5) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sampled S1002 profile on a regular grid from the flange back to the field side.

    Parameters
    ----------
    step_mm : lateral sampling step [mm]

    Returns
    -------
    (y [mm], z [mm]) arrays, y ascending from -70 to 60.
    """
    n_points = int(round((S1002_Y_MAX_MM - S1002_Y_MIN_MM) / step_mm)) + 1
    y = np.linspace(S1002_Y_MIN_MM, S1002_Y_MAX_MM, n_points)
    return y, s1002_height_mm(y)
