"""The planar patch problem: a contact patch sampled in its contact plane, and its grid.

Each patch is solved in its contact plane (CONTACT's planar approach: the plane through the
reference point at the reference angle delta_r; Vollebregt, CONTACT user guide). A locus
sample k lies at the lateral coordinate s_k = e_s . (P_k - P_ref) of the plane
(e_s = (sign cos delta_r, -sin delta_r) in track (y, z)); the undeformed normal gap at
(x, s_k) at vertical approach d is

    h(x, s_k) = (g_k + A_k (x - x_k)^2 - d) cos(delta_k) / cos(delta_k - delta_r),

the vertical gap turned into the distance along the plane normal (exact for locally parallel
surfaces), interpolated in s onto a grid of ``element_mm`` (CONTACT's 0.2 mm) elements
(``patch_grid``). ``plane_samples`` takes the locus samples of one patch into the plane;
``finish_patch`` turns a pressure on the grid into a :class:`NormalPatch` (force, area,
pressure centre, equivalent ellipse). The methods that fill the grid are in
``normal_contact`` (Hertz, BEM) and ``kik_piotrowski``.

Units: mm, MPa, N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.contact.locus import WheelLocus
from wearcast.physics.contact.patches import PatchRegion

_FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class NormalPatch:
    """Solved normal contact of one patch (``normal_contact``'s docstring, "API")."""

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
class PlaneSamples:
    s: _FloatArray       # lateral plane coordinate of the samples, ascending
    g: _FloatArray       # vertical gap [mm]
    x: _FloatArray       # locus x relative to the reference [mm]
    a: _FloatArray       # rolling curvature A [1/mm]
    c: _FloatArray       # cos(delta_k) / cos(delta_k - delta_r)
    y_wheel: _FloatArray
    y_track: _FloatArray
    b: _FloatArray       # lateral relative curvature B = -(1/2) d2 g / ds2 along the plane [1/mm]


def gradient(f: _FloatArray, s: _FloatArray) -> _FloatArray:
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


def plane_samples(locus: WheelLocus, row: int, region: PatchRegion, extend_mm: float
                   ) -> PlaneSamples:
    m = locus.gap_mm.shape[1]
    step = locus.arc_step_mm
    n_ext = math.ceil(extend_mm / step) + 2
    lo = max(int(region.samples.min()) - n_ext, 0)
    hi = min(int(region.samples.max()) + n_ext + 1, m)
    idx = lo + np.flatnonzero(locus.valid[row, lo:hi])
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
    centre = min(max(int(np.searchsorted(idx, deepest)), 0), s.size - 1)
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
        b = 0.5 * gradient(gradient(gn, s), s)  # B = (1/2) d2(h)/ds2, > 0 convex
    else:
        b = np.full(s.shape, np.nan)
    return PlaneSamples(s=s, g=g, x=locus.x_track_mm[row, idx] - region.x_track_mm,
                         a=locus.curvature_a_per_mm[idx], c=c,
                         y_wheel=locus.y_wheel_mm[idx], y_track=locus.y_track_mm[row, idx],
                         b=b)


def lattice(lo: float, hi: float, step: float) -> _FloatArray:
    """Element centres (k + 1/2) step covering [lo, hi], at least 3: a grid anchored to one
    lattice whatever the extent, so that as the approach grows the patch gains elements at its
    margin (out of contact) instead of every element moving, which made the discrete force a
    jumping function of the approach (up to 6 % of the load on measured wheels)."""
    k0 = int(np.floor(lo / step))
    k1 = max(int(np.ceil(hi / step)), k0 + 3)
    return np.asarray((np.arange(k0, k1) + 0.5) * step, dtype=np.float64)


def patch_grid(ps: PlaneSamples, approach_mm: float, element_mm: float, margin_mm: float,
          max_elements: int | None = None) -> tuple[_FloatArray, _FloatArray, _FloatArray]:
    """Normal gap h(x, s) [mm] on the patch grid at vertical approach d (module docstring);
    ``max_elements`` caps the elements per direction (coarser elements, same extent; on the
    lattice of ``_lattice`` per direction)."""
    pen = approach_mm - ps.g
    inside = pen > 0
    if not np.any(inside):
        raise ValueError("no interpenetration at this approach")
    half = np.sqrt(np.maximum(pen, 0.0) / ps.a)
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

    s = lattice(s_lo, s_hi, step(s_hi - s_lo))
    x = lattice(x_lo, x_hi, step(x_hi - x_lo))
    g = np.interp(s, ps.s, ps.g, left=np.inf, right=np.inf)
    xs = np.interp(s, ps.s, ps.x)
    a = np.interp(s, ps.s, ps.a)
    c = np.interp(s, ps.s, ps.c)
    h = (g[:, None] + a[:, None] * (x[None, :] - xs[:, None]) ** 2 - approach_mm) * c[:, None]
    h = np.where(np.isfinite(h), h, 1e3)
    return h, x, s


def finish_patch(region: PatchRegion, method: str, ps: PlaneSamples, x: _FloatArray,
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
