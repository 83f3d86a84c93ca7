"""Kik & Piotrowski's fast non-Hertzian normal contact of one patch.

Piotrowski & Kik, Vehicle System Dynamics 46 (2008) 27-48, with Hertz-consistent virtual
penetrations: instead of one factor eps = 0.55 the lateral virtual penetration is eps_y delta
and the strip lengths are scaled by sqrt(eps_x / eps_y), eps_x, eps_y those of the Hertz
ellipse whose lateral curvature B_eq = delta / w0^2 (w0 the half width of the rigid overlap)
matches the patch (``hertz_virtual_penetrations``); the contact area is then
{x_l(s)^2 > (x - x_s)^2} with x_l(s)^2 = (eps_x / eps_y) (g_min + eps_y delta - g(s)) / A(s);
the pressure is semi-elliptic along each strip, p = C A(s) sqrt(x_l(s)^2 - (x - x_s)^2)
(Hertz's ellipse exactly when A is constant and the gap quadratic); its force-approach
relation is that of the Hertz ellipse with the virtual area's length and width
(F = 2 pi E* a_long delta_n / (3 K(m)), Johnson 1985 eq. 4.39 ff.). Method "kp" of
``normal_contact.patch_normal_contact``; its accuracy against the BEM is in that module's
docstring (it misses the 10 % peak-pressure goal and is not the default).

Units: mm, MPa, N.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.special import ellipe, ellipk

from wearcast.physics.contact.hertz import effective_modulus_mpa, hertz_contact
from wearcast.physics.contact.patch_plane import (
    NormalPatch,
    PlaneSamples,
    finish_patch,
    patch_grid,
)
from wearcast.physics.contact.patches import PatchRegion

_FloatArray = NDArray[np.float64]


def _ends(s: _FloatArray, pen: _FloatArray) -> tuple[float, float]:
    """Lateral ends of the region pen > 0 on the samples, interpolated to pen = 0."""
    inside = np.flatnonzero(pen > 0)
    lo, hi = int(inside[0]), int(inside[-1])
    s_lo = float(s[lo]) if lo == 0 else float(np.interp(0.0, [pen[lo - 1], pen[lo]],
                                                         [s[lo - 1], s[lo]]))
    s_hi = float(s[hi]) if hi == s.size - 1 else float(np.interp(0.0, [pen[hi + 1], pen[hi]],
                                                                 [s[hi + 1], s[hi]]))
    return s_lo, s_hi


def hertz_virtual_penetrations(ratio_b_over_a: float) -> tuple[float, float]:
    """(eps_x, eps_y): Hertz contact semi-axes over the rigid-overlap semi-axes, squared, for
    the ellipse with curvature ratio B/A: a^2 = eps_x delta / A, b^2 = eps_y delta / B
    (from Johnson 1985 eqs. 4.39 ff.: eps_x = (K - E) / (m K) along the long axis,
    (E - k^2 K) / (m K) along the short one; both 1/2 for a circle)."""
    r = max(ratio_b_over_a, 1.0 / max(ratio_b_over_a, 1e-12))
    m = float(np.clip(-np.expm1(2.0 * _log_k_from_ratio(r)), 0.0, 1.0 - 1e-15))
    k2 = 1.0 - m
    if m < 1e-6:
        return 0.5, 0.5
    big_k, big_e = float(ellipk(m)), float(ellipe(m))
    eps_long = (big_k - big_e) / (m * big_k)
    eps_short = (big_e - k2 * big_k) / (m * big_k)
    # the long axis lies along the smaller curvature
    return (eps_long, eps_short) if ratio_b_over_a >= 1.0 else (eps_short, eps_long)


def _log_k_from_ratio(ratio: float) -> float:
    """log(b/a) of the Hertz ellipse with curvature ratio (>= 1), as ``hertz``."""
    hz = hertz_contact(1.0, 1.0, ratio)
    return float(np.log(min(hz.a_mm, hz.b_mm) / max(hz.a_mm, hz.b_mm)))


def kp_patch(region: PatchRegion, ps: PlaneSamples, approach_mm: float, young_mpa: float,
              poisson: float, element_mm: float, margin_mm: float) -> NormalPatch:
    e_star = effective_modulus_mpa(young_mpa, poisson)
    h, x, s = patch_grid(ps, approach_mm, element_mm, margin_mm)
    k_min = int(np.argmin(ps.g))
    pen = (approach_mm - ps.g) * ps.c                  # rigid overlap along the normal
    delta_n = float(pen[k_min])
    a_ref = float(ps.a[k_min] * ps.c[k_min])
    s_lo, s_hi = _ends(ps.s, pen)
    half_width0 = 0.5 * (s_hi - s_lo)
    b_eq = delta_n / max(half_width0, 1e-9) ** 2      # equivalent lateral curvature
    eps_x, eps_y = hertz_virtual_penetrations(b_eq / a_ref)
    # virtual lateral penetration eps_y delta; strip lengths scaled by sqrt(eps_x / eps_y)
    g_n = ps.g * ps.c
    pen_v = (float(g_n[k_min]) + eps_y * delta_n) - g_n
    c = np.interp(s, ps.s, ps.c)
    g = np.interp(s, ps.s, g_n, left=np.inf, right=np.inf)
    a = np.interp(s, ps.s, ps.a) * c
    xs = np.interp(s, ps.s, ps.x)
    pen_s = np.clip(float(g_n[k_min]) + eps_y * delta_n - g, 0.0, None)
    x_l2 = (eps_x / eps_y) * pen_s / a
    shape = a[:, None] * np.sqrt(np.clip(x_l2[:, None] - (x[None, :] - xs[:, None]) ** 2,
                                         0.0, None))
    dx, ds = float(x[1] - x[0]), float(s[1] - s[0])
    if shape.sum() <= 0 or not np.any(pen_v > 0):
        return finish_patch(region, "kp", ps, x, s, np.zeros_like(h))
    # force from the Hertz ellipse of the virtual area's length and width (continuous in d)
    v_lo, v_hi = _ends(ps.s, pen_v)
    half_width = 0.5 * (v_hi - v_lo)
    inside = pen_v > 0
    half_length = float(np.sqrt(np.max((eps_x / eps_y) * pen_v[inside]
                                       / (ps.a[inside] * ps.c[inside]))))
    long_ax, short_ax = max(half_width, half_length), min(half_width, half_length)
    m = 1.0 - (short_ax / long_ax) ** 2
    fn = 2.0 * np.pi * e_star * long_ax * delta_n / (3.0 * float(ellipk(m)))
    p = shape * (fn / (shape.sum() * dx * ds))
    return finish_patch(region, "kp", ps, x, s, p)
