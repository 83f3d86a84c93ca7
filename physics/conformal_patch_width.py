"""The lateral width of a conformal contact patch from the unsmoothed wheel-rail gap.

The curving table's Hertz patches take the curvature of a gap smoothed at the scale of a patch,
which turns a conformal pair into a narrow ellipse; :func:`conformal_half_width_mm` widens such
a patch to Kik & Piotrowski's virtual-penetration region of the raw gap (the ``kik_piotrowski``
patch width of the wear loop, ``class_contacts``). Lengths mm, forces N.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.hertz import effective_modulus_mpa
from wearcast.physics.curving_table import rail_envelope
from wearcast.physics.profiles.rails import RailShape

#: Kik & Piotrowski (1996): the patch is where the undeformed interpenetration exceeds
#: (1 - epsilon) of the approach, i.e. where the gap is below epsilon * approach; epsilon = 0.55.
KIK_PIOTROWSKI_EPSILON = 0.55


def conformal_half_width_mm(wheel_y_grid_mm: ArrayLike, wheel_z_grid_mm: ArrayLike,
                            rail: str | RailShape,
                            inclination: float, wheel_y_mm: ArrayLike, rail_y_mm: ArrayLike,
                            normal_n: ArrayLike, a_mm: ArrayLike, b_mm: ArrayLike,
                            search_mm: float = 12.0) -> NDArray[np.float64]:
    """Lateral half-width of a patch from the UNSMOOTHED gap (Kik-Piotrowski's virtual
    penetration), along the profile arc [mm], never below the Hertz ``b_mm``.

    The curving model's Hertz patches take the curvature of a gap smoothed over 2 mm, which
    turns a conformal pair (the S1002 flange root, concave R13, on the 60E1 gauge corner, convex
    R13: relative curvature ~0) into a narrow ellipse (b < 1 mm, p0 of several GPa). Seed 002
    §2.1 (Simpack) finds the patch by Kik-Piotrowski and replaces it by an equivalent ellipse;
    so do we, for the patch width only: with the approach delta = 3 N / (4 E* sqrt(a b)) of the
    Hertz patch (its circular equivalent, Johnson §4.2), the patch spans the connected range
    around the contact point where the raw gap is within epsilon * delta of its minimum
    (epsilon = 0.55, Kik & Piotrowski 1996). For a Hertzian pair this is about b; for a
    conformal one it is the extent of the conformal arcs.

    Parameters
    ----------
    wheel_y_grid_mm, wheel_z_grid_mm : the wheel profile z(y) in the wheel frame [mm]
    rail, inclination : rail profile and inclination (as the vehicle's)
    wheel_y_mm, rail_y_mm : contact points on the wheel and in the rail frame of the contact
        table (``CurvingResult.wheel_y_mm`` / ``rail_y_mm``), shape S [mm]
    normal_n, a_mm, b_mm : normal force [N] and Hertz semi-axes [mm], shape S
    search_mm : half-range searched around the contact point [mm]

    Returns
    -------
    half-width along the profile arc [mm], shape S (b_mm where not loaded)
    """
    yg = np.asarray(wheel_y_grid_mm, dtype=float)
    zg = np.asarray(wheel_z_grid_mm, dtype=float)
    yw, yr, n, a, b = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (
        wheel_y_mm, rail_y_mm, normal_n, a_mm, b_mm)))
    ry, rz, _ = rail_envelope(rail, inclination)
    e_star = effective_modulus_mpa()
    out = b.copy()
    step = 0.05
    local = np.arange(-search_mm, search_mm + 1e-9, step)
    loaded = np.nonzero((n > 1.0) & (a > 0) & (b > 0))
    if loaded[0].size == 0:
        return out
    # all loaded patches at once, row by row the arithmetic of one patch (the same numbers)
    yw_p, yr_p, n_p, a_p, b_p = (v[loaded] for v in (yw, yr, n, a, b))
    y = yw_p[:, None] + local[None, :]
    # rail_y is the rail-envelope coordinate of the contact (ContactTable.candidates:
    # rail_y = y + offset + shift, the coordinate build_contact_table samples the rail at)
    y_rail = y + (yr_p - yw_p)[:, None]
    gap = -np.interp(y, yg, zg) - np.interp(y_rail, ry, rz, left=np.nan, right=np.nan)
    gap = np.where(np.isfinite(gap), gap, np.inf)
    centre = int(np.argmin(np.abs(local)))
    lo_win = max(0, centre - int(round(1.0 / step)))
    hi_win = min(local.size, centre + int(round(1.0 / step)) + 1)
    g_min = np.min(gap[:, lo_win:hi_win], axis=1)
    delta = 3.0 * n_p / (4.0 * e_star * np.sqrt(a_p * b_p))
    inside = gap <= (g_min + KIK_PIOTROWSKI_EPSILON * delta)[:, None]
    # the connected run of inside points through the smallest gap near the contact point
    j0 = lo_win + np.argmin(gap[:, lo_win:hi_win], axis=1)
    cols = np.arange(local.size)[None, :]
    rows = np.arange(j0.size)
    last_out = np.maximum.accumulate(np.where(inside, -1, cols), axis=1)
    left = np.where(j0 > 0, last_out[rows, np.maximum(j0 - 1, 0)], -1) + 1
    first_out = np.minimum.accumulate(np.where(inside, local.size, cols)[:, ::-1],
                                      axis=1)[:, ::-1]
    right = np.where(j0 < local.size - 1, first_out[rows, np.minimum(j0 + 1, local.size - 1)],
                     local.size) - 1
    width_y = (right - left + 1) * step
    slope = np.interp(yw_p, yg, np.gradient(zg, yg))
    half_arc = 0.5 * width_y * np.sqrt(1.0 + slope * slope)
    out[loaded] = np.where(half_arc > b_p, half_arc, b_p)
    return out
