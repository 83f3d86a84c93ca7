"""Rigid alignment of a measured wheel profile to its reference profile.

Seed 000 §IV.A corrects the position of a measured profile by minimising the mean distance
between the measured and the reference curve over a lateral shift X, a vertical shift Y and a
rotation alpha (eq. 2, solved there by Hooke–Jeeves pattern search). docs/conventions.md "The hybrid
model" step 1 asks for the same three-parameter least-squares fit. Here it is solved by
Gauss–Newton with iteratively reweighted least squares, because the fit must run in well under
a millisecond per profile:

* model: a measured point (y, z) maps to (y', z') = R(theta) (y, z) + (dy, dz), rotation about
  the tape-circle origin;
* residual: the vertical gap z' - z_ref(y') scaled by 1 / sqrt(1 + z_ref'(y')^2), i.e. the
  first-order normal distance (seed 000's point-to-curve distance d_k);
* which points: only parts of the wheel that do not wear, so that wear does not pull the fit:
  the flange back ``FIT_WINDOWS_MM[0]`` (-69 <= y <= -58: never in rail contact except on
  check rails) and the field-side end of the tread ``FIT_WINDOWS_MM[1]`` (40 <= y <= 58:
  beyond the running band of seed 001 Figs. 6-7, whose tread wear ends near y = +30). The two
  windows are ~100 mm apart, so rotation is well determined; the steep flange back fixes the
  lateral shift. If a window has fewer than ``MIN_WINDOW_POINTS`` points, all points in the
  reference's range are used instead (noted by ``used_windows = False``);
* robustness: Huber weights (c = 1.345 sigma, sigma from the MAD of the residuals) drop the
  influence of outliers and of any wear that reaches into the windows.

The reference height is tabulated once per reference function on a 0.01 mm grid (linear
interpolation error < 1e-5 mm for S1002, whose smallest radius is 12 mm) with its slope.

Each rule of the fit is one function here (``fit_mask``, ``rotate``, ``on_reference``,
``residuals_and_jacobian``, ``huber_weights``, ``solve3``, ``converged``,
``normal_distances``), written for one profile's points or for padded rows of many: the block
alignment (:mod:`.alignment_batch`) calls the same functions on a chunk of profiles.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.ragged import upper_median

ReferenceHeight = Callable[[ArrayLike], NDArray[np.float64]]

#: Lateral windows [mm] of unworn wheel used for the fit: flange back, field-side end.
FIT_WINDOWS_MM: tuple[tuple[float, float], tuple[float, float]] = ((-69.0, -58.0), (40.0, 58.0))
#: Fewest points per window before falling back to the whole profile.
MIN_WINDOW_POINTS = 8
#: Largest |dz/dy| of the reference used in a residual; steeper points are left out.
_MAX_SLOPE = 8.0
#: Huber tuning constant [robust sigma] and the median-to-sigma factor of the fit's weights.
HUBER_C = 1.345
MAD_TO_SIGMA = 1.4826
#: Smallest robust scale [mm] behind the Huber cutoff.
MIN_SCALE_MM = 1e-3
_TABLE_Y_MIN_MM = -80.0
_TABLE_Y_MAX_MM = 80.0
_TABLE_STEP_MM = 0.01


@dataclass(frozen=True)
class ReferenceTable:
    """A reference profile tabulated for fast interpolation.

    Attributes
    ----------
    y_mm : ascending lateral grid [mm] covering where the reference is defined
    z_mm : reference height [mm]
    slope : dz/dy of the reference [-] (central differences of the function)
    """

    y_mm: NDArray[np.float64]
    z_mm: NDArray[np.float64]
    slope: NDArray[np.float64]

    def height_mm(self, y_mm: ArrayLike) -> NDArray[np.float64]:
        """Reference height at y [mm]; NaN outside the tabulated range."""
        return np.interp(np.asarray(y_mm, dtype=float), self.y_mm, self.z_mm, left=np.nan,
                         right=np.nan)


@lru_cache(maxsize=16)
def reference_table(reference_height: ReferenceHeight = s1002_height_mm) -> ReferenceTable:
    """Tabulate ``reference_height`` (y [mm] -> z [mm], NaN where undefined), cached."""
    n = int(round((_TABLE_Y_MAX_MM - _TABLE_Y_MIN_MM) / _TABLE_STEP_MM)) + 1
    y = np.linspace(_TABLE_Y_MIN_MM, _TABLE_Y_MAX_MM, n)
    z = np.asarray(reference_height(y), dtype=float)
    h = 1e-4
    slope = (np.asarray(reference_height(y + h)) - np.asarray(reference_height(y - h))) / (2 * h)
    defined = np.isfinite(z)
    if defined.sum() < 2:
        raise ValueError("reference profile is undefined on -80 <= y <= 80 mm")
    first, last = np.flatnonzero(defined)[[0, -1]]
    y, z, slope = y[first : last + 1], z[first : last + 1], slope[first : last + 1]
    # one-sided differences at the ends of the definition range
    slope = np.where(np.isfinite(slope), slope, np.gradient(z, y))
    return ReferenceTable(y_mm=y, z_mm=z, slope=slope)


@dataclass(frozen=True)
class AlignedProfile:
    """A profile moved onto its reference (seed 000 §IV.A).

    Attributes
    ----------
    y_mm, z_mm : aligned coordinates [mm], ascending y
    lateral_shift_mm, vertical_shift_mm : translation applied after the rotation [mm]
    rotation_rad : rotation applied about the origin [rad], positive counter-clockwise in
        the (y, z) plane
    rms_residual_mm : RMS normal distance to the reference over the fitted points [mm]
    n_used : number of points in the fit
    used_windows : True if the unworn windows were used, False if the whole profile was
    """

    y_mm: NDArray[np.float64]
    z_mm: NDArray[np.float64]
    lateral_shift_mm: float
    vertical_shift_mm: float
    rotation_rad: float
    rms_residual_mm: float
    n_used: int
    used_windows: bool = True


def fit_mask(y: NDArray, y_lo_mm: float, y_hi_mm: float,
             windows_mm: tuple[tuple[float, float], ...],
             valid: NDArray[np.bool_] | None = None) -> tuple[NDArray[np.bool_], NDArray]:
    """The points the fit uses, of a profile y (n,) [mm] or of padded rows (M, n) with their
    valid entries ``valid``: those in the unworn windows ``windows_mm`` and inside the
    reference's range [y_lo_mm, y_hi_mm] if every window holds ``MIN_WINDOW_POINTS``, else
    all points inside the range; and whether the windows were used (per row)."""
    inside = (y >= y_lo_mm) & (y <= y_hi_mm)
    if valid is not None:
        inside &= valid
    use = np.ones(y.shape[:-1], dtype=bool)
    union = np.zeros(y.shape, dtype=bool)
    for lo, hi in windows_mm:
        window = (y >= lo) & (y <= hi)
        if valid is not None:
            window &= valid
        use &= window.sum(axis=-1) >= MIN_WINDOW_POINTS
        union |= window
    return np.where(use[..., None], union & inside, inside), use


def rotate(y: NDArray, z: NDArray, c: Any, s: Any) -> tuple[NDArray, NDArray]:
    """Points (y, z) [mm] rotated about the tape-circle origin by the angle whose cosine and
    sine are ``c`` and ``s`` (seed 000 §IV.A: R(theta) (y, z); the shifts are added after)."""
    return c * y - s * z, s * y + c * z


def on_reference(yp: NDArray, slope: NDArray, y_lo_mm: float, y_hi_mm: float
                 ) -> NDArray[np.bool_]:
    """Which moved points y' [mm] a residual may use: strictly inside the reference's range
    and off its near-vertical parts (|dz/dy| of the reference below ``_MAX_SLOPE``)."""
    return (yp > y_lo_mm) & (yp < y_hi_mm) & (np.abs(slope) < _MAX_SLOPE)


def residuals_and_jacobian(yr: NDArray, zr: NDArray, dz: Any, z_ref: NDArray,
                           slope: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Seed 000 eq. (2)'s residuals, linearised: of the rotated points (yr, zr) [mm] shifted by
    dz [mm], the vertical gap to the reference height ``z_ref`` [mm] at the moved y scaled by
    1 / sqrt(1 + z_ref'^2) (first-order normal distance; ``slope`` = z_ref'), and its
    derivatives by the lateral shift, the vertical shift and the rotation
    (d(z' - f(y'))/dtheta = yr + f' zr)."""
    norm = 1.0 / np.sqrt(1.0 + slope * slope)
    residual = (zr + dz - z_ref) * norm
    return residual, -slope * norm, norm, (yr + slope * zr) * norm


def normal_distances(zr: NDArray, dz: Any, z_ref: NDArray, slope: NDArray
                     ) -> tuple[NDArray, NDArray[np.bool_]]:
    """Normal distances [mm] of the aligned points to the reference at the solution (the
    reported RMS residual): (zr + dz - z_ref) / sqrt(1 + z_ref'^2), and which of them count
    (the reference defined there, ``z_ref`` not NaN, and not near-vertical)."""
    good = np.isfinite(z_ref) & (np.abs(slope) < _MAX_SLOPE)
    return (zr + dz - z_ref) / np.sqrt(1.0 + slope ** 2), good


def converged(x0: Any, x1: Any, x2: Any, tolerance: float) -> Any:
    """Whether a Gauss–Newton step (lateral [mm], vertical [mm], rotation [rad]) is below
    ``tolerance`` (rotation weighted by 100 mm, the scale of the profile)."""
    return abs(x0) + abs(x1) + 100.0 * abs(x2) < tolerance


def _fit_points(y_mm: ArrayLike, z_mm: ArrayLike, reference_height: ReferenceHeight,
                windows_mm: tuple[tuple[float, float], ...]
                ) -> tuple[NDArray, NDArray, ReferenceTable, NDArray, bool]:
    """The profile as float arrays, its reference's table, the fit points (``fit_mask``)
    and whether the unworn windows were used."""
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    table = reference_table(reference_height)
    mask, used_windows = fit_mask(y, float(table.y_mm[0]), float(table.y_mm[-1]), windows_mm)
    return y, z, table, mask, bool(used_windows)


def huber_weights(abs_residual_mm: NDArray, valid: NDArray[np.bool_] | None = None) -> NDArray:
    """Huber IRLS weights min(1, c / |r|) of absolute residuals [mm]: c = 1.345 sigma, sigma
    1.4826 times their (upper) median, at least ``MIN_SCALE_MM``. Of one profile's residuals
    (n,), or of padded rows (M, n) with their valid entries ``valid`` (weight 0 elsewhere)."""
    if valid is None:
        half = abs_residual_mm.size // 2
        median = float(np.partition(abs_residual_mm, half)[half])
        cutoff: Any = HUBER_C * max(MAD_TO_SIGMA * median, MIN_SCALE_MM)
    else:
        median_rows = upper_median(abs_residual_mm, valid)
        cutoff = (HUBER_C * np.maximum(MAD_TO_SIGMA * median_rows, MIN_SCALE_MM))[:, None]
    weights = np.minimum(1.0, cutoff / np.maximum(abs_residual_mm, 1e-300))
    return weights if valid is None else np.where(valid, weights, 0.0)


def solve3(a00: Any, a01: Any, a02: Any, a10: Any, a11: Any, a12: Any, a20: Any, a21: Any,
           a22: Any, b0: Any, b1: Any, b2: Any) -> tuple[Any, Any, Any, Any]:
    """Solve the 3x3 system a x = b by Cramer's rule (cheaper than LAPACK at this size), for
    numbers or elementwise for arrays (one system per entry); also whether the system is
    regular (its determinant finite and at least 1e-12 |a00 a11 a22|; else x is
    meaningless)."""
    c00 = a11 * a22 - a12 * a21
    c01 = a12 * a20 - a10 * a22
    c02 = a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    scale = abs(a00 * a11 * a22) + 1e-300
    regular = (abs(det) >= 1e-12 * scale) & (abs(det) < math.inf)  # False for NaN too
    det = (det if regular else 1.0) if isinstance(det, float) else np.where(regular, det, 1.0)
    x0 = (b0 * c00 + a01 * (b2 * a12 - b1 * a22) + a02 * (b1 * a21 - b2 * a11)) / det
    x1 = (a00 * (b1 * a22 - b2 * a12) + b0 * c01 + a02 * (b2 * a10 - b1 * a20)) / det
    x2 = (a00 * (b2 * a11 - b1 * a21) + a01 * (b1 * a20 - b2 * a10) + b0 * c02) / det
    return x0, x1, x2, regular


_SINGULAR = "alignment is singular: the profile lacks the shape to fix the fit"
_NO_OVERLAP = "profile does not overlap its reference profile; cannot align"


def align_to_reference(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    reference_height: ReferenceHeight = s1002_height_mm,
    *,
    windows_mm: tuple[tuple[float, float], ...] = FIT_WINDOWS_MM,
    max_iterations: int = 10,
    tolerance: float = 1e-3,
    robust: bool = True,
) -> AlignedProfile:
    """Least-squares rigid alignment (lateral, vertical shift, rotation) to a reference.

    Parameters
    ----------
    y_mm, z_mm : cleaned profile [mm], ascending y, wheel frame (approximately placed)
    reference_height : vectorised reference z(y) [mm], NaN where undefined (default S1002)
    windows_mm : lateral windows [mm] of unworn profile the fit uses (see module doc)
    max_iterations : Gauss–Newton steps at most
    tolerance : stop when the parameter step is below this [mm, rad]
    robust : Huber reweighting of the residuals

    Returns
    -------
    AlignedProfile

    Seed 000 §IV.A eq. (2) (objective), solved by Gauss–Newton/IRLS instead of pattern search.
    """
    y, z, table, mask, used_windows = _fit_points(y_mm, z_mm, reference_height, windows_mm)
    yf, zf = y[mask], z[mask]
    if yf.size < 3:
        raise ValueError(_NO_OVERLAP)

    dy = dz = theta = 0.0
    ty, tz, ts = table.y_mm, table.z_mm, table.slope
    y_lo, y_hi = float(ty[0]), float(ty[-1])
    check_points = True
    for iteration in range(max_iterations):
        yr, zr = rotate(yf, zf, math.cos(theta), math.sin(theta))
        yp = yr + dy
        if check_points or yp.min() <= y_lo or yp.max() >= y_hi:
            # keep points inside the reference's range and off its near-vertical parts
            good = on_reference(yp, np.interp(yp, ty, ts), y_lo, y_hi)
            if good.sum() < 3:
                raise ValueError(_NO_OVERLAP)
            if not good.all():
                yf, zf, yr, zr, yp = yf[good], zf[good], yr[good], zr[good], yp[good]
            check_points = False
        residual, *rows = residuals_and_jacobian(yr, zr, dz, np.interp(yp, ty, tz),
                                                 np.interp(yp, ty, ts))
        jac = np.stack(rows)
        if robust and iteration >= 1:
            # Huber weights, scale from the MAD of the current residuals
            jw = jac * huber_weights(np.abs(residual))
        else:
            jw = jac
        x0, x1, x2, regular = solve3(*(jw @ jac.T).ravel().tolist(),
                                     *(-(jw @ residual)).tolist())
        if not regular:
            raise ValueError(_SINGULAR)
        dy += x0
        dz += x1
        theta += x2
        if iteration >= 2 and converged(x0, x1, x2, tolerance):
            break

    c, s = np.cos(theta), np.sin(theta)
    y_al, z_al = rotate(y, z, c, s)
    y_al, z_al = y_al + dy, z_al + dz
    if theta != 0.0 and np.any(np.diff(y_al) <= 0.0):
        order = np.argsort(y_al, kind="stable")
        y_al, z_al = y_al[order], z_al[order]
    # final residual at the solution
    yr, zr = rotate(yf, zf, c, s)
    yp = yr + dy
    r, good = normal_distances(zr, dz, np.interp(yp, ty, tz, left=np.nan, right=np.nan),
                               np.interp(yp, ty, ts))
    r = r[good]
    rms = float(np.sqrt(np.mean(r * r))) if r.size else float("nan")
    return AlignedProfile(
        y_mm=y_al,
        z_mm=z_al,
        lateral_shift_mm=float(dy),
        vertical_shift_mm=float(dz),
        rotation_rad=float(theta),
        rms_residual_mm=rms,
        n_used=int(good.sum()),
        used_windows=used_windows,
    )


def align_vertically(
    y_mm: ArrayLike,
    z_mm: ArrayLike,
    reference_height: ReferenceHeight = s1002_height_mm,
    *,
    windows_mm: tuple[tuple[float, float], ...] = FIT_WINDOWS_MM,
    max_iterations: int = 10,
    tolerance_mm: float = 1e-4,
) -> AlignedProfile:
    """Lateral-datum-preserving alignment: a vertical shift only, no rotation.

    The profile keeps the lateral position of the instrument's datum (the back face) and
    is moved up or down so that its unworn windows (``windows_mm``: flange back and the
    field-side end) lie on the reference in the least-squares sense, with Huber weights as in
    :func:`align_to_reference` (normal distances, near-vertical reference parts left out).
    Sd, Sh and qR are heights and widths relative to the profile's own tape circle, so this
    shift leaves them unchanged.

    Parameters
    ----------
    y_mm, z_mm : cleaned profile [mm], ascending y, placed on its datum
    reference_height : reference z(y) [mm], NaN where undefined (default S1002)
    windows_mm : lateral windows [mm] of unworn profile
    max_iterations : IRLS steps at most
    tolerance_mm : stop when the shift changes by less than this [mm]

    Returns
    -------
    AlignedProfile with ``lateral_shift_mm = rotation_rad = 0``.
    """
    y, z, table, mask, used_windows = _fit_points(y_mm, z_mm, reference_height, windows_mm)
    slope = np.interp(y, table.y_mm, table.slope)
    mask &= np.abs(slope) < _MAX_SLOPE
    if int(mask.sum()) < 3:
        raise ValueError(_NO_OVERLAP)
    yf, zf = y[mask], z[mask]
    z_ref = np.interp(yf, table.y_mm, table.z_mm)
    norm2 = 1.0 / (1.0 + slope[mask] ** 2)
    gap = z_ref - zf  # vertical gap the shift should close
    weights = np.ones_like(gap)
    dz = 0.0
    for _ in range(max_iterations):
        new = float(np.sum(weights * norm2 * gap) / np.sum(weights * norm2))
        residual = np.abs(zf + new - z_ref) * np.sqrt(norm2)
        weights = huber_weights(residual)
        done = abs(new - dz) < tolerance_mm
        dz = new
        if done:
            break
    r = (zf + dz - z_ref) * np.sqrt(norm2)
    return AlignedProfile(
        y_mm=y.copy(), z_mm=z + dz, lateral_shift_mm=0.0, vertical_shift_mm=dz,
        rotation_rad=0.0, rms_residual_mm=float(np.sqrt(np.mean(r * r))),
        n_used=int(mask.sum()), used_windows=used_windows)
