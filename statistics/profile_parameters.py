"""Flange parameters Sd, Sh, qR of a wheel profile and their in-service limits.

Definitions (EN 15313 / MiniProf "wheel wear" defaults L1 = 2, L2 = 70, L3 = 10 mm; DESIGN.md
"Conventions"; ``reference/README.md`` "Wheel limits"), in the wheel frame y [mm] from the
tape circle (back face at y = -70), z [mm] up towards the flange tip:

* Sh, flange height: flange-tip height minus the tape-circle height z(0);
* Sd, flange thickness: distance from the back face (y = -70) to the flange face (the
  field-side flank of the flange) at 10 mm above the tape-circle height;
* qR, flange slope measure: horizontal distance between the flange-face point 2 mm below the
  tip and the Sd point.

For S1002 new (EN 13715) these are 32.50 / 28.00 / 10.80 mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import ReferenceHeight
from wearcast.statistics.wear_curves import reference_on_grid

#: Lateral position of the back face in the wheel frame [mm] (tape circle 70 mm from it).
BACK_FACE_Y_MM = -70.0
#: Height of the Sd point above the tape-circle height [mm] (MiniProf L3).
SD_HEIGHT_MM = 10.0
#: Depth of the qR point below the flange tip [mm] (MiniProf L1).
QR_DEPTH_MM = 2.0


@dataclass(frozen=True)
class FlangeParameters:
    """Flange thickness Sd, flange height Sh and flange slope qR [mm]."""

    sd_mm: float
    sh_mm: float
    qr_mm: float


@dataclass(frozen=True)
class WheelLimits:
    """In-service limits of the flange parameters [mm]; override any of them.

    Defaults: German EBO Anlage 6 (also Austrian EisbBBV Anlage 2; EN 15313 governs) as
    summarised in ``reference/README.md`` "Wheel limits": flange thickness Sd >= 22 mm for
    international traffic (20 mm domestic), flange height Sh <= 36 mm, qR >= 6.5 mm.
    """

    sd_min_mm: float = 22.0
    sh_max_mm: float = 36.0
    qr_min_mm: float = 6.5

    def exceeded(self, parameters: FlangeParameters) -> tuple[str, ...]:
        """Names (``"sd"``, ``"sh"``, ``"qr"``) of the limits the parameters violate."""
        out = []
        if parameters.sd_mm < self.sd_min_mm:
            out.append("sd")
        if parameters.sh_mm > self.sh_max_mm:
            out.append("sh")
        if parameters.qr_mm < self.qr_min_mm:
            out.append("qr")
        return tuple(out)


#: Default limits (international traffic); ``WheelLimits(sd_min_mm=20.0)`` for domestic.
DEFAULT_LIMITS = WheelLimits()


def _flank_crossing(y: NDArray, z: NDArray, start: int, level: float) -> float:
    """y [mm] where z first drops below ``level`` walking from index ``start`` to +y.

    The crossing is found on the quadratic through the two points that bracket it and the
    next one (linear if there is none or the quadratic has no root between them): on the
    steep, curved flank a chord would be off by up to 0.01 mm for 0.5 mm sampling.
    """
    below = z[start:] < level
    if not below.any():
        return float("nan")
    k = start + int(np.argmax(below))
    if k == start:
        return float(y[k])
    y0, y1 = float(y[k - 1]), float(y[k])
    z0, z1 = float(z[k - 1]), float(z[k])
    h = y1 - y0
    t_lin = (level - z0) * h / (z1 - z0)
    if k + 1 >= y.size:
        return y0 + t_lin
    y2, z2 = float(y[k + 1]), float(z[k + 1])
    d01 = (z1 - z0) / h
    a = ((z2 - z1) / (y2 - y1) - d01) / (y2 - y0)
    # z0 + d01 t + a t (t - h) = level, t = y - y0
    b = d01 - a * h
    c = z0 - level
    if abs(a) * h < 1e-12 * (abs(b) + 1e-300):
        return y0 + t_lin
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return y0 + t_lin
    root = math.sqrt(disc)
    for t in ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a)):
        if 0.0 <= t <= h:
            return y0 + t
    return y0 + t_lin


def flange_parameters(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    *,
    tip_region_y_mm: tuple[float, float] = (-65.0, -40.0),
) -> FlangeParameters:
    """Sd, Sh and qR of one profile.

    Parameters
    ----------
    y_mm : ascending lateral positions [mm] from the tape circle (back face at -70); must
        cover the flange tip, its field-side flank and y = 0
    z_mm : heights [mm], positive towards the flange tip (e.g. aligned worn profile, or
        z_ref - w for a wear curve)
    tip_region_y_mm : where the flange tip is looked for [mm]

    Returns
    -------
    FlangeParameters; a value is NaN if its point is not in the data.

    Definitions: EN 15313 / MiniProf (module docstring); S1002 gives 32.50 / 28.00 / 10.80.
    """
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    finite = np.isfinite(z) & np.isfinite(y)
    if not finite.all():
        y, z = y[finite], z[finite]
    if y.size < 3 or y[0] > 0.0 or y[-1] < 0.0:
        nan = float("nan")
        return FlangeParameters(sd_mm=nan, sh_mm=nan, qr_mm=nan)
    z_tape = float(np.interp(0.0, y, z))
    lo, hi = np.searchsorted(y, tip_region_y_mm)
    if hi <= lo:
        nan = float("nan")
        return FlangeParameters(sd_mm=nan, sh_mm=nan, qr_mm=nan)
    k = lo + int(np.argmax(z[lo:hi]))
    z_tip = float(z[k])  # sampled maximum: off by <= h^2/(8 R) = 0.003 mm (h 0.5, R 12)
    y_sd = _flank_crossing(y, z, k, z_tape + SD_HEIGHT_MM)
    y_qr = _flank_crossing(y, z, k, z_tip - QR_DEPTH_MM)
    return FlangeParameters(
        sd_mm=y_sd - BACK_FACE_Y_MM, sh_mm=z_tip - z_tape, qr_mm=y_sd - y_qr
    )


@dataclass(frozen=True)
class FlangeParameterArrays:
    """Sd, Sh and qR of many profiles [mm], each of shape (N,); NaN where undefined."""

    sd_mm: NDArray[np.float64]
    sh_mm: NDArray[np.float64]
    qr_mm: NDArray[np.float64]

    def stacked(self) -> NDArray[np.float64]:
        """(N, 3) array with columns Sd, Sh, qR [mm]."""
        return np.column_stack([self.sd_mm, self.sh_mm, self.qr_mm])


def _flank_crossings(y: NDArray, z: NDArray, rows: NDArray, start: NDArray, level: NDArray
                     ) -> NDArray:
    """Vectorised :func:`_flank_crossing` for rows ``rows`` (M,) of ``z`` (N, g) [mm].

    Same rule as the scalar version, row by row: the first grid point at or after ``start``
    below ``level``, then the quadratic through the bracketing points and the next one, with
    the same fall-backs to the chord.
    """
    g = z.shape[1]
    below = (z[rows] < level[:, None]) & (np.arange(g)[None, :] >= start[:, None])
    found = below.any(axis=1)
    k = np.argmax(below, axis=1)
    at_start = k == start
    k1 = np.maximum(k, 1)
    y0, y1 = y[k1 - 1], y[k1]
    z0, z1 = z[rows, k1 - 1], z[rows, k1]
    h = y1 - y0
    with np.errstate(divide="ignore", invalid="ignore"):
        t_lin = (level - z0) * h / (z1 - z0)
        k2 = np.minimum(k1 + 1, g - 1)
        y2, z2 = y[k2], z[rows, k2]
        d01 = (z1 - z0) / h
        a = ((z2 - z1) / (y2 - y1) - d01) / (y2 - y0)
        b = d01 - a * h
        c = z0 - level
        disc = b * b - 4.0 * a * c
        root = np.sqrt(np.where(disc >= 0.0, disc, 0.0))
        t1 = (-b - root) / (2.0 * a)
        t2 = (-b + root) / (2.0 * a)
    quadratic = (k1 + 1 < g) & ~(np.abs(a) * h < 1e-12 * (np.abs(b) + 1e-300)) & (disc >= 0.0)
    ok1 = quadratic & (t1 >= 0.0) & (t1 <= h)
    ok2 = quadratic & ~ok1 & (t2 >= 0.0) & (t2 <= h)
    t = np.where(ok1, t1, np.where(ok2, t2, t_lin))
    out = np.where(at_start, y[k], y0 + t)
    return np.where(found, out, np.nan)


def flange_parameters_batch(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    *,
    tip_region_y_mm: tuple[float, float] = (-65.0, -40.0),
) -> FlangeParameterArrays:
    """Sd, Sh and qR of many profiles sampled on one common lateral grid (vectorised).

    Parameters
    ----------
    y_mm : (g,) ascending lateral grid [mm] from the tape circle (back face at -70)
    z_mm : (N, g) or (g,) heights [mm], positive towards the flange tip
    tip_region_y_mm : where the flange tip is looked for [mm]

    Returns
    -------
    FlangeParameterArrays of shape (N,). The result of every row is that of
    :func:`flange_parameters` on the row (same definitions and the same interpolation, so
    they agree to rounding); rows with non-finite heights are passed to it one by one.
    """
    y = np.asarray(y_mm, dtype=float)
    z = np.atleast_2d(np.asarray(z_mm, dtype=float))
    if y.ndim != 1 or z.ndim != 2 or z.shape[1] != y.size:
        raise ValueError(f"z_mm: must have shape (N, {y.size}), got {np.shape(z_mm)}")
    n = z.shape[0]
    sd, sh, qr = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
    lo, hi = np.searchsorted(y, tip_region_y_mm)
    if (not np.all(np.isfinite(y)) or y.size < 3 or y[0] > 0.0 or y[-1] < 0.0 or hi <= lo
            or n == 0):
        for i in range(n):
            fp = flange_parameters(y, z[i], tip_region_y_mm=tip_region_y_mm)
            sd[i], sh[i], qr[i] = fp.sd_mm, fp.sh_mm, fp.qr_mm
        return FlangeParameterArrays(sd, sh, qr)
    finite = np.isfinite(z).all(axis=1)
    for r in np.flatnonzero(~finite):
        fp = flange_parameters(y, z[r], tip_region_y_mm=tip_region_y_mm)
        sd[r], sh[r], qr[r] = fp.sd_mm, fp.sh_mm, fp.qr_mm
    zf = z[finite]
    if zf.shape[0]:
        # z at the tape circle, as np.interp(0, y, z) row by row
        j = min(int(np.searchsorted(y, 0.0, side="right")) - 1, y.size - 2)
        if y[j] == 0.0:
            z_tape = zf[:, j]
        else:
            slope = (zf[:, j + 1] - zf[:, j]) / (y[j + 1] - y[j])
            z_tape = slope * (0.0 - y[j]) + zf[:, j]
        nf = zf.shape[0]
        k = lo + np.argmax(zf[:, lo:hi], axis=1)
        z_tip = zf[np.arange(nf), k]
        # the Sd and the qR points of every row in one pass
        both = _flank_crossings(y, zf, np.tile(np.arange(nf), 2), np.tile(k, 2),
                                np.concatenate([z_tape + SD_HEIGHT_MM, z_tip - QR_DEPTH_MM]))
        y_sd, y_qr = both[:nf], both[nf:]
        sd[finite] = y_sd - BACK_FACE_Y_MM
        sh[finite] = z_tip - z_tape
        qr[finite] = y_sd - y_qr
    return FlangeParameterArrays(sd, sh, qr)


def parameters_from_wear_curve(
    grid_y_mm: ArrayLike,
    wear_mm: ArrayLike,
    reference_height: ReferenceHeight = s1002_height_mm,
) -> FlangeParameters:
    """Sd, Sh, qR of the worn profile z_worn = z_ref - w given on a lateral grid.

    Parameters
    ----------
    grid_y_mm : ascending lateral grid [mm] (must include y = 0, the flange tip and flank)
    wear_mm : wear curve on the grid [mm]
    reference_height : reference profile z(y) [mm] (default S1002)

    Returns
    -------
    FlangeParameters of the worn profile (DESIGN.md hybrid model step 6).
    """
    grid = np.asarray(grid_y_mm, dtype=float)
    z_worn = reference_on_grid(grid, reference_height) - np.asarray(wear_mm, dtype=float)
    return flange_parameters(grid, z_worn)
