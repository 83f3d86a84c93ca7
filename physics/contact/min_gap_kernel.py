"""Minimum vertical gap of a rolled wheel over its rail, without yaw, as a compiled kernel.

``min_gap_no_yaw(y_ws, z_ws, rail_y, rail_z, rail_slope, shift, roll, r0)`` does per pose
(lateral shift [mm], roll [rad]) what ``geometry._min_gap`` does for the two-dimensional
cross-section (yaw 0): the wheel samples (wheelset frame, [mm]) turned by the roll and shifted,
the vertical gap of each over the rail's upper envelope (linear interpolation, no rail: no
gap), the smallest gap refined by a parabola through its neighbours (``geometry._refine``),
and the derivative of the gap with respect to the roll at that sample
(z_w-rotation less the rail slope times the lateral motion). Returns (gap (N,), d gap /
d roll (N,)); a pose with no wheel sample over the rail gets an infinite gap.

The rigid roll solve of the curving model's contact table (``geometry._solve_roll``, twice per
iteration over all shifts) spent most of the table's time building the (N, M) gap arrays for
this minimum; the kernel keeps one row at a time. The numpy path (``geometry._min_gap_numpy``)
is the reference: the two agree to rounding (``tests/physics/test_contact_geometry.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray


@njit(cache=True, inline="always")
def _locate(x: float, xp: NDArray[np.float64], j: int) -> int:
    """Index j with xp[j] <= x < xp[j+1] (xp ascending, xp[0] <= x < xp[-1]), walking from
    the previous sample's index (the wheel samples are monotone in y)."""
    last = xp.size - 2
    j = min(max(j, 0), last)
    while j > 0 and x < xp[j]:
        j -= 1
    while j < last and x >= xp[j + 1]:
        j += 1
    return j


@njit(cache=True, inline="always")
def interp_on_interval(x: float, xp: NDArray[np.float64], fp: NDArray[np.float64],
                       j: int) -> float:
    """np.interp's formula on the interval j (xp[j] <= x <= xp[j + 1]): the slope form from
    the left point, from the right one where that gives NaN, the common value of a flat
    interval where both do (so results equal numpy's bit for bit)."""
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    value = slope * (x - xp[j]) + fp[j]
    if math.isnan(value):
        value = slope * (x - xp[j + 1]) + fp[j + 1]
        if math.isnan(value) and fp[j] == fp[j + 1]:
            value = fp[j]
    return value


@njit(cache=True, inline="always")
def _gap_rate(y: float, lateral: float, vertical: float, c: float, s: float,
              j: int, rail_y: NDArray[np.float64], rail_slope: NDArray[np.float64],
              dz_dy: NDArray[np.float64]) -> float:
    """d gap / d roll [mm/rad] of one wheel sample (wheelset frame lateral, vertical [mm]) at
    track y [mm] under roll (cos c, sin s): the sample's vertical motion less the rail's rise
    over its lateral motion, the rail's slope being that of the linear interpolation the gap
    takes (the slope ``dz_dy`` of the interval found from ``j``, rail_y[j] <= y <
    rail_y[j + 1]; the end slopes of ``rail_slope`` at and beyond the envelope's ends)."""
    k = rail_y.size
    if math.isnan(y):
        slope = np.nan
    elif y <= rail_y[0]:
        slope = rail_slope[0]
    elif y >= rail_y[k - 1]:
        slope = rail_slope[k - 1]
    else:
        slope = dz_dy[_locate(y, rail_y, j)]
    dz = lateral * c - vertical * s
    dy = -lateral * s - vertical * c
    return dz - slope * dy


@njit(cache=True, inline="always")
def refined_minimum_rate(gm: float, g0: float, gp: float, dm: float, d0: float,
                         dp: float) -> float:
    """Derivative of the parabola-refined minimum g0 - (gm - gp) t / 4, t = (gm - gp) /
    (2 (gm - 2 g0 + gp)) clipped to [-1/2, 1/2] (``geometry._refine``; curvature > 0), from the
    three samples' gaps and their derivatives dm, d0, dp: d0 - ((dm - dp) t + (gm - gp) dt) / 4
    (dt = 0 where t is clipped)."""
    curv = gm - 2.0 * g0 + gp
    t = 0.5 * (gm - gp) / curv
    dt = 0.0
    if t < -0.5:
        t = -0.5
    elif t > 0.5:
        t = 0.5
    else:
        dt = 0.5 * ((dm - dp) * curv - (gm - gp) * (dm - 2.0 * d0 + dp)) / (curv * curv)
    return d0 - 0.25 * ((dm - dp) * t + (gm - gp) * dt)


@njit(cache=True)
def min_gap_no_yaw(y_ws: NDArray[np.float64], z_ws: NDArray[np.float64],
                   rail_y: NDArray[np.float64], rail_z: NDArray[np.float64],
                   rail_slope: NDArray[np.float64], shift: NDArray[np.float64],
                   roll: NDArray[np.float64], r0: float
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    n = shift.size
    m = y_ws.size
    k = rail_y.size
    y_lo = rail_y[0]
    y_hi = rail_y[k - 1]
    value = np.empty(n)
    deriv = np.empty(n)
    gap = np.empty(m)
    ys = np.empty(m)
    js = np.zeros(m, dtype=np.int64)  # each sample's rail interval (where it has one)
    dz_dy = (rail_z[1:] - rail_z[:-1]) / (rail_y[1:] - rail_y[:-1])  # np.interp's slopes
    for i in range(n):
        c = math.cos(roll[i])
        s = math.sin(roll[i])
        j = 0
        best = np.inf
        idx = 0
        for p in range(m):
            lateral = y_ws[p]
            vertical = z_ws[p]
            y = shift[i] + lateral * c - vertical * s
            z = r0 + lateral * s + vertical * c
            ys[p] = y
            if y < y_lo or y > y_hi or math.isnan(y):
                g = np.inf
            elif y == y_hi:
                g = z - rail_z[k - 1]
            else:
                j = _locate(y, rail_y, j)
                js[p] = j
                g = z - (dz_dy[j] * (y - rail_y[j]) + rail_z[j])
                if math.isnan(g):
                    g = z - interp_on_interval(y, rail_y, rail_z, j)
            if not math.isfinite(g):
                g = np.inf
            gap[p] = g
            if g < best:
                best = g
                idx = p
        # parabolic refinement (geometry._refine) and its exact derivative with respect to
        # the roll (``refined_minimum_rate``)
        g0 = gap[idx]
        gm = gap[max(idx - 1, 0)]
        gp = gap[min(idx + 1, m - 1)]
        curv = gm - 2.0 * g0 + gp
        d0 = _gap_rate(ys[idx], y_ws[idx], z_ws[idx], c, s, js[idx], rail_y, rail_slope, dz_dy)
        if idx > 0 and idx < m - 1 and math.isfinite(curv) and curv > 0:
            t = 0.5 * (gm - gp) / curv
            t = min(max(t, -0.5), 0.5)
            value[i] = g0 - 0.25 * (gm - gp) * t
            dm = _gap_rate(ys[idx - 1], y_ws[idx - 1], z_ws[idx - 1], c, s, js[idx - 1],
                           rail_y, rail_slope, dz_dy)
            dp = _gap_rate(ys[idx + 1], y_ws[idx + 1], z_ws[idx + 1], c, s, js[idx + 1],
                           rail_y, rail_slope, dz_dy)
            deriv[i] = refined_minimum_rate(gm, g0, gp, dm, d0, dp)
        else:
            value[i] = g0
            deriv[i] = d0
    return value, deriv


@njit(cache=True)
def gap_rows_no_yaw(y_ws: NDArray[np.float64], z_ws: NDArray[np.float64],
                    rail_y: NDArray[np.float64], rail_z: NDArray[np.float64],
                    shift: NDArray[np.float64], cos_roll: NDArray[np.float64],
                    sin_roll: NDArray[np.float64], r0: float, gap0_mm: NDArray[np.float64],
                    end_slopes: tuple[float, float], beyond_rail: bool
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Vertical gaps (N, M) [mm] of the wheel samples (wheelset frame, [mm]) over the rail's
    upper envelope at height 0 less each pose's ``gap0_mm`` (N,) [mm], per pose (lateral shift
    [mm], cos and sin of the roll): what ``geometry._gaps`` computes without yaw, with its
    arithmetic (the sample turned and shifted as ``geometry._points``, the rail by np.interp's
    formula, inf where no rail is below), one row at a time instead of (N, M) temporaries. The
    cos and sin come from the caller (numpy's), so with ``gap0_mm`` 0 the rows equal
    ``_gaps``'s bit for bit.

    With ``beyond_rail`` the rail's end faces are continued as straight lines at
    ``end_slopes`` (dz/dy at the envelope's first and last point [-]) where no rail is below,
    so the gap is finite there too, and the second result is the track-y distance [mm] of each
    sample inside the envelope (N, M) (positive with rail below, negative beyond either end;
    ``geometry.rigid_wheel_gap_beyond_rail``); without it, an empty (0, 0) array.
    Returns (gap_mm, inside_mm)."""
    n = shift.size
    m = y_ws.size
    k = rail_y.size
    y_lo = rail_y[0]
    y_hi = rail_y[k - 1]
    slope_lo, slope_hi = end_slopes
    out = np.empty((n, m))
    inside = np.empty((n, m) if beyond_rail else (0, 0))
    dz_dy = (rail_z[1:] - rail_z[:-1]) / (rail_y[1:] - rail_y[:-1])  # np.interp's slopes
    for i in range(n):
        c = cos_roll[i]
        s = sin_roll[i]
        j = 0
        for p in range(m):
            lateral = y_ws[p]
            vertical = z_ws[p]
            y = shift[i] + lateral * c - vertical * s
            z = r0 + lateral * s + vertical * c
            if beyond_rail:
                inside[i, p] = min(y - y_lo, y_hi - y)
            if y < y_lo or y > y_hi or math.isnan(y):
                g = np.inf
                if beyond_rail and y < y_lo:  # before the envelope's first point: its face
                    g = z - (rail_z[0] + slope_lo * (y - y_lo))
                elif beyond_rail and y > y_hi:  # beyond its last point
                    g = z - (rail_z[k - 1] + slope_hi * (y - y_hi))
            elif y == y_hi:
                g = z - rail_z[k - 1]
            else:
                j = _locate(y, rail_y, j)
                g = z - (dz_dy[j] * (y - rail_y[j]) + rail_z[j])
                if math.isnan(g):
                    g = z - interp_on_interval(y, rail_y, rail_z, j)
            out[i, p] = (g if math.isfinite(g) else np.inf) - gap0_mm[i]
    return out, inside
