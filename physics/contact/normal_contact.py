"""Normal contact of one wheel on its rail: non-Hertzian patches, BEM or fast, Hertz where valid.

This is the function the curving and wear models call per wheel: ``wheel_normal_contact``
takes a contact locus (``locus.wheel_locus``, roll solved or prescribed) and a vertical
wheel load and returns, per pose, the contact patches (``patches.patch_regions``: merged or
split by the interpenetration region as CONTACT does) with their pressure on a grid, normal
force, reference location, pressure centre, peak pressure and an equivalent ellipse.
``patch_normal_contact`` solves one patch for a given vertical approach.

API for the curving helper
--------------------------
``wheel_normal_contact(locus, wheel_load_n, method="auto", lateral_ratio=None, ...)``
  -> list (one per pose) of ``WheelNormalContact(approach_mm, patches: list[NormalPatch])``.
``NormalPatch`` fields: ``region`` (reference location: ``y_wheel_mm``, ``y_track_mm``,
``x_track_mm``, ``z_rail_mm``, ``contact_angle_rad``, ``rolling_radius_mm``),
``normal_force_n`` [N], ``pressure_mpa`` (n_s, n_x) on the grid ``x_mm`` (rolling, from the
reference) x ``s_mm`` (lateral in the contact plane, towards the wheel's field side, from the
reference), ``peak_pressure_mpa``, ``area_mm2``, ``centre_x_mm``/``centre_s_mm`` (pressure
centre) and ``centre_y_wheel_mm`` (its wheel position), ``a_mm``/``b_mm`` (equivalent
ellipse: b half the lateral extent, a = area / (pi b)), ``method`` used.
``method="auto"`` is the production method (Hertz / coarse BEM, below); "bem" the reference.
``lateral_ratio`` (optional, per pose a list of F_s/F_n per patch from a tangential solution)
enters the vertical equilibrium sum F_n (cos delta + (F_s/F_n) sin delta) = W.

Planar patch problem
--------------------
Each patch is solved in its contact plane (CONTACT's planar approach: the plane through the
reference point at the reference angle delta_r).  A locus sample k lies at the lateral
coordinate s_k = e_s . (P_k - P_ref) of the plane (e_s = (sign cos delta_r, -sin delta_r) in
track (y, z)); the undeformed normal gap at (x, s_k) at vertical approach d is

    h(x, s_k) = (g_k + A_k (x - x_k)^2 - d) cos(delta_k) / cos(delta_k - delta_r),

the vertical gap turned into the distance along the plane normal (exact for locally parallel
surfaces), interpolated in s onto a grid of ``element_mm`` (CONTACT's 0.2 mm) elements.

Methods
-------
"bem": ``normal_bem.solve_normal_bem`` on that grid (Kalker's NORM-type influence
  coefficients, FFT, Polonsky-Keer) with the approach prescribed; the exact solution of the
  half-space problem on the discretised geometry.
"kp": Kik & Piotrowski's fast method (Piotrowski & Kik, Vehicle System Dynamics 46 (2008)
  27-48) with Hertz-consistent virtual penetrations: instead of one factor eps = 0.55 the
  lateral virtual penetration is eps_y delta and the strip lengths are scaled by
  sqrt(eps_x / eps_y), eps_x, eps_y those of the Hertz ellipse whose lateral curvature
  B_eq = delta / w0^2 (w0 the half width of the rigid overlap) matches the patch
  (``hertz_virtual_penetrations``); the contact area is then {x_l(s)^2 > (x - x_s)^2} with
  x_l(s)^2 = (eps_x / eps_y) (g_min + eps_y delta - g(s)) / A(s); the pressure is
  semi-elliptic along each strip, p = C A(s) sqrt(x_l(s)^2 - (x - x_s)^2) (Hertz's ellipse
  exactly when A is constant and the gap quadratic); its force-approach relation is that of
  the Hertz ellipse with the virtual area's length and width (F = 2 pi E* a_long delta_n /
  (3 K(m)), Johnson 1985 eq. 4.39 ff.).
"hertz": one ellipse from the curvatures at the deepest point of the patch
  (``hertz.hertz_contact``; A from the wheel radius, B from the normal gap's second
  derivative along the plane).
"bem-coarse": the BEM on a grid of at most ``COARSE_ELEMENTS`` (24) elements per direction
  over the rigid interpenetration region (never finer than ``element_mm``).
"auto" (the production method): Hertz where the patch really is elliptic, else
  "bem-coarse".  Criterion (``curvature_spread``): the lateral relative curvature B, weighted
  by pen^(3/2) over the interpenetration region, has a relative standard deviation below
  ``HERTZ_CURVATURE_VARIATION`` = 0.25 (and B > 0).  Measured on S1002 / 60E1 1:40 and 1:20
  at 10 and 60 kN (shifts -4 ... 9 mm): where the spread is below 0.25 Hertz is within
  3.2 % of the BEM's peak pressure and 0.11 mm of its pressure centre; above 0.45 it is off
  by up to 43 % and 6.8 mm (the merged tread + flange-root patch).

Measured against the fine BEM on conformal treads (``benchmarks/normal_contact_accuracy.py``;
S1002 on 60E1 1:40 and 1:20 and nine measured MiniProf wheels, 10 and 60 kN, 198 cases):
"auto" p95 (max) position 0.10 mm (0.19), F_n 0.01 %, peak pressure 1.8 % (3.8 %), Hertz in
32 % of the cases; "bem-coarse" alone (50-case subset) 0.005 mm, 0.01 %, 1.7 %; "kp" (as
above) 0.06 mm (0.85), 0.01 %, 15.8 % (30 % on the centred S1002 / 60E1 1:40 tread), so it
misses the 10 % goal and is not the default.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ellipe, ellipk

from wearcast.physics.contact.hertz import (
    STEEL_POISSON,
    STEEL_YOUNG_MPA,
    effective_modulus_mpa,
    hertz_contact,
)
from wearcast.physics.contact.locus import NoContactError, WheelLocus
from wearcast.physics.contact.normal_bem import solve_normal_bem
from wearcast.physics.contact.patches import PatchRegion, patch_regions

_FloatArray = NDArray[np.float64]

#: Kik & Piotrowski's virtual-penetration factor eps.
KP_VIRTUAL_PENETRATION = 0.55
#: Largest weighted relative spread of the lateral curvature B across a patch for Hertz
#: ("auto"; ``curvature_spread``), measured against the BEM (module docstring).
HERTZ_CURVATURE_VARIATION = 0.25
#: Methods of ``patch_normal_contact``.
METHODS = ("bem", "bem-coarse", "kp", "hertz", "auto")
#: Elements per direction of the "bem-coarse" grid (over the rigid interpenetration region).
COARSE_ELEMENTS = 24


@dataclass(frozen=True)
class NormalPatch:
    """Solved normal contact of one patch (module docstring, "API")."""

    region: PatchRegion
    method: str
    normal_force_n: float
    x_mm: _FloatArray
    s_mm: _FloatArray
    pressure_mpa: _FloatArray
    peak_pressure_mpa: float
    area_mm2: float
    centre_x_mm: float
    centre_s_mm: float
    centre_y_wheel_mm: float
    centre_y_track_mm: float
    a_mm: float
    b_mm: float

    @property
    def contact_angle_rad(self) -> float:
        """delta at the reference [rad]."""
        return self.region.contact_angle_rad


@dataclass(frozen=True)
class WheelNormalContact:
    """All patches of one wheel at one pose, carrying the vertical load together.

    approach_mm : common rigid vertical approach d of wheel and rail [mm]
    patches : ``NormalPatch`` per patch, field side first
    load_residual_n : vertical force of the normal forces less the load [N]: 0 to the
        iteration's tolerance, except at a jump of the force-approach curve (patches merging)
        where no approach carries the load exactly
    """

    approach_mm: float
    patches: list[NormalPatch]
    load_residual_n: float = 0.0

    @property
    def vertical_force_n(self) -> float:
        """sum F_n cos(delta) [N] (normal forces only)."""
        return float(sum(p.normal_force_n * np.cos(p.contact_angle_rad) for p in self.patches))


@dataclass(frozen=True)
class _PlaneSamples:
    s: _FloatArray       # lateral plane coordinate of the samples, ascending
    g: _FloatArray       # vertical gap [mm]
    x: _FloatArray       # locus x relative to the reference [mm]
    a: _FloatArray       # rolling curvature A [1/mm]
    c: _FloatArray       # cos(delta_k) / cos(delta_k - delta_r)
    y_wheel: _FloatArray
    y_track: _FloatArray
    b: _FloatArray       # lateral relative curvature B = -(1/2) d2 g / ds2 along the plane [1/mm]


#: Smallest approach [mm] the search for the approach carrying a wheel load starts from.
MIN_APPROACH_MM = 1e-12

def _gradient(f: _FloatArray, s: _FloatArray) -> _FloatArray:
    """``np.gradient(f, s)`` of a 1-D array on strictly increasing samples (>= 3), the same
    formulas (second-order central differences on the uneven samples, first-order one-sided
    at the ends) without numpy's generic axis handling, which cost more than the sums."""
    dx = np.diff(s)
    dx1, dx2 = dx[:-1], dx[1:]
    out = np.empty_like(f)
    a = -(dx2) / (dx1 * (dx1 + dx2))
    b = (dx2 - dx1) / (dx1 * dx2)
    c = dx1 / (dx2 * (dx1 + dx2))
    out[1:-1] = a * f[:-2] + b * f[1:-1] + c * f[2:]
    out[0] = (f[1] - f[0]) / dx[0]
    out[-1] = (f[-1] - f[-2]) / dx[-1]
    return out


def _plane_samples(locus: WheelLocus, row: int, region: PatchRegion, extend_mm: float
                   ) -> _PlaneSamples:
    m = locus.gap_mm.shape[1]
    step = float(np.median(np.diff(locus.arc_length_mm)))
    n_ext = int(np.ceil(extend_mm / step)) + 2
    lo = max(int(region.samples.min()) - n_ext, 0)
    hi = min(int(region.samples.max()) + n_ext + 1, m)
    idx = np.arange(lo, hi)
    idx = idx[locus.valid[row, idx]]
    dr = region.contact_angle_rad
    sign = locus.sign
    dy = locus.y_track_mm[row, idx] - region.y_track_mm
    dz = locus.z_rail_mm[row, idx] - region.z_rail_mm
    s = sign * np.cos(dr) * dy - np.sin(dr) * dz
    # keep the monotone run of s that contains the patch
    if s.size < 2:
        raise ValueError("patch: fewer than 2 locus samples across it")
    inc = np.diff(s) > 0
    # the monotone run through the deepest sample of the patch (always interpenetrating)
    deepest = int(region.samples[np.argmin(locus.gap_mm[row, region.samples])])
    centre = int(np.clip(np.searchsorted(idx, deepest), 0, s.size - 1))
    # the run of equal directions around it: from after the last change below the centre
    # to the first change at or above it
    other = inc != inc[min(centre, inc.size - 1)]
    below = np.flatnonzero(other[:centre])
    above = np.flatnonzero(other[centre:])
    keep_lo = int(below[-1]) + 1 if below.size else 0
    keep_hi = centre + int(above[0]) + 1 if above.size else s.size
    sel = slice(keep_lo, keep_hi)
    idx, s = idx[sel], s[sel]
    order = np.argsort(s)
    idx, s = idx[order], s[order]
    delta = locus.contact_angle_rad[row, idx]
    g = locus.gap_mm[row, idx]
    c = np.cos(delta) / np.cos(delta - dr)
    gn = g * c
    if s.size >= 3:
        b = 0.5 * _gradient(_gradient(gn, s), s)  # B = (1/2) d2(h)/ds2, > 0 convex
    else:
        b = np.full(s.shape, np.nan)
    return _PlaneSamples(s=s, g=g, x=locus.x_track_mm[row, idx] - region.x_track_mm,
                         a=locus.curvature_a_per_mm[idx], c=c,
                         y_wheel=locus.y_wheel_mm[idx], y_track=locus.y_track_mm[row, idx],
                         b=b)


def _lattice(lo: float, hi: float, step: float) -> _FloatArray:
    """Element centres (k + 1/2) step covering [lo, hi], at least 3: a grid anchored to one
    lattice whatever the extent, so that as the approach grows the patch gains elements at its
    margin (out of contact) instead of every element moving, which made the discrete force a
    jumping function of the approach (up to 6 % of the load on measured wheels)."""
    k0 = int(np.floor(lo / step))
    k1 = max(int(np.ceil(hi / step)), k0 + 3)
    return np.asarray((np.arange(k0, k1) + 0.5) * step, dtype=np.float64)


def _grid(ps: _PlaneSamples, approach_mm: float, element_mm: float, margin_mm: float,
          max_elements: int | None = None) -> tuple[_FloatArray, _FloatArray, _FloatArray]:
    """Normal gap h(x, s) [mm] on the patch grid at vertical approach d (module docstring);
    ``max_elements`` caps the elements per direction (coarser elements, same extent; on the
    lattice of ``_lattice`` per direction)."""
    pen = approach_mm - ps.g
    inside = pen > 0
    if not np.any(inside):
        raise ValueError("no interpenetration at this approach")
    half = np.sqrt(np.clip(pen, 0.0, None) / ps.a)
    s_lo = ps.s[inside].min() - margin_mm
    s_hi = ps.s[inside].max() + margin_mm
    x_lo = np.min((ps.x - half)[inside]) - margin_mm
    x_hi = np.max((ps.x + half)[inside]) + margin_mm
    def step(extent: float) -> float:
        # the fine grid: element_mm (CONTACT's 0.2 mm); the coarse one 20-24 elements over
        # the extent, sizes from the ladder element_mm * 2^(k/4), so that a growing patch
        # keeps its elements until the ladder's next rung
        if max_elements is None:
            return element_mm
        rung = np.ceil(4.0 * np.log2(extent / (element_mm * max_elements)))
        return float(element_mm * 2.0 ** (rung / 4.0))

    s = _lattice(s_lo, s_hi, step(s_hi - s_lo))
    x = _lattice(x_lo, x_hi, step(x_hi - x_lo))
    g = np.interp(s, ps.s, ps.g, left=np.inf, right=np.inf)
    xs = np.interp(s, ps.s, ps.x)
    a = np.interp(s, ps.s, ps.a)
    c = np.interp(s, ps.s, ps.c)
    h = (g[:, None] + a[:, None] * (x[None, :] - xs[:, None]) ** 2 - approach_mm) * c[:, None]
    h = np.where(np.isfinite(h), h, 1e3)
    return h, x, s


def _finish(region: PatchRegion, method: str, ps: _PlaneSamples, x: _FloatArray,
            s: _FloatArray, p: _FloatArray) -> NormalPatch:
    dx = float(x[1] - x[0])
    ds = float(s[1] - s[0])
    fn = float(p.sum() * dx * ds)
    contact = p > 0
    if fn <= 0 or not np.any(contact):
        return NormalPatch(region, method, 0.0, x, s, p, 0.0, 0.0, 0.0, 0.0,
                           region.y_wheel_mm, region.y_track_mm, 0.0, 0.0)
    cx = float((p.sum(axis=0) * x).sum() / p.sum())
    cs = float((p.sum(axis=1) * s).sum() / p.sum())
    rows = np.flatnonzero(contact.any(axis=1))
    b = 0.5 * (s[rows[-1]] - s[rows[0]] + ds)
    area = float(np.count_nonzero(contact) * dx * ds)
    return NormalPatch(
        region=region, method=method, normal_force_n=fn, x_mm=x, s_mm=s, pressure_mpa=p,
        peak_pressure_mpa=float(p.max()), area_mm2=area, centre_x_mm=cx, centre_s_mm=cs,
        centre_y_wheel_mm=float(np.interp(cs, ps.s, ps.y_wheel)),
        centre_y_track_mm=float(np.interp(cs, ps.s, ps.y_track)),
        a_mm=area / (np.pi * b), b_mm=float(b))


def curvature_spread(ps: _PlaneSamples, approach_mm: float) -> tuple[float, float]:
    """(mean, relative spread) of the lateral relative curvature B over the interpenetration
    region, weighted by pen^(3/2) (pen = d - g, the Hertz-like pressure weight): the spread
    is the weighted standard deviation over the weighted mean (inf where B <= 0 or fewer
    than 3 samples span the region)."""
    pen = np.clip(approach_mm - ps.g, 0.0, None)
    inside = pen > 0
    if np.count_nonzero(inside) < 3 or not np.all(np.isfinite(ps.b[inside])):
        return float("nan"), float("inf")
    w = pen[inside] ** 1.5
    b = ps.b[inside]
    mean = float(np.sum(w * b) / np.sum(w))
    if mean <= 0:
        return mean, float("inf")
    return mean, float(np.sqrt(np.sum(w * (b - mean) ** 2) / np.sum(w)) / mean)


def is_elliptic(ps: _PlaneSamples, approach_mm: float) -> bool:
    """Hertz criterion ("auto", module docstring): the weighted relative spread of B across
    the interpenetration region (``curvature_spread``) is below
    ``HERTZ_CURVATURE_VARIATION``, and B > 0 (convex)."""
    _, spread = curvature_spread(ps, approach_mm)
    return bool(spread < HERTZ_CURVATURE_VARIATION)


def _hertz_patch(region: PatchRegion, ps: _PlaneSamples, approach_mm: float,
                 young_mpa: float, poisson: float, element_mm: float) -> NormalPatch:
    k = int(np.argmin(ps.g))
    c_ref = float(ps.c[k])
    a_curv = float(ps.a[k]) * c_ref
    b_curv = float(ps.b[k])
    unit = hertz_contact(1.0, a_curv, b_curv, young_mpa, poisson)
    delta_n = max(approach_mm - float(ps.g.min()), 0.0) * c_ref
    fn = float((delta_n / float(unit.approach_mm)) ** 1.5)
    # a, b and p0 grow as F^(1/3) for a fixed geometry (Johnson 1985 eqs. 4.39 ff.): the unit
    # force's ellipse scaled, not a second solve of the ellipse's shape
    scale = float(np.cbrt(fn))
    a, b = float(unit.a_mm) * scale, float(unit.b_mm) * scale
    p0 = float(unit.p0_mpa) * scale
    s0 = float(ps.s[np.argmin(ps.g)])
    x = np.arange(-a, a + element_mm, element_mm)
    s = s0 + np.arange(-b, b + element_mm, element_mm)
    if x.size < 3 or s.size < 3:
        x = np.linspace(-a, a, 5)
        s = s0 + np.linspace(-b, b, 5)
    rho = 1.0 - (x[None, :] / a) ** 2 - ((s[:, None] - s0) / b) ** 2 if fn > 0 else -np.ones(
        (s.size, x.size))
    p = p0 * np.sqrt(np.clip(rho, 0.0, None))
    if not fn > 0:
        return _finish(region, "hertz", ps, x, s, p)
    # exact Hertz totals instead of the sampled ones
    return NormalPatch(region, "hertz", fn, x, s, p, p0, float(np.pi * a * b),
                       0.0, s0, float(np.interp(s0, ps.s, ps.y_wheel)),
                       float(np.interp(s0, ps.s, ps.y_track)), a, b)


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


def _kp_patch(region: PatchRegion, ps: _PlaneSamples, approach_mm: float, young_mpa: float,
              poisson: float, element_mm: float, margin_mm: float) -> NormalPatch:
    e_star = effective_modulus_mpa(young_mpa, poisson)
    h, x, s = _grid(ps, approach_mm, element_mm, margin_mm)
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
        return _finish(region, "kp", ps, x, s, np.zeros_like(h))
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
    return _finish(region, "kp", ps, x, s, p)


def warm_pressure(previous: NormalPatch | None, x: _FloatArray, s: _FloatArray
                  ) -> _FloatArray | None:
    """A start pressure on the grid (x, s) [mm] from a nearby solution ``previous`` (the same
    patch at a slightly different load or approach: an earlier round of the normal /
    tangential coupling or of the approach iteration): its pressure interpolated bilinearly
    onto the grid (0 outside it), or None when it carries no pressure."""
    if previous is None or not previous.normal_force_n > 0 or previous.x_mm.size < 2 or (
            previous.s_mm.size < 2):
        return None
    px, ps_ = previous.x_mm, previous.s_mm
    fx = (x - px[0]) / (px[1] - px[0])
    fs = (s - ps_[0]) / (ps_[1] - ps_[0])
    ix = np.clip(np.floor(fx).astype(np.intp), 0, px.size - 2)
    js = np.clip(np.floor(fs).astype(np.intp), 0, ps_.size - 2)
    tx = np.clip(fx - ix, 0.0, 1.0)
    ts = np.clip(fs - js, 0.0, 1.0)
    inside = ((fx >= 0) & (fx <= px.size - 1))[None, :] & ((fs >= 0) & (fs <= ps_.size - 1))[
        :, None]
    p = previous.pressure_mpa
    out = ((1 - ts)[:, None] * ((1 - tx)[None, :] * p[np.ix_(js, ix)]
                                + tx[None, :] * p[np.ix_(js, ix + 1)])
           + ts[:, None] * ((1 - tx)[None, :] * p[np.ix_(js + 1, ix)]
                            + tx[None, :] * p[np.ix_(js + 1, ix + 1)]))
    out = np.where(inside, out, 0.0)
    return out if out.sum() > 0 else None


def patch_normal_contact(locus: WheelLocus, row: int, region: PatchRegion, approach_mm: float,
                         method: str = "auto", young_mpa: float = STEEL_YOUNG_MPA,
                         poisson: float = STEEL_POISSON, element_mm: float = 0.2,
                         margin_mm: float = 0.6, warm: NormalPatch | None = None
                         ) -> NormalPatch:
    """Normal contact of one patch at vertical approach d [mm] (module docstring).

    Parameters
    ----------
    locus, row : contact locus and pose index
    region : the patch (``patches.patch_regions`` at the same approach)
    approach_mm : rigid vertical approach d [mm] (the gap of the locus is 0 at first touch)
    method : "bem", "kp", "hertz" or "auto"
    element_mm : element size of the grid [mm] (CONTACT's DX = DS = 0.2 mm)
    margin_mm : grid margin around the interpenetration region [mm]
    warm : optional nearby solution of the same patch to start the BEM from
        (``warm_pressure``; the same solution to the solver's tolerance, fewer iterations)
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, not {method!r}")
    ps = _plane_samples(locus, row, region, extend_mm=margin_mm + 2.0 * element_mm)
    if method == "auto":
        method = "hertz" if is_elliptic(ps, approach_mm) else "bem-coarse"
    if method == "hertz" and float(ps.b[np.argmin(ps.g)]) <= 0:
        raise ValueError("Hertz needs a convex patch (B > 0); use 'kp' or 'bem' here")
    if method == "hertz":
        return _hertz_patch(region, ps, approach_mm, young_mpa, poisson, element_mm)
    if method == "kp":
        return _kp_patch(region, ps, approach_mm, young_mpa, poisson, element_mm, margin_mm)
    coarse = method == "bem-coarse"
    h, x, s = _grid(ps, approach_mm, element_mm, margin_mm,
                    COARSE_ELEMENTS if coarse else None)
    res = solve_normal_bem(h, x, s, approach_mm=0.0, young_mpa=young_mpa, poisson=poisson,
                           tol=1e-6 if coarse else 1e-7,
                           initial_pressure_mpa=warm_pressure(warm, x, s))
    return _finish(region, method, ps, x, s, res.pressure_mpa)


def _single_patch_by_force(locus: WheelLocus, row: int, load_n: float, ratio: float,
                           approach_mm: float, method: str, young_mpa: float, poisson: float,
                           element_mm: float, margin_mm: float = 0.6,
                           warm: NormalPatch | None = None
                           ) -> tuple[float, NormalPatch] | None:
    """Fast path of ``wheel_normal_contact`` for a single patch: its normal force is known
    from the load, F_n = W / (cos delta + r sin delta), so the BEM (or Hertz) is solved with
    the force prescribed and returns the approach; the patch is re-identified at that
    approach until it settles (2-3 solves instead of a bracketing iteration).  None when
    there is not exactly one patch or the method has no force-prescribed form ("kp").
    ``warm``: a nearby solution to start the BEM from (``warm_pressure``); each re-solve
    starts from the previous one."""
    d = approach_mm
    for _ in range(6):
        regions = patch_regions(locus, row, d)
        if len(regions) != 1:
            return None
        region = regions[0]
        fn = load_n / max(np.cos(region.contact_angle_rad)
                          + ratio * np.sin(region.contact_angle_rad), 0.05)
        ps = _plane_samples(locus, row, region, extend_mm=margin_mm + 2.0 * element_mm)
        chosen = method
        if chosen == "auto":
            chosen = "hertz" if is_elliptic(ps, d) else "bem-coarse"
        k = int(np.argmin(ps.g))
        c_min = float(ps.c[k])
        if chosen == "hertz":
            if float(ps.b[k]) <= 0:
                return None
            unit = hertz_contact(1.0, float(ps.a[k]) * c_min, float(ps.b[k]), young_mpa,
                                 poisson)
            d_new = float(ps.g[k]) + float(unit.approach_mm) * fn ** (2.0 / 3.0) / c_min
            patch = _hertz_patch(region, ps, d_new, young_mpa, poisson, element_mm)
        elif chosen in ("bem", "bem-coarse"):
            coarse = chosen == "bem-coarse"
            h, x, s = _grid(ps, d, element_mm, margin_mm, COARSE_ELEMENTS if coarse else None)
            res = solve_normal_bem(h, x, s, normal_force_n=fn, young_mpa=young_mpa,
                                   poisson=poisson, tol=1e-6 if coarse else 1e-7,
                                   initial_pressure_mpa=warm_pressure(warm, x, s))
            border = np.concatenate([res.pressure_mpa[0], res.pressure_mpa[-1],
                                     res.pressure_mpa[:, 0], res.pressure_mpa[:, -1]])
            d_new = d + res.approach_mm / c_min
            patch = _finish(region, chosen, ps, x, s, res.pressure_mpa)
            warm = patch
            if np.any(border > 0):  # the grid was too small: grow it and solve again
                d = max(d_new, 1.2 * d)
                continue
        else:
            return None
        if abs(d_new - d) <= 1e-3 * abs(d_new):
            return d_new, patch
        d = d_new
    return None


def wheel_normal_contact(locus: WheelLocus, wheel_load_n: float | NDArray[np.float64],
                         method: str = "auto", lateral_ratio: list[list[float]] | None = None,
                         young_mpa: float = STEEL_YOUNG_MPA, poisson: float = STEEL_POISSON,
                         element_mm: float = 0.2, rtol: float = 1e-4,
                         approach_guess_mm: ArrayLike | None = None,
                         patch_guess: Sequence[Sequence[NormalPatch]] | None = None
                         ) -> list[WheelNormalContact]:
    """Patches of one wheel carrying its vertical load W, for every pose of the locus.

    The common vertical approach d solves sum_i F_n,i(d) (cos delta_i + r_i sin delta_i) = W
    (r_i = F_s/F_n from ``lateral_ratio``, default 0) by bracketing and the Illinois
    (regula falsi) iteration to ``rtol`` of W; the patches are re-identified at every d
    (``patches.patch_regions``), so merging and splitting follow the load.  A single patch
    takes a fast path: its force is known, so it is solved with the force prescribed and the
    approach follows (``_single_patch_by_force``).  ``approach_guess_mm`` (per pose,
    optional) starts either iteration near a known solution; ``patch_guess`` (per pose, the
    patches of a nearby solution, e.g. the previous round of the normal / tangential
    coupling) starts the BEM solves from their pressures (``warm_pressure``).

    Returns one ``WheelNormalContact`` per pose; module docstring for the patch fields.
    """
    n = locus.gap_mm.shape[0]
    loads = np.broadcast_to(np.asarray(wheel_load_n, dtype=float), (n,))
    if np.any(loads <= 0):
        raise ValueError("wheel_load_n must be positive")
    out = []
    for row in range(n):
        ratios = lateral_ratio[row] if lateral_ratio is not None else None
        guesses: list[NormalPatch] = list(patch_guess[row]) if patch_guess is not None else []

        def solve(d: float, row: int = row, ratios: list[float] | None = ratios,
                  guesses: list[NormalPatch] = guesses) -> tuple[float, list[NormalPatch]]:
            regions = patch_regions(locus, row, d)
            warm = guesses if len(guesses) == len(regions) else []
            patches = [patch_normal_contact(locus, row, reg, d, method, young_mpa, poisson,
                                            element_mm, warm=warm[k] if warm else None)
                       for k, reg in enumerate(regions)]
            guesses[:] = patches
            total = 0.0
            for k, p in enumerate(patches):
                r = ratios[k] if ratios is not None and k < len(ratios) else 0.0
                total += p.normal_force_n * max(np.cos(p.contact_angle_rad)
                                                + r * np.sin(p.contact_angle_rad), 0.05)
            return total, patches

        load = float(loads[row])
        if approach_guess_mm is not None:
            start = float(np.broadcast_to(np.asarray(approach_guess_mm, dtype=float), (n,))[row])
        else:
            start = 0.03 * (load / 1e4) ** (2.0 / 3.0)
        fast = _single_patch_by_force(locus, row, load, ratios[0] if ratios else 0.0, start,
                                      method, young_mpa, poisson, element_mm,
                                      warm=guesses[0] if len(guesses) == 1 else None)
        if fast is not None:
            out.append(WheelNormalContact(approach_mm=fast[0], patches=[fast[1]]))
            continue
        lo, f_lo = 0.0, -load
        if approach_guess_mm is not None:
            guess = float(np.broadcast_to(np.asarray(approach_guess_mm, dtype=float), (n,))[row])
            f_g, patches = solve(0.98 * guess)
            if f_g - load < 0:
                lo, f_lo = 0.98 * guess, f_g - load
            hi = 1.02 * guess if f_g - load < 0 else 0.98 * guess
        else:
            # Hertz-like first guess from a 10 kN wheel on a tread: d ~ 0.03 mm (W/10 kN)^(2/3)
            hi = 0.03 * (load / 1e4) ** (2.0 / 3.0)
        # a first guess that underflowed to 0 (a load near the smallest float) would be
        # doubled for ever: start the doubling from the smallest approach tried
        hi = max(hi, MIN_APPROACH_MM)
        f_hi, patches = solve(hi)
        f_hi -= load
        while f_hi < 0:
            lo, f_lo = hi, f_hi
            hi *= 2.0
            f_hi, patches = solve(hi)
            f_hi -= load
            if hi > 5.0:
                raise NoContactError("wheel", "no approach up to 5 mm carries the wheel load: "
                                     "the wheel does not reach its rail")
        side = 0
        d = hi
        best = (np.inf, d, patches)  # (|residual|, approach, patches)
        for _ in range(60):
            d = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
            f, patches = solve(d)
            f -= load
            if abs(f) < best[0]:
                best = (abs(f), d, patches)
            if abs(f) < rtol * load or hi - lo < 1e-7 * hi:
                break
            if f > 0:
                hi, f_hi = d, f
                if side == 1:
                    f_lo *= 0.5
                side = 1
            else:
                lo, f_lo = d, f
                if side == -1:
                    f_hi *= 0.5
                side = -1
        else:
            raise RuntimeError("normal contact: the approach iteration did not converge")
        residual = 0.0
        if best[0] >= rtol * load:
            # the bracket closed on a jump of the force-approach curve: where two patches
            # merge (or a patch's region changes) no approach carries exactly the load; the
            # side nearer it is taken and the difference reported (``load_residual_n``)
            d, patches = best[1], best[2]
            residual = float(sum(p.normal_force_n * np.cos(p.contact_angle_rad)
                                 for p in patches)) - load
        out.append(WheelNormalContact(approach_mm=float(d), patches=patches,
                                      load_residual_n=residual))
    return out
