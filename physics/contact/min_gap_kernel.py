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
                g = z - (dz_dy[j] * (y - rail_y[j]) + rail_z[j])
                if math.isnan(g):
                    g = z - interp_on_interval(y, rail_y, rail_z, j)
            if not math.isfinite(g):
                g = np.inf
            gap[p] = g
            if g < best:
                best = g
                idx = p
        # parabolic refinement (geometry._refine)
        g0 = gap[idx]
        gm = gap[max(idx - 1, 0)]
        gp = gap[min(idx + 1, m - 1)]
        curv = gm - 2.0 * g0 + gp
        if idx > 0 and idx < m - 1 and math.isfinite(curv) and curv > 0:
            t = 0.5 * (gm - gp) / curv
            t = min(max(t, -0.5), 0.5)
            value[i] = g0 - 0.25 * (gm - gp) * t
        else:
            value[i] = g0
        # rail slope at the minimum's sample (np.interp, edge values outside)
        y_min = ys[idx]
        if y_min <= y_lo:
            slope = rail_slope[0]
        elif y_min >= y_hi:
            slope = rail_slope[k - 1]
        elif math.isnan(y_min):
            slope = np.nan
        else:
            slope = interp_on_interval(y_min, rail_y, rail_slope, _locate(y_min, rail_y, 0))
        yw = y_ws[idx]
        zw = z_ws[idx]
        dz = yw * c - zw * s
        dy = -yw * s - zw * c
        deriv[i] = dz - slope * dy
    return value, deriv
