"""Flange parameters Sd, Sh, qR of a wheel profile (EN 15313 / MiniProf).

Definitions (EN 15313 / MiniProf "wheel wear" defaults L1 = 2, L2 = 70, L3 = 10 mm;
docs/conventions.md "Profile parameters and limits"; EBO Anlage 6 in docs/references.md),
in the wheel frame y [mm] from the tape circle (back face at y = -70), z [mm] up towards the
flange tip:

* Sh, flange height: flange-tip height minus the tape-circle height z(0);
* Sd, flange thickness: distance from the back face (y = -70) to the flange face (the
  field-side flank of the flange) at 10 mm above the tape-circle height;
* qR, flange slope measure: horizontal distance between the flange-face point 2 mm below the
  tip and the Sd point.

For S1002 new (EN 13715) these are 32.50 / 28.00 / 10.80 mm.

Measured profiles (``wearcast.statistics``), the wear loop (``physics.wear_loop``) and the
loop twin all take the tape-circle height from the (worn) profile itself, as EN 15313 and the
instrument do: tread wear at y = 0 raises Sh and lifts the Sd point up the flank.
:func:`nominal_frame_flange_parameters` (heights from the nominal tape circle z = 0, the tip
anywhere left of y = -25 mm, chord crossings) is the convention the loop used before; it is
the same :func:`flange_parameters` with other options, kept for comparisons (e.g. to show that
wear never thickens the flange in the new profile's frame).

The definitions are written once: the heights of the Sd and qR points (``_point_heights``),
Sd/Sh/qR from the flank points (``_sd_sh_qr``) and the flank crossing (``_bracket_crossing``;
searched along one profile by ``_flank_crossing``, along many rows, on a common grid or on
rows of their own, by ``_flank_crossings``). :func:`flange_parameters` (one profile),
:func:`flange_parameters_batch` (many on one grid) and :func:`flange_parameters_rows` (many of
different lengths) use them and give the same numbers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Lateral position of the back face in the wheel frame [mm] (tape circle 70 mm from it).
BACK_FACE_Y_MM = -70.0
#: Height of the Sd point above the tape-circle height [mm] (MiniProf L3).
SD_HEIGHT_MM = 10.0
#: Depth of the qR point below the flange tip [mm] (MiniProf L1).
QR_DEPTH_MM = 2.0
#: Where :func:`flange_parameters` looks for the flange tip by default [mm].
TIP_REGION_Y_MM = (-65.0, -40.0)
#: Tip region of the wear loop's nominal-frame parameters: left of the flange root [mm].
NOMINAL_TIP_REGION_Y_MM = (-math.inf, -25.0)


@dataclass(frozen=True)
class FlangeParameters:
    """Flange thickness Sd, flange height Sh and flange slope qR [mm]."""

    sd_mm: float
    sh_mm: float
    qr_mm: float


def _point_heights(z_tape: Any, z_tip: Any) -> tuple[Any, Any]:
    """Heights [mm] of the Sd point (``SD_HEIGHT_MM`` above the tape-circle height) and of the
    qR point (``QR_DEPTH_MM`` below the flange tip)."""
    return z_tape + SD_HEIGHT_MM, z_tip - QR_DEPTH_MM


def _sd_sh_qr(y_sd: Any, y_qr: Any, z_tip: Any, z_tape: Any) -> tuple[Any, Any, Any]:
    """Sd, Sh, qR [mm] (module docstring) from the flank points y_sd, y_qr [mm] and the
    heights of the tip and the tape circle [mm]."""
    return y_sd - BACK_FACE_Y_MM, z_tip - z_tape, y_sd - y_qr


def _bracket_crossing(y0: Any, y1: Any, y2: Any, z0: Any, z1: Any, z2: Any, level: Any,
                      has_next: Any) -> NDArray:
    """Offset t = y - y0 [mm] where z crosses ``level`` between (y0, z0) and (y1, z1),
    elementwise: on the quadratic through the two bracketing points and the next one (y2, z2)
    where ``has_next``, the quadratic is not degenerate and has a root in [0, h]; else on the
    chord. On the steep, curved flank a chord would be off by up to 0.01 mm for 0.5 mm
    sampling."""
    h = y1 - y0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t_lin = (level - z0) * h / (z1 - z0)
        d01 = (z1 - z0) / h
        a = ((z2 - z1) / (y2 - y1) - d01) / (y2 - y0)
        # z0 + d01 t + a t (t - h) = level
        b = d01 - a * h
        disc = b * b - 4.0 * a * (z0 - level)
        root = np.sqrt(np.maximum(disc, 0.0))
        t1 = (-b - root) / (2.0 * a)
        t2 = (-b + root) / (2.0 * a)
    quadratic = has_next & (np.abs(a) * h >= 1e-12 * (np.abs(b) + 1e-300)) & (disc >= 0.0)
    ok1 = quadratic & (t1 >= 0.0) & (t1 <= h)
    ok2 = quadratic & (t2 >= 0.0) & (t2 <= h)
    return np.asarray(np.where(ok1, t1, np.where(ok2, t2, t_lin)))


def _flank_crossing(y: NDArray, z: NDArray, start: int, level: float,
                    quadratic: bool = True) -> float:
    """y [mm] where z first drops below ``level`` walking from index ``start`` to +y, on the
    quadratic through the bracketing points and the next one (:func:`_bracket_crossing`;
    the chord if ``quadratic`` is False)."""
    below = z[start:] < level
    if not below.any():
        return float("nan")
    k = start + int(np.argmax(below))
    if k == start:
        return float(y[k])
    k2 = min(k + 1, y.size - 1)
    t = _bracket_crossing(y[k - 1], y[k], y[k2], z[k - 1], z[k], z[k2], level,
                          quadratic and k + 1 < y.size)
    return float(y[k - 1] + t)


def flange_parameters(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    *,
    tip_region_y_mm: tuple[float, float] = TIP_REGION_Y_MM,
    tape_circle_z_mm: float | None = None,
    interpolation: str = "quadratic",
) -> FlangeParameters:
    """Sd, Sh and qR of one profile.

    Parameters
    ----------
    y_mm : ascending lateral positions [mm] from the tape circle (back face at -70); must
        cover the flange tip, its field-side flank and y = 0
    z_mm : heights [mm], positive towards the flange tip (e.g. aligned worn profile, or
        z_ref - w for a wear curve)
    tip_region_y_mm : where the flange tip is looked for [mm]
    tape_circle_z_mm : height [mm] the Sh and Sd heights are measured from; None (default)
        takes the profile's own z(0), as the instrument does; the wear loop passes 0 (the
        nominal tape circle of the wheel frame)
    interpolation : flank crossings on the local ``quadratic`` (default) or the ``linear``
        chord between the bracketing points

    Returns
    -------
    FlangeParameters; a value is NaN if its point is not in the data.

    Definitions: EN 15313 / MiniProf (module docstring); S1002 gives 32.50 / 28.00 / 10.80.
    """
    if interpolation not in ("quadratic", "linear"):
        raise ValueError(f"interpolation must be 'quadratic' or 'linear', got {interpolation!r}")
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    finite = np.isfinite(z) & np.isfinite(y)
    if not finite.all():
        y, z = y[finite], z[finite]
    if y.size < 3 or y[0] > 0.0 or y[-1] < 0.0:
        nan = float("nan")
        return FlangeParameters(sd_mm=nan, sh_mm=nan, qr_mm=nan)
    if tape_circle_z_mm is None:
        z_tape = float(np.interp(0.0, y, z))
    else:
        z_tape = float(tape_circle_z_mm)
    lo, hi = np.searchsorted(y, tip_region_y_mm)
    if hi <= lo:
        nan = float("nan")
        return FlangeParameters(sd_mm=nan, sh_mm=nan, qr_mm=nan)
    k = lo + int(np.argmax(z[lo:hi]))
    z_tip = float(z[k])  # sampled maximum: off by <= h^2/(8 R) = 0.003 mm (h 0.5, R 12)
    quadratic = interpolation == "quadratic"
    sd_level, qr_level = _point_heights(z_tape, z_tip)
    y_sd = _flank_crossing(y, z, k, sd_level, quadratic)
    y_qr = _flank_crossing(y, z, k, qr_level, quadratic)
    sd, sh, qr = _sd_sh_qr(y_sd, y_qr, z_tip, z_tape)
    return FlangeParameters(sd_mm=sd, sh_mm=sh, qr_mm=qr)


def nominal_frame_flange_parameters(y_mm: ArrayLike, z_mm: ArrayLike) -> FlangeParameters:
    """Sd, Sh, qR [mm] as the wear loop reports them (:func:`flange_parameters` options).

    Heights from the nominal tape circle z = 0 of the wheel frame (not the worn z(0)), the
    tip anywhere left of y = -25 mm, linear flank crossings. y_mm ascending [mm], z_mm
    heights [mm]; S1002 new gives 32.50 / 28.00 / 10.80 (chord crossings on a 0.2 mm grid:
    Sd 32.502, qR 10.796).
    """
    return flange_parameters(y_mm, z_mm, tip_region_y_mm=NOMINAL_TIP_REGION_Y_MM,
                             tape_circle_z_mm=0.0, interpolation="linear")


@dataclass(frozen=True)
class FlangeParameterArrays:
    """Sd, Sh and qR of many profiles [mm], each of shape (N,); NaN where undefined."""

    sd_mm: NDArray[np.float64]
    sh_mm: NDArray[np.float64]
    qr_mm: NDArray[np.float64]

    def stacked(self) -> NDArray[np.float64]:
        """(N, 3) array with columns Sd, Sh, qR [mm]."""
        return np.column_stack([self.sd_mm, self.sh_mm, self.qr_mm])


def _flank_crossings(y: NDArray, z: NDArray, start: NDArray, levels: NDArray,
                     n: NDArray | None = None) -> NDArray:
    """Vectorised :func:`_flank_crossing`: rows of ``z`` (M, g) [mm] on the common grid ``y``
    (g,) [mm] or on their own rows ``y`` (M, g) [mm], their start indices ``start`` (M,) and
    L levels per row ``levels`` (M, L) [mm]; ``n`` (M,) the number of points of each row (the
    rest padding; None: all g). Returns y (M, L) [mm].

    Same rule as the scalar version, row by row and level by level: the first point at or
    after ``start`` below the level, then the quadratic through the bracketing points and
    the next one, with the same fall-backs to the chord. Only the columns from the smallest
    start on are searched.
    """
    m, g = z.shape
    s0 = int(start.min()) if start.size else 0
    cols = np.arange(s0, g)
    below = z[:, None, s0:] < levels[:, :, None]
    if not (start == s0).all():
        below &= (cols >= start[:, None])[:, None, :]
    if n is not None:
        below &= (cols < n[:, None])[:, None, :]
    found = below.any(axis=2)
    k = below.argmax(axis=2) + s0
    at_start = k == start[:, None]
    k1 = np.maximum(k, 1)
    k2 = np.minimum(k1 + 1, g - 1)
    row = (np.arange(m) * g)[:, None]
    flat = z.reshape(-1)
    z0, z1, z2 = flat[row + (k1 - 1)], flat[row + k1], flat[row + k2]
    if y.ndim == 1:
        y0, y1, y2, y_k = y[k1 - 1], y[k1], y[k2], y[k]
    else:
        flat_y = y.reshape(-1)
        y0, y1, y2, y_k = (flat_y[row + (k1 - 1)], flat_y[row + k1], flat_y[row + k2],
                           flat_y[row + k])
    t = _bracket_crossing(y0, y1, y2, z0, z1, z2, levels,
                          k1 + 1 < (g if n is None else n[:, None]))
    out = np.where(at_start, y_k, y0 + t)
    return np.where(found, out, np.nan)


@dataclass(frozen=True)
class BatchGrid:
    """What the batched Sd/Sh/qR need of a lateral grid, computed once per grid: the grid
    y [mm], the tip-region columns [lo, hi) and the tape-circle interpolation (columns j,
    j + 1 and the weight of j + 1). ``None`` from :meth:`build` when the grid cannot give
    the parameters (too short, no tape circle, no tip region)."""

    y_mm: NDArray
    tip_lo: int
    tip_hi: int
    tape_j: int
    tape_w: float

    @classmethod
    def build(cls, y_mm: NDArray, tip_region_y_mm: tuple[float, float] = TIP_REGION_Y_MM
              ) -> BatchGrid | None:
        y = np.asarray(y_mm, dtype=float)
        lo, hi = (int(v) for v in np.searchsorted(y, tip_region_y_mm))
        if (not np.all(np.isfinite(y)) or y.size < 3 or y[0] > 0.0 or y[-1] < 0.0
                or hi <= lo):
            return None
        j = min(int(np.searchsorted(y, 0.0, side="right")) - 1, y.size - 2)
        w = 0.0 if y[j] == 0.0 else (0.0 - y[j]) / (y[j + 1] - y[j])
        return cls(y, lo, hi, j, float(w))

    def parameters(self, z: NDArray) -> NDArray:
        """(M, 3) Sd, Sh, qR [mm] of finite rows ``z`` (M, g) on this grid."""
        n = z.shape[0]
        j = self.tape_j
        if self.tape_w == 0.0:
            z_tape = z[:, j]
        else:  # as np.interp(0, y, z) row by row
            z_tape = (z[:, j + 1] - z[:, j]) * self.tape_w + z[:, j]
        k = self.tip_lo + np.argmax(z[:, self.tip_lo:self.tip_hi], axis=1)
        z_tip = z[np.arange(n), k]
        both = _flank_crossings(self.y_mm, z, k, np.column_stack(_point_heights(z_tape, z_tip)))
        return np.column_stack(_sd_sh_qr(both[:, 0], both[:, 1], z_tip, z_tape))


def flange_parameters_batch(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    *,
    tip_region_y_mm: tuple[float, float] = TIP_REGION_Y_MM,
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
    out = np.full((n, 3), np.nan)
    grid = BatchGrid.build(y, tip_region_y_mm) if n else None
    finite = np.isfinite(z).all(axis=1) if grid is not None else np.zeros(n, bool)
    for r in np.flatnonzero(~finite):
        fp = flange_parameters(y, z[r], tip_region_y_mm=tip_region_y_mm)
        out[r] = fp.sd_mm, fp.sh_mm, fp.qr_mm
    if grid is not None and finite.any():
        out[finite] = grid.parameters(z if finite.all() else z[finite])
    return FlangeParameterArrays(out[:, 0].copy(), out[:, 1].copy(), out[:, 2].copy())


def flange_parameters_rows(
    y_mm: NDArray[np.float64],
    z_mm: NDArray[np.float64],
    valid: NDArray[np.bool_],
    *,
    tip_region_y_mm: tuple[float, float] = TIP_REGION_Y_MM,
) -> NDArray[np.float64]:
    """:func:`flange_parameters` of many profiles of different lengths, vectorised.

    Parameters
    ----------
    y_mm, z_mm : (M, L) padded rows [mm]: each profile's points ascending in y in the first
        columns of its row, finite; the rest padding (any values)
    valid : (M, L) the profiles' columns (``valid[i, :n_i]`` True, the rest False)
    tip_region_y_mm : where the flange tip is looked for [mm]

    Returns
    -------
    (M, 3) Sd, Sh, qR [mm] with the definitions, the tape-circle height (``np.interp``'s own
    formula at y = 0) and the quadratic flank crossings of :func:`flange_parameters`, so the
    numbers are the same; NaN where a point is not in the data.
    """
    m, width = y_mm.shape
    out = np.full((m, 3), np.nan)
    n = valid.sum(axis=1)
    if m == 0 or width == 0:
        return out
    rows = np.arange(m)
    last = np.maximum(n - 1, 0)
    big = np.where(valid, y_mm, np.inf)  # ascending with the padding beyond the data
    usable = (n >= 3) & (y_mm[:, 0] <= 0.0) & (y_mm[rows, last] >= 0.0)
    # tape circle: np.interp(0, y, z)
    j = np.clip((big <= 0.0).sum(axis=1) - 1, 0, width - 1)
    j1 = np.minimum(j + 1, width - 1)
    yj, zj, yj1, zj1 = y_mm[rows, j], z_mm[rows, j], y_mm[rows, j1], z_mm[rows, j1]
    with np.errstate(divide="ignore", invalid="ignore"):
        z_tape = np.where((j == last) | (yj == 0.0), zj,
                          (zj1 - zj) / (yj1 - yj) * (0.0 - yj) + zj)
    lo = (big < tip_region_y_mm[0]).sum(axis=1)
    hi = (big < tip_region_y_mm[1]).sum(axis=1)
    usable &= hi > lo
    cols = np.arange(width)
    in_tip = (cols >= lo[:, None]) & (cols < hi[:, None])
    k = np.argmax(np.where(in_tip, z_mm, -np.inf), axis=1)
    z_tip = z_mm[rows, k]
    levels = np.column_stack(_point_heights(z_tape, z_tip))
    crossing = _flank_crossings(y_mm, z_mm, k, levels, n)
    sd, sh, qr = _sd_sh_qr(crossing[:, 0], crossing[:, 1], z_tip, z_tape)
    out[usable, 0] = sd[usable]
    out[usable, 1] = sh[usable]
    out[usable, 2] = qr[usable]
    return out
