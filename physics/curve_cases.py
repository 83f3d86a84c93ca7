"""Operating points of the quasi-static curving model: curvature, unbalanced lateral
acceleration, speed and traction torque of one curve (``curving.solve_curving_cases``).

Track: curvature kappa = +1/R for a curve to the vehicle's left (``direction="left"``), -1/R
for a right curve, 0 for tangent track; cant raises the outer rail. The speed follows from a
prescribed unbalanced lateral acceleration (cant deficiency) when it is not given: seed 001 §4
(a_nc = 0.58 m/s^2), seed 003 §5.3 (a_nc = 0.8 m/s^2 capped by the line speed).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.vehicles import GRAVITY_M_S2
from wearcast.physics.vocabulary import SIDES

#: Lateral distance used for the cant angle (rail-centre spacing) [mm].
CANT_BASE_MM = 1500.0


def speed_from_cant_deficiency(radius_m: ArrayLike, cant_mm: ArrayLike,
                               unbalanced_acceleration_m_s2: float = 0.58,
                               max_speed_m_s: float | None = None) -> NDArray[np.float64]:
    """Curving speed that gives a prescribed unbalanced lateral acceleration.

    V = sqrt(R (a_nc + g cant / 1500 mm)); tangent track (R = inf/NaN) gives ``max_speed_m_s``
    (or inf). Seed 001 §4 uses a_nc = 0.58 m/s^2, seed 003 §5.3 a_nc = 0.8 m/s^2 capped by the
    line speed. A cant deficiency limit D [mm] is the same as a_nc = g D / 1500.

    Parameters
    ----------
    radius_m : curve radius [m]; cant_mm : cant [mm]
    unbalanced_acceleration_m_s2 : a_nc [m/s^2]
    max_speed_m_s : optional cap [m/s]

    Returns
    -------
    speed [m/s]
    """
    r = np.asarray(radius_m, dtype=float)
    c = np.asarray(cant_mm, dtype=float)
    finite = np.isfinite(r) & (r > 0)
    base = unbalanced_acceleration_m_s2 + GRAVITY_M_S2 * c / CANT_BASE_MM
    v = np.where(finite, np.sqrt(np.clip(np.where(finite, r, 1.0) * base, 0.0, None)), np.inf)
    if max_speed_m_s is not None:
        v = np.minimum(v, max_speed_m_s)
    return v


@dataclass(frozen=True)
class CurveCase:
    """One operating point: signed curvature kappa [1/m] (+ left), unbalanced lateral
    acceleration [m/s^2] (+y), speed [m/s], traction torque per axle [N m]."""

    curvature_per_m: float
    unbalanced_acceleration_m_s2: float
    speed_m_s: float
    torque_nm: float

    def scaled(self, t: float) -> CurveCase:
        return CurveCase(t * self.curvature_per_m, t * self.unbalanced_acceleration_m_s2,
                         self.speed_m_s, t * self.torque_nm)


def curve_case(radius_m: float | None, cant_mm: float = 0.0, speed_m_s: float | None = None,
               direction: str = "left", unbalanced_acceleration_m_s2: float = 0.58,
               torque_nm: float = 0.0, tangent_speed_m_s: float = 30.0) -> CurveCase:
    """Build a :class:`CurveCase` from radius [m] (None/inf = tangent), cant [mm], speed [m/s]
    (None: from the unbalanced acceleration, :func:`speed_from_cant_deficiency`), direction."""
    if direction not in SIDES:
        raise ValueError(f"direction must be 'left' or 'right', got {direction!r}")
    if radius_m is not None and np.isfinite(radius_m) and radius_m <= 0:
        raise ValueError(f"radius_m must be positive, got {radius_m}")
    if cant_mm < 0:
        raise ValueError(f"cant_mm must be >= 0, got {cant_mm}")
    if radius_m is None or not np.isfinite(radius_m):  # tangent track
        v = tangent_speed_m_s if speed_m_s is None else speed_m_s
        return CurveCase(0.0, 0.0, float(v), torque_nm)
    if speed_m_s is None:
        speed_m_s = float(speed_from_cant_deficiency(radius_m, cant_mm,
                                                     unbalanced_acceleration_m_s2))
    if speed_m_s <= 0:
        raise ValueError(f"speed must be positive, got {speed_m_s}")
    sign = 1.0 if direction == "left" else -1.0
    kappa = sign / radius_m
    a_unb = speed_m_s**2 * kappa - sign * GRAVITY_M_S2 * cant_mm / CANT_BASE_MM
    return CurveCase(kappa, a_unb, float(speed_m_s), torque_nm)
