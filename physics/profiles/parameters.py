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

Each rule is written once, as compiled (numba) code on one profile: the height at a lateral
position (``_height_at``, the tape circle, ``np.interp``'s numbers; public as
:func:`tape_circle_height_mm`), the flange-tip search (``_tip_index``), the heights of the Sd
and qR points (``_point_heights``), the flank crossing (``_flank_crossing`` with
``_bracket_crossing``) and Sd/Sh/qR from the flank points (``_sd_sh_qr``).
``_parameters_kernel`` runs them over rows, on a common grid or on rows of their own;
:func:`flange_parameters` (one profile), :func:`flange_parameters_batch` (many on one grid) and
:func:`flange_parameters_rows` (many of different lengths) all call it, so their numbers are
the same to the bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
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


@njit(cache=True)
def _point_heights(z_tape: float, z_tip: float) -> tuple[float, float]:
    """Heights [mm] of the Sd point (``SD_HEIGHT_MM`` above the tape-circle height) and of the
    qR point (``QR_DEPTH_MM`` below the flange tip)."""
    return z_tape + SD_HEIGHT_MM, z_tip - QR_DEPTH_MM


@njit(cache=True)
def _sd_sh_qr(y_sd: float, y_qr: float, z_tip: float, z_tape: float
              ) -> tuple[float, float, float]:
    """Sd, Sh, qR [mm] (module docstring) from the flank points y_sd, y_qr [mm] and the
    heights of the tip and the tape circle [mm]."""
    return y_sd - BACK_FACE_Y_MM, z_tip - z_tape, y_sd - y_qr


@njit(cache=True, error_model="numpy")
def _height_at(y: NDArray, z: NDArray, n: int, x: float) -> float:
    """Height [mm] of the profile (y, z) [mm] (its first ``n`` points, y ascending) at the
    lateral position ``x`` [mm], with the formula and the end rules of ``np.interp`` (so its
    numbers): the last point at or before ``x``; its height if it lies at ``x`` or is the
    last point, else the chord to the next; the first height before the first point."""
    j = -1
    while j + 1 < n and y[j + 1] <= x:
        j += 1
    if j < 0:
        return float(z[0])
    if j >= n - 1 or y[j] == x:
        return float(z[j])
    return float((z[j + 1] - z[j]) / (y[j + 1] - y[j]) * (x - y[j]) + z[j])


@njit(cache=True)
def _tip_index(y: NDArray, z: NDArray, n: int, y_from: float, y_to: float) -> int:
    """Index of the flange tip of the profile (y, z) [mm] (its first ``n`` points): the first
    highest point with y_from <= y < y_to [mm] (the sampled maximum: off by <= h^2/(8 R) =
    0.003 mm for h 0.5, R 12); -1 if no point lies there."""
    k = -1
    for i in range(n):
        if y[i] >= y_to:
            break
        if y[i] >= y_from and (k < 0 or z[i] > z[k]):
            k = i
    return k


@njit(cache=True, error_model="numpy")
def _bracket_crossing(y0: float, y1: float, y2: float, z0: float, z1: float, z2: float,
                      level: float, has_next: bool) -> float:
    """Offset t = y - y0 [mm] where z crosses ``level`` between (y0, z0) and (y1, z1): on
    the quadratic through the two bracketing points and the next one (y2, z2) where
    ``has_next``, the quadratic is not degenerate and has a root in [0, h]; else on the
    chord. On the steep, curved flank a chord would be off by up to 0.01 mm for 0.5 mm
    sampling."""
    h = y1 - y0
    dz = z1 - z0
    t_lin = (level - z0) * h / dz
    if not has_next:
        return t_lin
    d01 = dz / h
    a = ((z2 - z1) / (y2 - y1) - d01) / (y2 - y0)
    # z0 + d01 t + a t (t - h) = level
    b = d01 - a * h
    disc = b * b - 4.0 * a * (z0 - level)
    if not (abs(a) * h >= 1e-12 * (abs(b) + 1e-300) and disc >= 0.0):
        return t_lin
    root = math.sqrt(disc)
    t1 = (-b - root) / (2.0 * a)
    if t1 >= 0.0 and t1 <= h:
        return t1
    t2 = (-b + root) / (2.0 * a)
    if t2 >= 0.0 and t2 <= h:
        return t2
    return t_lin


@njit(cache=True)
def _flank_crossing(y: NDArray, z: NDArray, n: int, start: int, level: float,
                    quadratic: bool) -> float:
    """y [mm] where z first drops below ``level`` walking from index ``start`` to +y along
    the profile's first ``n`` points: NaN if it never does, the start point if it is below
    already, else :func:`_bracket_crossing` between the first point below and the one
    before (the chord if ``quadratic`` is False)."""
    k = start
    while k < n and not z[k] < level:
        k += 1
    if k >= n:
        return math.nan
    if k == start:
        return float(y[k])
    k2 = min(k + 1, n - 1)
    return float(y[k - 1] + _bracket_crossing(y[k - 1], y[k], y[k2], z[k - 1], z[k], z[k2],
                                              level, quadratic and k + 1 < n))


@njit(cache=True)
def _parameters_kernel(y: NDArray, z: NDArray, n: NDArray, y_from: float, y_to: float,
                       tape_circle_z_mm: float, quadratic: bool) -> NDArray:
    """Sd, Sh, qR (M, 3) [mm] of the rows of ``z`` (M, L) [mm]: row i holds a profile's
    ``n[i]`` points (the rest padding), ascending in ``y`` (1, L), a common grid, or
    (M, L), the rows' own; tape circle at ``tape_circle_z_mm`` [mm] (NaN: each profile's
    own height at y = 0, :func:`_height_at`); tip region [y_from, y_to) [mm]. NaN where a
    point is not in the data."""
    m = z.shape[0]
    out = np.full((m, 3), np.nan)
    for i in range(m):
        yi = y[0] if y.shape[0] == 1 else y[i]
        zi = z[i]
        ni = n[i]
        if ni < 3 or yi[0] > 0.0 or yi[ni - 1] < 0.0:
            continue
        k = _tip_index(yi, zi, ni, y_from, y_to)
        if k < 0:
            continue
        z_tape = _height_at(yi, zi, ni, 0.0) if math.isnan(tape_circle_z_mm) else \
            tape_circle_z_mm
        z_tip = zi[k]
        sd_level, qr_level = _point_heights(z_tape, z_tip)
        y_sd = _flank_crossing(yi, zi, ni, k, sd_level, quadratic)
        y_qr = _flank_crossing(yi, zi, ni, k, qr_level, quadratic)
        out[i, 0], out[i, 1], out[i, 2] = _sd_sh_qr(y_sd, y_qr, z_tip, z_tape)
    return out


def _parameters(y: NDArray, z: NDArray, n: NDArray,
                tip_region_y_mm: tuple[float, float] = TIP_REGION_Y_MM,
                tape_circle_z_mm: float | None = None, quadratic: bool = True) -> NDArray:
    """The one computation behind :func:`flange_parameters`, :func:`flange_parameters_batch`
    and :func:`flange_parameters_rows`: :func:`_parameters_kernel` on y (1, L) or (M, L) and
    z (M, L) [mm] and the point counts n (M,), each at most L (checked: the compiled loops
    do not check their indices)."""
    y = np.ascontiguousarray(y, dtype=np.float64)
    z = np.ascontiguousarray(z, dtype=np.float64)
    n = np.ascontiguousarray(n, dtype=np.int64)
    if (z.ndim != 2 or y.ndim != 2 or y.shape[1] != z.shape[1]
            or y.shape[0] not in (1, z.shape[0]) or n.shape != (z.shape[0],)
            or (n.size and (n.max() > z.shape[1] or n.min() < 0))):
        raise ValueError(f"y_mm, z_mm: rows of the same length with a point count each, got "
                         f"y {y.shape}, z {z.shape}, n {n.shape}")
    return np.asarray(_parameters_kernel(y, z, n, float(tip_region_y_mm[0]),
        float(tip_region_y_mm[1]),
        math.nan if tape_circle_z_mm is None else float(tape_circle_z_mm), bool(quadratic)))


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
    Non-finite points are dropped; the rest go through :func:`_parameters` as one row.
    """
    if interpolation not in ("quadratic", "linear"):
        raise ValueError(f"interpolation must be 'quadratic' or 'linear', got {interpolation!r}")
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    if y.ndim != 1 or z.shape != y.shape:
        raise ValueError(f"y_mm, z_mm: one profile, got shapes {y.shape}, {z.shape}")
    finite = np.isfinite(z) & np.isfinite(y)
    if not finite.all():
        y, z = y[finite], z[finite]
    sd, sh, qr = _parameters(y[None, :], z[None, :], np.array([y.size]), tip_region_y_mm,
                             tape_circle_z_mm, interpolation == "quadratic")[0].tolist()
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


def tape_circle_height_mm(y_mm: ArrayLike, z_mm: ArrayLike) -> float:
    """Height [mm] of a profile (or a wear curve) at the tape circle y = 0: z at y = 0 by
    the chord between the neighbouring points (``np.interp``'s numbers, the end heights
    outside the data). y_mm ascending [mm], z_mm [mm]."""
    y = np.ascontiguousarray(y_mm, dtype=np.float64)
    z = np.ascontiguousarray(z_mm, dtype=np.float64)
    if y.ndim != 1 or y.size == 0 or z.shape != y.shape:
        raise ValueError(f"y_mm, z_mm: one or more points each, got {y.shape}, {z.shape}")
    return float(_height_at(y, z, y.size, 0.0))


def flange_parameters_batch(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    *,
    tip_region_y_mm: tuple[float, float] = TIP_REGION_Y_MM,
) -> FlangeParameterArrays:
    """Sd, Sh and qR of many profiles sampled on one common lateral grid (one compiled loop).

    Parameters
    ----------
    y_mm : (g,) ascending lateral grid [mm] from the tape circle (back face at -70)
    z_mm : (N, g) or (g,) heights [mm], positive towards the flange tip
    tip_region_y_mm : where the flange tip is looked for [mm]

    Returns
    -------
    FlangeParameterArrays of shape (N,). The result of every row is that of
    :func:`flange_parameters` on the row, to the bit (the same :func:`_parameters`); rows
    with non-finite heights are passed to it one by one.
    """
    y = np.asarray(y_mm, dtype=float)
    z = np.atleast_2d(np.asarray(z_mm, dtype=float))
    if y.ndim != 1 or z.ndim != 2 or z.shape[1] != y.size:
        raise ValueError(f"z_mm: must have shape (N, {y.size}), got {np.shape(z_mm)}")
    n = z.shape[0]
    out = np.full((n, 3), np.nan)
    finite = np.isfinite(z).all(axis=1) & bool(np.isfinite(y).all())
    for r in np.flatnonzero(~finite):
        fp = flange_parameters(y, z[r], tip_region_y_mm=tip_region_y_mm)
        out[r] = fp.sd_mm, fp.sh_mm, fp.qr_mm
    if finite.any():
        rows = z if finite.all() else z[finite]
        out[finite] = _parameters(y[None, :], rows, np.full(rows.shape[0], y.size),
                                  tip_region_y_mm)
    return FlangeParameterArrays(out[:, 0].copy(), out[:, 1].copy(), out[:, 2].copy())


def flange_parameters_rows(
    y_mm: NDArray[np.float64],
    z_mm: NDArray[np.float64],
    valid: NDArray[np.bool_],
    *,
    tip_region_y_mm: tuple[float, float] = TIP_REGION_Y_MM,
) -> NDArray[np.float64]:
    """:func:`flange_parameters` of many profiles of different lengths (one compiled loop).

    Parameters
    ----------
    y_mm, z_mm : (M, L) padded rows [mm]: each profile's points ascending in y in the first
        columns of its row, finite; the rest padding (any values)
    valid : (M, L) the profiles' columns (``valid[i, :n_i]`` True, the rest False)
    tip_region_y_mm : where the flange tip is looked for [mm]

    Returns
    -------
    (M, 3) Sd, Sh, qR [mm], each row that of :func:`flange_parameters` on the profile, to
    the bit (the same :func:`_parameters`); NaN where a point is not in the data.
    """
    return _parameters(y_mm, z_mm, valid.sum(axis=1), tip_region_y_mm)
