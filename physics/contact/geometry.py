"""Rigid wheel-rail contact geometry of a wheelset on a straight track, with optional yaw.

For a prescribed lateral shift of the wheelset, the roll angle and the height of the
wheelset are solved so that each wheel touches its rail (minimum vertical gap zero on both
sides), and every contact point is reported: the primary (gap 0) and, where the profiles
approach each other a second time within a tolerance, a secondary patch (two-point contact,
typically tread + flange).  Background: seed 000 §V, seed 002 §2, seed 004 §2 (contact search
before Hertz/FASTSIM); the case is the Manchester contact benchmark (docs/references.md).

Frames and signs (read this before using the results)
------------------------------------------------------
Track frame (ISO 8855-like, seen from behind in the running direction):
  x along the track (running direction), **y lateral, positive to the LEFT**, z up.
  Origin: track centre line, at the height of the top of the (un-inclined) rails.
  The rails are upright rail profiles turned about their top by the inclination, with the
  gauge points (``gauge_height_mm`` below the highest point of each inclined rail, innermost
  point) at y = +/- gauge_mm / 2.
Wheelset pose:
  ``shift_mm`` lateral displacement of the wheelset centre, **positive towards the left
  rail** (so the left flange closes up).  ``roll_rad`` rotation about +x, **positive when the
  left wheel rises**.  ``height_mm`` vertical displacement of the axle from its nominal
  position (tape circles of radius r0 standing on the rail tops at z = 0).
Wheel frame (per wheel, docs/conventions.md): ``y_wheel_mm`` from the tape circle, negative towards
the
  flange, i.e. positive towards the wheel's outer (field) face for both wheels; z = radius
  increase over the nominal radius r0.  The left wheel's tape circle is at y_ws = +d/2, the
  right one at -d/2 in the wheelset frame, d = flange_back_distance + 2 * tape offset (1500).
Rail frame (per rail): ``y_rail_mm`` in the rail profile's own frame (upright rail, top at
  (0, 0), gauge side y < 0 — as ``profiles.rails``); for a rail given already inclined
  (``rail_inclination = 0``) its own frame as given.
Contact angle ``contact_angle_rad`` (delta): angle of the common tangent to the track plane,
  measured in the wheel's outward-lateral / downward plane: delta = atan(d z_down / d u) with u
  lateral away from the track centre, taken from the rail's tangent (the rail is prismatic,
  so the contact normal lies in the cross-section, with or without yaw).  **Negative on a
  normal tread and on the flange** (the rail pushes the wheel towards the track centre):
  about -0.03 on the tread, -1.2 on the S1002 flange.  This is CONTACT's sign for the right
  wheel (and minus CONTACT's printed value for its mirrored left wheel).
Rolling radius ``rolling_radius_mm`` = r0 + z_wheel at the contact point.
Curvatures for Hertz: the undeformed gap near the contact is A x^2 + B y^2 (seed 000 eq. 9),
  ``curvature_a_per_mm`` = A = cos(gamma) / (2 r), the wheel's circumferential curvature
  (gamma = profile angle in the wheel frame; a straight rail adds nothing), and
  ``curvature_b_per_mm`` = B = (k_wheel + k_rail) / 2 with k the lateral profile curvatures,
  positive where a surface is convex towards the other body.  A or B is negative where the
  sum is not convex (conformal contact); Hertz then does not apply.
Yaw ``yaw_rad`` (psi, about +z, positive turning the front of the wheelset to the left): the
  wheels are surfaces of revolution and the rails prismatic, so for each wheel circle the
  point nearest the rail is turned about the axle by theta with tan(theta) = sin(psi) x rail
  slope (the stationary point of the vertical gap); a flange contact then leads or trails the
  axle (``x_track_mm``) and the effective flangeway shrinks (by ~0.3 mm at 15 mrad).  The
  curvatures A, B keep their zero-yaw form (their yaw change is second order).  With yaw = 0
  the result is the 2D cross-section through the axle.
Two-point contact: a second local minimum of the gap whose gap is at most
  ``two_point_gap_mm`` (default 0.05 mm: above the elastic approach of the bodies under a
  10 kN wheel load, 16-36 um in the Manchester A-2.2 results, so a second point that close
  can carry load once the first is compressed; heavier loads approach further) and which
  is separated from the primary by a rise of the gap of at least ``separation_mm``.  Its gap
  is reported so that a normal-contact model can share the load itself.

All solutions are vectorised over shifts: ``contact_table`` for an array of shifts is the main
entry point; ``contact_points`` is a convenience for one shift.  Valid for shifts up to a few
mm beyond flange contact (before the flange climbs over the rail) and |yaw| <= 0.1 rad.  The
result types are in ``geometry_results``; a table's equivalent conicity in
``equivalent_conicity``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.geometry_results import (
    ContactPatches,
    ContactPoint,
    ContactTable,
    WheelContacts,
    WheelsetContact,
)
from wearcast.physics.contact.min_gap_kernel import gap_rows_no_yaw, min_gap_no_yaw
from wearcast.physics.profiles.measured import ProfileCurve, rail_curve, s1002_curve
from wearcast.physics.vocabulary import check_side

_FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class WheelsetTrack:
    """A wheelset (left wheel profile, mirrored right wheel) on a track (two rails).

    Parameters
    ----------
    wheel : wheel profile in the wheel frame (docs/conventions.md), used for the left wheel and,
    mirrored,
        for the right wheel unless ``wheel_right`` is given
    rail : rail profile in the upright rail frame (gauge side y < 0), used for both rails unless
        ``rail_right`` is given; it is inclined by ``rail_inclination`` here
    nominal_radius_mm : r0, the wheel radius at the tape circle [mm]
    flange_back_distance_mm : distance between the wheels' back faces [mm]
    tape_circle_offset_mm : tape circle from the back face [mm] (70)
    gauge_mm : track gauge [mm], measured ``gauge_height_mm`` below the rail top
    rail_inclination : inclination slope (1/40, 1/20; 0 for a rail given already inclined)
    wheel_sample_mm : arc-length spacing of the wheel samples of the contact search [mm]; the
        gap minimum is refined by a parabola between samples
    rail_gauge_point_mm : the rails' gauge point (y, z) in the upright rail frame [mm], when
        it is known and the rail curve does not reach it (a measured head whose lip overhangs
        the gauge face: the curve is what a wheel can touch, the gauge point lies under the
        lip); None finds it on the curve, ``gauge_height_mm`` below the inclined top
    rail_right_gauge_point_mm : the same for ``rail_right`` when it is given (its own head
        may need the known point where the left one does not); without ``rail_right`` the
        right rail is ``rail`` and takes ``rail_gauge_point_mm``
    """

    wheel: ProfileCurve
    rail: ProfileCurve
    wheel_right: ProfileCurve | None = None
    rail_right: ProfileCurve | None = None
    nominal_radius_mm: float = 460.0
    flange_back_distance_mm: float = 1360.0
    tape_circle_offset_mm: float = 70.0
    gauge_mm: float = 1435.0
    gauge_height_mm: float = 14.0
    rail_inclination: float = 1.0 / 40.0
    wheel_sample_mm: float = 0.2
    rail_gauge_point_mm: tuple[float, float] | None = None
    rail_right_gauge_point_mm: tuple[float, float] | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def tape_circle_distance_mm(self) -> float:
        """Lateral distance between the two tape circles [mm] (1500 for 1360 + 2 x 70)."""
        return self.flange_back_distance_mm + 2.0 * self.tape_circle_offset_mm


def s1002_60e1(rail_inclination: float = 1.0 / 40.0, nominal_radius_mm: float = 460.0,
               rail: str = "60E1") -> WheelsetTrack:
    """S1002 wheels on 60E1 (or 60E2) rails, gauge 1435 mm at 14 mm, flange backs 1360 mm:
    the Manchester benchmark geometry (docs/references.md; rails 1:40 by default)."""
    return WheelsetTrack(wheel=s1002_curve(), rail=rail_curve(rail),
                         nominal_radius_mm=nominal_radius_mm, rail_inclination=rail_inclination)


# ------------------------------------------------------------------------------------------
# prepared samples
# ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Side:
    """Wheel samples (wheelset frame) and rail envelope (track frame) of one side."""

    sign: float                   # +1 left, -1 right
    wheel: ProfileCurve
    rail: ProfileCurve
    s_wheel: _FloatArray          # arc length of the wheel samples [mm]
    y_ws: _FloatArray             # wheel sample, lateral, wheelset frame [mm]
    z_ws: _FloatArray             # wheel sample, vertical, wheelset frame [mm] (= -(r0 + z))
    rail_y: _FloatArray           # rail upper envelope, track y ascending [mm]
    rail_z: _FloatArray           # rail height [mm]
    rail_slope: _FloatArray       # dz/dy in the track frame [-]
    rail_s: _FloatArray           # arc length on the rail curve [mm]
    rail_offset_mm: float         # track |y| of the rail frame origin
    inclination_rad: float


def _rail_envelope(rail: ProfileCurve, inclination: float, gauge_mm: float,
                   gauge_height_mm: float, sign: float,
                   gauge_point_mm: tuple[float, float] | None = None
                   ) -> tuple[_FloatArray, _FloatArray, _FloatArray, _FloatArray, float]:
    s = rail.sample(0.05)
    y_r, z_r = rail.point(s)
    alpha = np.arctan(inclination)
    y_i = y_r * np.cos(alpha) - z_r * np.sin(alpha)
    z_i = y_r * np.sin(alpha) + z_r * np.cos(alpha)
    if gauge_point_mm is not None:  # given (upright frame): turned with the rail
        y_gauge = gauge_point_mm[0] * np.cos(alpha) - gauge_point_mm[1] * np.sin(alpha)
        return _placed(y_i, z_i, s, float(gauge_mm / 2.0 - y_gauge), sign)
    # gauge point: innermost point gauge_height_mm below the top of the inclined rail
    z_gauge = z_i.max() - gauge_height_mm
    top = int(np.argmax(z_i))
    below = np.flatnonzero(z_i[: top + 1] < z_gauge)
    if below.size == 0:
        raise ValueError("rail profile does not reach gauge_height_mm below its top on the "
                         "gauge side (y < 0)")
    k = below[-1]
    frac = (z_gauge - z_i[k]) / (z_i[k + 1] - z_i[k])
    y_gauge = y_i[k] + frac * (y_i[k + 1] - y_i[k])
    return _placed(y_i, z_i, s, float(gauge_mm / 2.0 - y_gauge), sign)


def _placed(y_i: _FloatArray, z_i: _FloatArray, s: _FloatArray, offset: float, sign: float
            ) -> tuple[_FloatArray, _FloatArray, _FloatArray, _FloatArray, float]:
    """The inclined rail placed at ``offset`` from the track centre on side ``sign``: its
    upper envelope in track y (ascending), heights, slopes, arc lengths and the offset."""
    y_t = sign * (offset + y_i)
    # upper envelope seen from above: keep points that advance in track y
    order = np.arange(y_t.size) if sign > 0 else np.arange(y_t.size)[::-1]
    y_o, z_o, s_o = y_t[order], z_i[order], s[order]
    keep = y_o > np.maximum.accumulate(np.concatenate([[-np.inf], y_o[:-1]]))
    y_o, z_o, s_o = y_o[keep], z_o[keep], s_o[keep]
    slope = np.gradient(z_o, y_o)
    return y_o, z_o, slope, s_o, float(offset)


def _prepare(wt: WheelsetTrack) -> tuple[_Side, _Side]:
    if "sides" in wt._cache:
        return wt._cache["sides"]
    sides = []
    right_gauge = (wt.rail_gauge_point_mm if wt.rail_right is None
                   else wt.rail_right_gauge_point_mm)
    for sign, wheel, rail, gauge_point in (
            (1.0, wt.wheel, wt.rail, wt.rail_gauge_point_mm),
            (-1.0, wt.wheel_right or wt.wheel, wt.rail_right or wt.rail, right_gauge)):
        s_w = wheel.sample(wt.wheel_sample_mm)
        y_w, z_w = wheel.point(s_w)
        ry, rz, rslope, rs, offset = _rail_envelope(rail, wt.rail_inclination, wt.gauge_mm,
                                                    wt.gauge_height_mm, sign, gauge_point)
        sides.append(_Side(sign, wheel, rail, s_w,
                           sign * (wt.tape_circle_distance_mm / 2.0 + y_w),
                           -(wt.nominal_radius_mm + z_w), ry, rz, rslope, rs, offset,
                           float(np.arctan(wt.rail_inclination))))
    result = (sides[0], sides[1])
    wt._cache["sides"] = result
    return result


# ------------------------------------------------------------------------------------------
# gap evaluation
# ------------------------------------------------------------------------------------------
def _points(side: _Side, shift: _FloatArray, roll: _FloatArray, yaw: _FloatArray, r0: float,
            axial: _FloatArray, radius: _FloatArray, grid: bool
            ) -> tuple[_FloatArray, _FloatArray, _FloatArray]:
    """Track coordinates (x, y, z) of the lowest points of wheel circles, height 0.

    ``axial`` [mm] is the circle's position along the axle (wheelset frame), ``radius`` [mm] its
    radius; pose arrays have shape (N,), circle arrays (M,) with ``grid`` (results (N, M)) or
    (N,) without (one circle per pose, results (N,)).
    Without yaw the lowest point of a circle is straight below the axle.  With yaw psi the
    point of a circle nearest to the (prismatic) rail is turned by theta about the axle, where
    the vertical gap is stationary: tan(theta) = sin(psi) * rail slope there (a fixed point,
    three iterations; the contraction factor is r * psi^2 / R_rail < 0.05).  The point then
    leads (x > 0) or trails the axle by r sin(theta).
    """
    def col(a: _FloatArray) -> _FloatArray:
        return a[:, None] if grid else a

    c, s = np.cos(col(roll)), np.sin(col(roll))
    cy, sy = np.cos(col(yaw)), np.sin(col(yaw))
    lateral = axial * cy
    vertical = -radius
    y = col(shift) + lateral * c - vertical * s
    if not np.any(yaw != 0.0):  # the 2D cross-section: no trigonometry on the samples
        z = r0 + lateral * s + vertical * c
        return np.broadcast_to(-axial * sy, np.shape(y)), y, z
    sin_t = np.zeros(np.shape(y))
    for _ in range(3):
        slope = np.interp(y, side.rail_y, side.rail_slope, left=0.0, right=0.0)
        # theta = atan(slope sin(psi)): sin and cos of it without trigonometric calls
        t = slope * sy
        cos_t = 1.0 / np.sqrt(1.0 + t * t)
        sin_t = t * cos_t
        lateral = radius * sin_t * sy + axial * cy
        vertical = -radius * cos_t
        y = col(shift) + lateral * c - vertical * s
    z = r0 + lateral * s + vertical * c
    x = radius * sin_t * cy - axial * sy
    return x, y, z


def _gaps(side: _Side, shift: _FloatArray, roll: _FloatArray, yaw: _FloatArray, r0: float
          ) -> tuple[_FloatArray, _FloatArray]:
    """Vertical gaps (N, M) of the wheel samples over the rail and their track y, height 0."""
    _, y, z = _points(side, shift, roll, yaw, r0, side.y_ws, -side.z_ws, grid=True)
    z_rail = np.interp(y, side.rail_y, side.rail_z, left=np.nan, right=np.nan)
    gap = z - z_rail
    return np.where(np.isfinite(gap), gap, np.inf), y


def _three_samples(gap: _FloatArray, idx: NDArray[np.intp]
                   ) -> tuple[_FloatArray, _FloatArray, _FloatArray, _FloatArray,
                              NDArray[np.bool_]]:
    """Each row's sampled minimum at ``idx`` and its neighbours (gm, g0, gp), their second
    difference gm - 2 g0 + gp, and where a parabola through them has a minimum (an interior
    sample, finite and positive curvature)."""
    rows = np.arange(gap.shape[0])
    m = gap.shape[1]
    g0 = gap[rows, idx]
    gm = gap[rows, np.clip(idx - 1, 0, m - 1)]
    gp = gap[rows, np.clip(idx + 1, 0, m - 1)]
    with np.errstate(invalid="ignore"):
        curv = gm - 2.0 * g0 + gp
    ok = (idx > 0) & (idx < m - 1) & np.isfinite(curv) & (curv > 0)
    return gm, g0, gp, curv, ok


def _refine(gap: _FloatArray, idx: NDArray[np.intp]) -> tuple[_FloatArray, _FloatArray]:
    """Parabolic refinement of a sampled minimum: (minimum value, offset in samples)."""
    gm, g0, gp, curv, ok = _three_samples(gap, idx)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(ok, 0.5 * (gm - gp) / np.where(ok, curv, 1.0), 0.0)
    t = np.clip(t, -0.5, 0.5)
    with np.errstate(invalid="ignore"):
        value = g0 - 0.25 * (gm - gp) * t
    return np.where(ok, value, g0), t


def _min_gap(side: _Side, shift: _FloatArray, roll: _FloatArray, yaw: _FloatArray, r0: float
             ) -> tuple[_FloatArray, _FloatArray]:
    """Minimum gap (N,) and its derivative with respect to roll (N,) (yaw neglected in it).

    Without yaw (the cross-section) from the compiled kernel ``min_gap_kernel.min_gap_no_yaw``
    (one pose at a time), else from the (N, M) gaps (``_min_gap_numpy``, the kernel's
    reference)."""
    if not np.any(yaw != 0.0):
        return min_gap_no_yaw(side.y_ws, side.z_ws, side.rail_y, side.rail_z, side.rail_slope,
                              np.ascontiguousarray(shift, dtype=float),
                              np.ascontiguousarray(roll, dtype=float), float(r0))
    return _min_gap_numpy(side, shift, roll, yaw, r0)


def _min_gap_numpy(side: _Side, shift: _FloatArray, roll: _FloatArray, yaw: _FloatArray,
                   r0: float) -> tuple[_FloatArray, _FloatArray]:
    """:func:`_min_gap` from the (N, M) gap array (any yaw). The derivative is that of the
    parabola-refined minimum (:func:`_refined_rate`) from each of its three samples' rates
    d gap / d roll = d z / d roll - rail slope x d y / d roll, the rail slope being that of
    the linear interpolation the gap takes (yaw neglected in the rates)."""
    gap, y = _gaps(side, shift, roll, yaw, r0)
    idx = np.argmin(gap, axis=1)
    value, _ = _refine(gap, idx)
    rows = np.arange(gap.shape[0])
    m = gap.shape[1]
    c, s = np.cos(roll), np.sin(roll)
    dz_dy = np.diff(side.rail_z) / np.diff(side.rail_y)  # np.interp's interval slopes

    def rate(p: NDArray[np.intp]) -> _FloatArray:
        y_p = y[rows, p]
        j = np.clip(np.searchsorted(side.rail_y, y_p, side="right") - 1, 0, dz_dy.size - 1)
        slope = np.where(y_p <= side.rail_y[0], side.rail_slope[0],
                         np.where(y_p >= side.rail_y[-1], side.rail_slope[-1], dz_dy[j]))
        yw, zw = side.y_ws[p], side.z_ws[p]
        return (yw * c - zw * s) - slope * (-yw * s - zw * c)

    d0 = rate(idx)
    gm, g0, gp, _, ok = _three_samples(gap, idx)
    dm = rate(np.clip(idx - 1, 0, m - 1))
    dp = rate(np.clip(idx + 1, 0, m - 1))
    return value, np.where(ok, _refined_rate(gm, g0, gp, dm, d0, dp, ok), d0)


def _refined_rate(gm: _FloatArray, g0: _FloatArray, gp: _FloatArray, dm: _FloatArray,
                  d0: _FloatArray, dp: _FloatArray, ok: NDArray[np.bool_]) -> _FloatArray:
    """Derivative of :func:`_refine`'s minimum g0 - (gm - gp) t / 4 (t = (gm - gp) /
    (2 curv), curv = gm - 2 g0 + gp > 0, clipped to [-1/2, 1/2]) from the samples' gaps and
    derivatives: d0 - ((dm - dp) t + (gm - gp) dt) / 4, dt = 0 where t is clipped (rows
    ``ok``; the others get d0). ``min_gap_kernel.refined_minimum_rate`` per row."""
    with np.errstate(invalid="ignore", divide="ignore"):
        curv = np.where(ok, gm - 2.0 * g0 + gp, 1.0)
        diff = np.where(ok, gm - gp, 0.0)
        t = 0.5 * diff / curv
        inside = (t >= -0.5) & (t <= 0.5)
        dt = np.where(inside, 0.5 * ((dm - dp) * curv - diff * (dm - 2.0 * d0 + dp))
                      / (curv * curv), 0.0)
        rate = d0 - 0.25 * ((dm - dp) * np.clip(t, -0.5, 0.5) + diff * dt)
    return np.where(ok, rate, d0)


def _solve_roll(sides: tuple[_Side, _Side], shift: _FloatArray, yaw: _FloatArray, r0: float,
                tol_mm: float = 1e-9, max_iter: int = 60, start: _FloatArray | None = None
                ) -> tuple[_FloatArray, _FloatArray]:
    """Roll (N,) with equal minimum gaps on both sides, and that gap (N,) at height 0.

    The gap difference F = g_left - g_right grows with roll (the left wheel lifts), so a
    Newton iteration safeguarded by bisection on [-0.1, 0.1] rad converges (to the one root,
    from any start in the bracket: ``start`` (N,), default 0)."""
    n = shift.size
    lo, hi = np.full(n, -0.1), np.full(n, 0.1)
    roll = np.zeros(n) if start is None else np.clip(np.asarray(start, dtype=float), -0.1, 0.1)
    gap = np.zeros(n)
    active = np.arange(n)  # rows still iterating (a converged row is not evaluated again)
    for _ in range(max_iter):
        sa, ra, ya = shift[active], roll[active], yaw[active]
        g_left, d_left = _min_gap(sides[0], sa, ra, ya, r0)
        g_right, d_right = _min_gap(sides[1], sa, ra, ya, r0)
        with np.errstate(invalid="ignore"):  # inf - inf: a wheel off its rail, raised below
            f = g_left - g_right
        gap[active] = 0.5 * (g_left + g_right)
        if not np.all(np.isfinite(f)):
            raise ValueError("a wheel is off its rail for some shift (no rail under the wheel)")
        done = np.abs(f) < tol_mm
        if np.all(done):
            break
        la = np.where(f <= 0, ra, lo[active])
        ha = np.where(f > 0, ra, hi[active])
        df = d_left - d_right
        with np.errstate(divide="ignore", invalid="ignore"):
            step = ra - f / df
        bad = ~np.isfinite(step) | (step <= la) | (step >= ha) | (df <= 0)
        lo[active], hi[active] = la, ha
        roll[active] = np.where(done, ra, np.where(bad, 0.5 * (la + ha), step))
        active = active[~done]
    return roll, gap


def _patches(wt: WheelsetTrack, side: _Side, shift: _FloatArray, roll: _FloatArray,
             yaw: _FloatArray, height: _FloatArray, gap: _FloatArray, idx: NDArray[np.intp],
             valid: NDArray[np.bool_]) -> ContactPatches:
    idx = np.where(valid, idx, 0)
    gap_value, t = _refine(gap, idx)
    step = side.s_wheel[1] - side.s_wheel[0]
    s_w = np.clip(side.s_wheel[idx] + t * step, 0.0, side.wheel.length_mm)
    y_w, z_w = side.wheel.point(s_w)
    wheel_angle = side.wheel.tangent_angle_at(s_w)
    wheel_angle = np.arctan(np.tan(wheel_angle))  # fold into (-pi/2, pi/2)
    r0 = wt.nominal_radius_mm
    radius = r0 + z_w
    axial = side.sign * (wt.tape_circle_distance_mm / 2.0 + y_w)
    x_t, y_t, z_t = _points(side, shift, roll, yaw, r0, axial, radius, grid=False)
    z_t = z_t + height
    # the rail is prismatic, so the contact normal is the rail's normal in the cross-section:
    # delta from the rail's tangent angle in the track frame (inclined, mirrored for the right)
    s_r = np.interp(y_t, side.rail_y, side.rail_s)
    y_r, z_r = side.rail.point(s_r)
    rail_angle = np.arctan(np.tan(side.rail.tangent_angle_at(s_r)))
    delta = -(rail_angle + side.inclination_rad)
    k_wheel = -side.wheel.curvature_at(s_w)
    k_rail = -side.rail.curvature_at(s_r)
    curv_a = np.cos(wheel_angle) / (2.0 * radius)
    curv_b = 0.5 * (k_wheel + k_rail)

    def masked(a: ArrayLike) -> _FloatArray:
        return np.where(valid, np.asarray(a, dtype=float), np.nan)

    return ContactPatches(
        valid=valid, gap_mm=masked(np.maximum(gap_value, 0.0)), x_track_mm=masked(x_t),
        y_wheel_mm=masked(y_w), z_wheel_mm=masked(z_w), y_rail_mm=masked(y_r),
        z_rail_mm=masked(z_r), y_track_mm=masked(y_t), z_track_mm=masked(z_t),
        contact_angle_rad=masked(delta), wheel_angle_rad=masked(wheel_angle),
        rolling_radius_mm=masked(radius), curvature_a_per_mm=masked(curv_a),
        curvature_b_per_mm=masked(curv_b), wheel_curvature_per_mm=masked(k_wheel),
        rail_curvature_per_mm=masked(k_rail),
    )


def _secondary(gap: _FloatArray, primary: NDArray[np.intp], two_point_gap_mm: float,
               separation_mm: float) -> tuple[NDArray[np.intp], NDArray[np.bool_]]:
    """Best second local minimum of each row's gap, separated from the primary by a rise."""
    n, m = gap.shape
    cols = np.arange(m)[None, :]
    p = primary[:, None]
    finite = np.where(np.isfinite(gap), gap, 1e30)
    # running maximum of the gap walking away from the primary, in both directions
    ahead = np.where(cols >= p, finite, -np.inf)
    run_ahead = np.maximum.accumulate(ahead, axis=1)
    behind = np.where(cols <= p, finite, -np.inf)[:, ::-1]
    run_behind = np.maximum.accumulate(behind, axis=1)[:, ::-1]
    barrier = np.where(cols >= p, run_ahead, run_behind)
    interior = np.zeros_like(finite, dtype=bool)
    interior[:, 1:-1] = (finite[:, 1:-1] <= finite[:, :-2]) & (finite[:, 1:-1] < finite[:, 2:])
    candidate = (interior & (cols != p) & (finite <= two_point_gap_mm)
                 & (barrier - finite >= separation_mm))
    score = np.where(candidate, finite, np.inf)
    idx = np.argmin(score, axis=1)
    return idx, np.isfinite(score[np.arange(n), idx])


def _pose_arrays(shifts_mm: ArrayLike, yaw_rad: ArrayLike) -> tuple[_FloatArray, _FloatArray]:
    shift = np.atleast_1d(np.asarray(shifts_mm, dtype=float))
    yaw = np.broadcast_to(np.asarray(yaw_rad, dtype=float), shift.shape).copy()
    if shift.ndim != 1:
        raise ValueError("shifts_mm must be a scalar or a 1-D array")
    if np.any(np.abs(yaw) > 0.1):
        raise ValueError("yaw_rad beyond 0.1 rad: the yaw correction is for small angles")
    return shift, yaw


def contact_table(wt: WheelsetTrack, shifts_mm: ArrayLike, yaw_rad: ArrayLike = 0.0,
                  two_point_gap_mm: float = 0.05, separation_mm: float = 0.005) -> ContactTable:
    """Contact geometry for many lateral shifts at once.

    Parameters
    ----------
    wt : wheelset and track
    shifts_mm : lateral shifts of the wheelset [mm] (N,), positive towards the left rail
    yaw_rad : wheelset yaw [rad], scalar or (N,), positive turning the front to the left
        (counter-clockwise seen from above); 0 = the 2D cross-section (module docstring)
    two_point_gap_mm : largest gap [mm] at which a second minimum counts as a contact patch
    separation_mm : minimum rise of the gap [mm] between two minima for them to be separate
        patches (smaller rises are one conformal patch)

    Returns
    -------
    ContactTable with the solved roll and height and the contact patches of both wheels.
    """
    shift, yaw = _pose_arrays(shifts_mm, yaw_rad)
    sides = _prepare(wt)
    r0 = wt.nominal_radius_mm
    roll, gap0 = _solve_roll(sides, shift, yaw, r0)
    height = -gap0
    wheels = []
    for side in sides:
        gap, _ = _gaps(side, shift, roll, yaw, r0)
        gap = gap + height[:, None]
        primary = np.argmin(gap, axis=1)
        second, has_second = _secondary(gap, primary, two_point_gap_mm, separation_mm)
        wheels.append(WheelContacts(
            primary=_patches(wt, side, shift, roll, yaw, height, gap, primary,
                             np.ones(shift.size, dtype=bool)),
            secondary=_patches(wt, side, shift, roll, yaw, height, gap, second, has_second),
        ))
    return ContactTable(shift, yaw, roll, height, wheels[0], wheels[1])


def wheel_gap(wt: WheelsetTrack, shifts_mm: ArrayLike, side: str = "left",
              yaw_rad: ArrayLike = 0.0) -> tuple[_FloatArray, _FloatArray]:
    """Vertical gap between one wheel and its rail along the wheel profile, at the solved pose.

    Parameters
    ----------
    wt : wheelset and track
    shifts_mm : lateral shifts [mm] (N,), positive towards the left rail
    side : ``"left"`` or ``"right"``
    yaw_rad : wheelset yaw [rad], scalar or (N,) (as ``contact_table``)

    Returns
    -------
    (y_wheel_mm (M,), gap_mm (N, M)): the wheel samples' lateral positions in the wheel frame
    [mm] and the undeformed vertical gap [mm] (0 at the primary contact, inf where no rail is
    below).  A normal-contact model can use it to find every point within its approach.
    """
    check_side(side)
    shift, yaw = _pose_arrays(shifts_mm, yaw_rad)
    sides = _prepare(wt)
    roll, gap0 = _solve_roll(sides, shift, yaw, wt.nominal_radius_mm)
    chosen = sides[0] if side == "left" else sides[1]
    gap, _ = _gaps(chosen, shift, roll, yaw, wt.nominal_radius_mm)
    y_wheel, _ = chosen.wheel.point(chosen.s_wheel)
    return y_wheel, gap - gap0[:, None]


def _rigid_pose(wt: WheelsetTrack, shifts_mm: ArrayLike, side: str
                ) -> tuple[_FloatArray, _FloatArray, _FloatArray, _Side]:
    """The rigid pose without yaw at each shift: (shift_mm (N,), roll_rad (N,), gap0_mm (N,),
    the chosen side's samples), gap0 the solved minimum gap of both wheels at height 0 (the
    wheelset lowers by it to touch) [mm, rad, mm]."""
    check_side(side)
    shift, yaw = _pose_arrays(shifts_mm, 0.0)
    sides = _prepare(wt)
    start = None
    if shift.size > 4 * _ROLL_START_STRIDE:
        # the roll is continuous in the shift: solved on every _ROLL_START_STRIDE-th shift
        # first, interpolated, it starts Newton within a few iterations of the root (the same
        # root to tol_mm; from roll 0 most shifts take 8-11 iterations)
        order = np.argsort(shift, kind="stable")
        coarse = order[np.unique(np.r_[np.arange(0, shift.size, _ROLL_START_STRIDE),
                                       shift.size - 1])]
        roll_c, _ = _solve_roll(sides, shift[coarse], yaw[coarse], wt.nominal_radius_mm)
        start = np.interp(shift, shift[coarse], roll_c)
    roll, gap0 = _solve_roll(sides, shift, yaw, wt.nominal_radius_mm, start=start)
    return shift, roll, gap0, sides[0] if side == "left" else sides[1]


def rigid_wheel_gap(wt: WheelsetTrack, shifts_mm: ArrayLike, side: str = "left"
                    ) -> tuple[_FloatArray, _FloatArray, _FloatArray]:
    """:func:`wheel_gap` without yaw, with the solved roll: (y_wheel_mm (M,), gap_mm (N, M),
    roll_rad (N,)) [mm, mm, rad]. The gap is 0 at each wheel's primary contact (rigid pose);
    the curving model's contact table is built from it (``curving.build_contact_table``)."""
    shift, roll, gap0, chosen = _rigid_pose(wt, shifts_mm, side)
    # _gaps's rows without yaw, less gap0, from the compiled kernel (the same numbers, bit for
    # bit)
    gap, _ = gap_rows_no_yaw(chosen.y_ws, chosen.z_ws, chosen.rail_y, chosen.rail_z,
                             np.ascontiguousarray(shift), np.cos(roll), np.sin(roll),
                             float(wt.nominal_radius_mm), gap0, (0.0, 0.0), False)
    y_wheel, _ = chosen.wheel.point(chosen.s_wheel)
    return y_wheel, gap, roll


def rigid_wheel_gap_beyond_rail(wt: WheelsetTrack, shifts_mm: ArrayLike, side: str = "left"
                                ) -> tuple[_FloatArray, _FloatArray, _FloatArray, _FloatArray]:
    """:func:`rigid_wheel_gap` defined beyond the rail's ends too, for smoothing it.

    Returns (y_wheel_mm (M,), gap_mm (N, M), roll_rad (N,), inside_mm (N, M)): the same pose
    and the same gap over the rail; beyond the rail's envelope (the flange past the gauge face,
    the tread past the field side) the rail's end faces are continued as straight lines at the
    slope of their last 0.5 mm, so the gap is finite and continuous there (it rises steeply:
    no contact). ``inside_mm`` is the track-y distance of each wheel point inside the rail's
    envelope (positive with rail below, negative beyond either end), continuous in the shift
    and not quantised by the wheel's or the rail's sampling [mm]. Both from one pass of the
    compiled kernel ``min_gap_kernel.gap_rows_no_yaw`` (``beyond_rail``), referred to the solved
    pose's gap like :func:`rigid_wheel_gap`'s."""
    shift, roll, gap0, chosen = _rigid_pose(wt, shifts_mm, side)
    ry, rz = chosen.rail_y, chosen.rail_z
    lo = int(np.searchsorted(ry, ry[0] + _END_FACE_MM))
    hi = int(np.searchsorted(ry, ry[-1] - _END_FACE_MM)) - 1
    end_slopes = (float((rz[lo] - rz[0]) / (ry[lo] - ry[0])),
                  float((rz[-1] - rz[hi]) / (ry[-1] - ry[hi])))
    gap, inside = gap_rows_no_yaw(chosen.y_ws, chosen.z_ws, ry, rz,
                                  np.ascontiguousarray(shift), np.cos(roll), np.sin(roll),
                                  float(wt.nominal_radius_mm), gap0, end_slopes, True)
    y_wheel, _ = chosen.wheel.point(chosen.s_wheel)
    return y_wheel, gap, roll, inside


#: Length [mm] of track y over which the rail's end faces' slopes are taken
#: (:func:`rigid_wheel_gap_beyond_rail`).
_END_FACE_MM = 0.5


#: Stride of the coarse roll solve that starts :func:`rigid_wheel_gap`'s (shifts).
_ROLL_START_STRIDE = 8


def contact_points(wt: WheelsetTrack, lateral_shift_mm: float, yaw_rad: float = 0.0,
                   two_point_gap_mm: float = 0.05) -> WheelsetContact:
    """Contact geometry at one lateral shift [mm] (positive towards the left rail) and yaw
    [rad] (positive turning the front to the left).

    Returns the pose and, per wheel, the primary contact point followed by a secondary one
    where there is two-point contact."""
    table = contact_table(wt, [lateral_shift_mm], yaw_rad=yaw_rad,
                          two_point_gap_mm=two_point_gap_mm)

    def points(wheel: WheelContacts) -> tuple[ContactPoint, ...]:
        found = (wheel.primary.row(0), wheel.secondary.row(0))
        return tuple(p for p in found if p is not None)

    return WheelsetContact(float(table.shift_mm[0]), float(table.yaw_rad[0]),
                           float(table.roll_rad[0]), float(table.height_mm[0]),
                           points(table.left), points(table.right))
