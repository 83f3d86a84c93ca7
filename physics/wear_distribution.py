"""From worn volume to worn profile: global and local application, normal mapping, smoothing.

* Global application (seed 004 eqs. 3-5): the worn volume of a patch, Delta V [mm^3], removed
  around the wheel's circumference is the cross-section area A = Delta V / (2 pi R_cp)
  [mm^2], spread across the patch with a semi-elliptic normal depth
  Delta z_n(s) = Delta z_0 sqrt(1 - s^2/b^2), s the arc coordinate across the patch, b its
  lateral semi-axis; Delta z_0 = Delta V / (pi^2 R_cp b) (eq. 5). Seed 004 eq. (4) weighs the
  arc element with cos(delta); we use the geometric relation ds = dy / cos(delta) instead, so
  the volume of seed 002 eq. (8) of the worn profile equals the law's Delta V on any part of
  the profile (the two agree on the tread, delta ~ 0). The semi-ellipse is integrated exactly
  over each grid cell, so a patch narrower than the grid spacing still removes exactly its
  volume (no aliasing peaks).
* Local application (seed 002 eqs. 4-5): Archard per element of the FASTSIM grid,
  Delta z_n(x, y) = k(v_el, p_el) p_el s_el / H with the element's sliding distance
  s_el = |slip| dx and zone from the element's own sliding speed and pressure; summed along each
  longitudinal strip and spread over the circumference (divided by 2 pi R_cp).
* The normal depth moves each profile point along the inward normal (seed 004 eq. 9):
  Y_w = Y + d sin(delta), Z_w = Z - d cos(delta), tan(delta) = dZ/dY; the worn profile is
  re-sampled on the original Y. Seed 002 eqs. (6)-(7) print Delta Y = d / sqrt(1 + g^2) and
  Delta Z = d g / sqrt(1 + g^2), which swaps the components for a gradient g = dZ/dY; we use
  the geometric (eq. 9) form, :func:`normal_to_lateral_vertical`.
* Worn volume (seed 002 eq. 8): Delta W = int (Z_or - Z_worn) 2 pi R_w(Y) dY, R_w = R0 + Z.
* Smoothing of the worn depth: moving average (window in mm) or a smoothing spline
  (scipy's ``make_smoothing_spline``; penalty ``lam``); both are linear in the depth.

Wheel frame of docs/conventions.md: y [mm] lateral (negative towards the flange), z [mm] radius
increase
over the tape circle; depths in mm, positive = material removed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, cast, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import make_smoothing_spline
from scipy.ndimage import uniform_filter1d
from scipy.spatial import cKDTree

from wearcast.physics.contact.fastsim import FastsimResult
from wearcast.physics.wear_laws import ArchardKTH, kth_zone

#: How a patch's wear is laid on the profile: ``global`` (its worn volume spread
#: semi-elliptically, seed 004 eqs. 3-5) or ``local`` (per element of the FASTSIM grid, seed
#: 002 eqs. 4-5).
Application = Literal["global", "local"]
APPLICATIONS: tuple[Application, ...] = get_args(Application)
#: Methods of :class:`Smoothing`.
SmoothingMethod = Literal["moving_average", "spline", "none"]
SMOOTHING_METHODS: tuple[SmoothingMethod, ...] = get_args(SmoothingMethod)


def check_application(application: str) -> Application:
    """``application`` itself when it is ``global`` or ``local``; a ValueError naming it
    otherwise."""
    if application not in APPLICATIONS:
        raise ValueError(f"application must be 'global' or 'local', got {application!r}")
    return cast(Application, application)


def _grid_step(y_grid_mm: NDArray[np.float64]) -> float:
    step = np.diff(y_grid_mm)
    if y_grid_mm.ndim != 1 or step.size < 1 or np.any(step <= 0):
        raise ValueError("y_grid_mm must be 1-D, ascending, with at least two points")
    if not np.allclose(step, step[0], rtol=1e-6, atol=1e-9):
        raise ValueError("y_grid_mm must be uniformly spaced")
    return float(step[0])


def _semicircle_cdf(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """Share of the area of the unit semi-ellipse sqrt(1 - u^2) left of u."""
    u = np.clip(u, -1.0, 1.0)
    return (u * np.sqrt(1.0 - u * u) + np.arcsin(u)) / np.pi + 0.5


def semi_elliptic_depth(y_grid_mm: ArrayLike, centre_y_mm: ArrayLike, b_mm: ArrayLike,
                        volume_mm3: ArrayLike, rolling_radius_mm: ArrayLike,
                        contact_angle_rad: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Global application: normal wear depth of patches on a uniform y grid (seed 004 eqs. 3-5).

    Parameters
    ----------
    y_grid_mm : (n,) uniform lateral grid of the wheel profile [mm]
    centre_y_mm : patch centres on the wheel profile [mm], batch shape S
    b_mm : lateral semi-axes (along the profile arc) [mm]
    volume_mm3 : worn volume removed from the wheel [mm^3]
    rolling_radius_mm : wheel radius at the contact R_cp [mm]
    contact_angle_rad : profile angle delta at the patch [rad] (the patch spans b cos(delta)
        in y)

    Returns
    -------
    normal depth [mm], shape S + (n,). Its vertical equivalent (depth / cos(delta)) integrates
    over y to Delta V / (2 pi R_cp) exactly; its peak is Delta z_0 = Delta V / (pi^2 R_cp b).
    """
    y = np.asarray(y_grid_mm, dtype=float)
    h = _grid_step(y)
    yc, b, vol, r, d = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (
        centre_y_mm, b_mm, volume_mm3, rolling_radius_mm, contact_angle_rad)))
    if np.any(b <= 0) or np.any(r <= 0):
        raise ValueError("b_mm and rolling_radius_mm must be positive")
    cos_d = np.cos(d)[..., None]
    half = b[..., None] * cos_d
    area = (vol / (2.0 * np.pi * r))[..., None]
    cells = _patch_window(y, h, yc, half[..., 0], area[..., 0])
    if cells is None:
        lo = (y - 0.5 * h - yc[..., None]) / half
        hi = (y + 0.5 * h - yc[..., None]) / half
        weight = _semicircle_cdf(hi) - _semicircle_cdf(lo)
        return area * weight / h * cos_d
    # the same formula on each patch's window of cells only (``_patch_window``)
    y_cells = y[cells]
    lo = (y_cells - 0.5 * h - yc.reshape(-1, 1)) / half.reshape(-1, 1)
    hi = (y_cells + 0.5 * h - yc.reshape(-1, 1)) / half.reshape(-1, 1)
    weight = _semicircle_cdf(hi) - _semicircle_cdf(lo)
    values = area.reshape(-1, 1) * weight / h * cos_d.reshape(-1, 1)
    out = np.zeros((yc.size, y.size))
    out[np.arange(yc.size)[:, None], cells] = values
    return out.reshape(yc.shape + (y.size,))


#: Cells beyond a patch's extent on either side that :func:`semi_elliptic_depth` still
#: evaluates (margin for the rounding of the window's bounds; the weight there is exactly 0).
_WINDOW_MARGIN_CELLS = 2


def _patch_window(y: NDArray[np.float64], h: float, yc: NDArray[np.float64],
                  half: NDArray[np.float64], area: NDArray[np.float64]
                  ) -> NDArray[np.intp] | None:
    """The cells of the uniform grid ``y`` (spacing h) that :func:`semi_elliptic_depth`
    evaluates for each patch (centre yc, half-width ``half`` in y [mm], batch shape S): one
    window of equal width per patch, shape (prod S, W), covering the patch's extent
    [yc - half, yc + half] and ``_WINDOW_MARGIN_CELLS`` more cells on each side, clipped to the
    grid (a clipped window repeats its edge cell).

    Outside the extent both cell bounds u = (y -/+ h/2 - yc) / half lie beyond -1 or +1, so
    ``_semicircle_cdf`` clips them to the same value and the weight is exactly 0: the depth
    there is exactly 0 and computing the formula only in the windows gives the dense result
    bit for bit (``tests/physics/test_wear_distribution.py``). None (evaluate every cell)
    when an input is not finite (a non-finite area times a zero weight is NaN, not 0) or the
    windows would not be narrower than the grid."""
    if yc.size == 0 or not (np.all(np.isfinite(yc)) and np.all(np.isfinite(half))
                            and np.all(half > 0) and np.all(np.isfinite(area))):
        return None
    first = np.floor((yc - half - y[0]) / h).astype(np.intp).reshape(-1) - _WINDOW_MARGIN_CELLS
    last = np.ceil((yc + half - y[0]) / h).astype(np.intp).reshape(-1) + _WINDOW_MARGIN_CELLS
    width = int(np.max(last - first)) + 1
    if width >= y.size:
        return None
    return np.clip(first[:, None] + np.arange(width)[None, :], 0, y.size - 1)


def _box_deposit(y_grid_mm: NDArray[np.float64], step_mm: float, centre_mm: NDArray[np.float64],
                 width_mm: NDArray[np.float64], area: NDArray[np.float64]) -> NDArray[np.float64]:
    """Deposit boxes [c - w/2, c + w/2] onto the cells [y_i - h/2, y_i + h/2] of a uniform grid.

    centre_mm, width_mm : (P, m) box centres and widths [mm] (widths > 0)
    area : (P, k, m) quantity carried by each box (k channels)

    Returns (P, k, n): per cell, the sum of area * overlap / w. The end cells reach to
    infinity, so every box is deposited in full (sum over cells = sum of area exactly) and
    boxes beyond the grid land in the end cells, as before. Each box touches at most
    ceil(w / h) + 1 cells; those few cells are visited in a loop, vectorised over all boxes.
    """
    n = y_grid_mm.size
    start = centre_mm - 0.5 * width_mm
    stop = centre_mm + 0.5 * width_mm
    first = np.clip(np.floor((start - y_grid_mm[0]) / step_mm + 0.5).astype(int), 0, n - 1)
    # ceil(w / h) + 1 cells suffice; one more guards the floor() at a cell edge.
    span = int(np.ceil(np.max(width_mm) / step_mm)) + 2 if width_mm.size else 0
    rows = np.arange(area.shape[0])[:, None, None]
    channels = np.arange(area.shape[1])[None, :, None]
    out = np.zeros((area.shape[0], area.shape[1], n))
    for k in range(span):
        cell = first + k
        inside = cell < n
        cell = np.minimum(cell, n - 1)
        lo = np.where(cell == 0, -np.inf, y_grid_mm[cell] - 0.5 * step_mm)
        hi = np.where(cell == n - 1, np.inf, y_grid_mm[cell] + 0.5 * step_mm)
        overlap = np.clip(np.minimum(hi, stop) - np.maximum(lo, start), 0.0, None)
        share = np.where(inside, overlap / width_mm, 0.0)
        np.add.at(out, (rows, channels, cell[:, None, :]), area * share[:, None, :])
    return out


def local_archard_depth(result: FastsimResult, rolling_speed_m_s: ArrayLike,
                        centre_y_mm: ArrayLike, rolling_radius_mm: ArrayLike,
                        contact_angle_rad: ArrayLike, y_grid_mm: ArrayLike,
                        law: ArchardKTH = ArchardKTH()) -> NDArray[np.float64]:
    """Local application of Archard/KTH on the FASTSIM grid (seed 002 eqs. 4-5), as a basis.

    Parameters
    ----------
    result : FASTSIM solution of P patches (batch shape (P,)); its local y axis must point
        towards the wheel's field side (+y of the wheel frame), as in ``physics.curving``
    rolling_speed_m_s : vehicle speed V [m/s], shape (P,) or scalar
    centre_y_mm, rolling_radius_mm, contact_angle_rad : patch centre on the wheel profile [mm],
        R_cp [mm], profile angle [rad], shape (P,)
    y_grid_mm : (n,) uniform grid of the wheel profile [mm]
    law : zone bounds and hardness (the coefficients are NOT applied)

    Returns
    -------
    normal depth per metre rolled PER UNIT zone coefficient [mm/m], shape (P, 4, n); multiply
    by the zone coefficients (``basis @``-style over axis 1) for the depth per metre rolled.
    Element depth k p s_el / H with s_el = |slip| dx [mm] and the element's zone from its
    sliding speed |slip| V and pressure p. The strip at y_prof = y_c + y_el cos(delta) covers
    [y_prof - w/2, y_prof + w/2], w = dy_el cos(delta), and goes to the grid cells
    [y_i - h/2, y_i + h/2] in proportion to the overlap (box deposition: area-conserving, and
    free of the comb that point deposition leaves on grids finer than the strips).
    """
    y = np.asarray(y_grid_mm, dtype=float)
    h = _grid_step(y)
    shape = np.shape(result.fx_n)
    if len(shape) != 1:
        raise ValueError("local_archard_depth expects a 1-D batch of patches")
    v = np.broadcast_to(np.asarray(rolling_speed_m_s, dtype=float), shape)
    yc, r, d = (np.broadcast_to(np.asarray(a, dtype=float), shape)
                for a in (centre_y_mm, rolling_radius_mm, contact_angle_rad))
    slip = np.hypot(result.sx, result.sy)                       # (P, ny, nx) [-]
    pn = result.pn_mpa                                          # (P, ny, nx) [MPa]
    zone = kth_zone(slip * v[:, None, None], pn, law)           # (P, ny, nx)
    dx = np.asarray(result.dx_mm, dtype=float)[:, None, None]
    per_pass = pn * slip * dx / law.hardness_mpa                # [mm] per unit k
    onehot = zone[:, None, :, :] == np.arange(1, 5)[None, :, None, None]
    strips = np.sum(np.where(onehot, per_pass[:, None], 0.0), axis=-1)  # (P, 4, ny)
    strips = strips * (1000.0 / (2.0 * np.pi * r))[:, None, None]  # per metre rolled
    dy_el = np.asarray(result.dy_mm, dtype=float)               # arc spacing of the strips
    cos_d = np.cos(d)
    y_strip = yc[:, None] + np.asarray(result.y_mm, dtype=float) * cos_d[:, None]  # (P, ny)
    area = strips * dy_el[:, None, None]                        # arc-measure area [mm^2/m]
    width = np.broadcast_to(np.maximum(dy_el * cos_d, 1e-9 * h)[:, None], y_strip.shape)
    out = _box_deposit(y, h, y_strip, width, area)              # [mm^2/m] per cell
    return out * (cos_d / h)[:, None, None]


def local_rate_depth(result: FastsimResult, element_rate_mm_per_m: ArrayLike,
                     centre_y_mm: ArrayLike, rolling_radius_mm: ArrayLike,
                     contact_angle_rad: ArrayLike, y_grid_mm: ArrayLike) -> NDArray[np.float64]:
    """Local application of any law on the FASTSIM grid (seed 003 §4.2, seed 002 eqs. 4-5).

    element_rate_mm_per_m : (P, n_y, n_x) normal depth per metre travelled while the element is
        in contact [mm/m] (``wear_laws.element_depth_rate_mm_per_m``); 0 outside the patch
    Other arguments as :func:`local_archard_depth`.

    Returns the normal depth per metre rolled on the grid [mm/m], shape (P, n). One passage
    through the element removes rate dx / 1000 [mm]; a point of the wheel passes
    1000 / (2 pi R_cp) times per metre rolled, so each longitudinal strip wears
    sum_x rate dx / (2 pi R_cp) per metre; the strips are box-deposited as in
    :func:`local_archard_depth` (volume conserving).
    """
    shape = np.shape(result.fx_n)
    if len(shape) != 1:
        raise ValueError("local_rate_depth expects a 1-D batch of patches")
    rate = np.where(result.in_contact, np.asarray(element_rate_mm_per_m, dtype=float), 0.0)
    r = np.broadcast_to(np.asarray(rolling_radius_mm, dtype=float), shape)
    dx = np.asarray(result.dx_mm, dtype=float)
    dx = np.broadcast_to(dx, shape)[:, None, None]
    strips = np.sum(rate * dx, axis=-1) / (2.0 * np.pi * r)[:, None]      # (P, ny) mm/m
    return _deposit_strips(result, strips[:, None, :], centre_y_mm, contact_angle_rad,
                           y_grid_mm)[:, 0, :]


def _deposit_strips(result: FastsimResult, strips: NDArray[np.float64], centre_y_mm: ArrayLike,
                    contact_angle_rad: ArrayLike, y_grid_mm: ArrayLike) -> NDArray[np.float64]:
    """Box deposition of per-strip normal depths (P, k, n_y) [mm/m] onto the profile grid:
    the strip at y_prof = y_c + y_el cos(delta) covers w = dy_el cos(delta); returns (P, k, n)."""
    y = np.asarray(y_grid_mm, dtype=float)
    h = _grid_step(y)
    shape = np.shape(result.fx_n)
    yc, d = (np.broadcast_to(np.asarray(a, dtype=float), shape)
             for a in (centre_y_mm, contact_angle_rad))
    dy_el = np.broadcast_to(np.asarray(result.dy_mm, dtype=float), shape)
    cos_d = np.cos(d)
    y_strip = yc[:, None] + np.asarray(result.y_mm, dtype=float) * cos_d[:, None]
    area = strips * dy_el[:, None, None]
    width = np.broadcast_to(np.maximum(dy_el * cos_d, 1e-9 * h)[:, None], y_strip.shape)
    out = _box_deposit(y, h, y_strip, width, area)
    return out * (cos_d / h)[:, None, None]


def normal_to_lateral_vertical(normal_depth_mm: ArrayLike, slope: ArrayLike
                               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Lateral and vertical components of a normal wear depth (seed 004 eq. 9; seed 002 eqs.
    6-7 with the components in their geometric order).

    slope : profile gradient dZ/dY [-]. Returns (Delta Y, Delta Z) [mm]: the worn point moves by
    +Delta Y laterally and -Delta Z vertically (into the material).
    """
    d = np.asarray(normal_depth_mm, dtype=float)
    g = np.asarray(slope, dtype=float)
    norm = np.sqrt(1.0 + g * g)
    return d * g / norm, d / norm


def apply_normal_wear(y_mm: ArrayLike, z_mm: ArrayLike, normal_depth_mm: ArrayLike
                      ) -> NDArray[np.float64]:
    """Worn profile z on the same y grid after removing a normal depth (seed 004 eq. 9).

    Each point moves along the inward normal; the moved curve is re-sampled at the original y
    (linear interpolation). Where the moved points fold back (depth larger than the local
    radius of curvature) the vertical equivalent depth / cos(delta) is used instead.
    """
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    d = np.asarray(normal_depth_mm, dtype=float)
    slope = np.gradient(z, y)
    dy, dz = normal_to_lateral_vertical(d, slope)
    yw, zw = y + dy, z - dz
    vertical = z - d * np.sqrt(1.0 + slope * slope)
    if np.all(np.diff(yw) > 0):
        out = np.interp(y, yw, zw)
        # Ends: the moved curve does not cover the grid ends; use the vertical equivalent.
        outside = (y < yw[0]) | (y > yw[-1])
        return np.where(outside, vertical, out)
    return vertical


#: Spacing of the reference curve's points along its arc for :func:`depth_below_mm` [mm].
_DEPTH_ARC_SPACING_MM = 0.02


def depth_below_mm(y_mm: ArrayLike, z_reference_mm: ArrayLike, z_worn_mm: ArrayLike
                   ) -> NDArray[np.float64]:
    """Depth of each worn point below the reference profile, normal to it [mm]: the distance
    from (y, z_worn) to the reference curve where the point lies below it, else 0.

    The vertical difference z_ref - z_worn at a fixed y is this depth over cos(delta) on a
    flank at angle delta (a flange face worn 1 mm sideways at 80 deg differs by 5.8 mm at a
    fixed y), so a depth check that must hold on the flange too (a wheel rim's wear,
    ``wear_loop.MAX_WHEEL_WEAR_MM``) measures this one. The reference curve is re-sampled
    every ``_DEPTH_ARC_SPACING_MM`` of arc, so the distance to its nearest point is within
    half that of the distance to the curve."""
    y = np.asarray(y_mm, dtype=float)
    z0 = np.asarray(z_reference_mm, dtype=float)
    z1 = np.asarray(z_worn_mm, dtype=float)
    out = np.zeros(np.broadcast_shapes(y.shape, z1.shape))
    below = np.broadcast_to(z0 - z1 > 0, out.shape)
    if not np.any(below):
        return out
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(y), np.diff(z0)))])
    s = np.linspace(0.0, arc[-1], max(int(arc[-1] / _DEPTH_ARC_SPACING_MM) + 1, 2))
    tree = cKDTree(np.column_stack([np.interp(s, arc, y), np.interp(s, arc, z0)]))
    points = np.column_stack([np.broadcast_to(y, out.shape)[below], z1[below]])
    out[below] = tree.query(points)[0]
    return out


def worn_volume_mm3(y_mm: ArrayLike, z_reference_mm: ArrayLike, z_worn_mm: ArrayLike,
                    wheel_radius_mm: float) -> float:
    """Worn volume between two profiles (seed 002 eq. 8) [mm^3].

    Delta W = int (Z_or - Z_worn) 2 pi R_w(Y) dY with R_w = wheel_radius_mm + Z_or(Y) (the
    rolling radius at Y; z is the radius increase over the tape circle).
    """
    y = np.asarray(y_mm, dtype=float)
    z0 = np.asarray(z_reference_mm, dtype=float)
    z1 = np.asarray(z_worn_mm, dtype=float)
    return float(np.trapezoid((z0 - z1) * 2.0 * np.pi * (wheel_radius_mm + z0), y))


def moving_average(values: ArrayLike, y_grid_mm: ArrayLike, window_mm: float) -> NDArray:
    """Centred moving average over ``window_mm`` along the last axis (edges: nearest).

    Conserves the integral away from the ends; linear in ``values``.
    """
    y = np.asarray(y_grid_mm, dtype=float)
    h = _grid_step(y)
    n = max(1, int(round(window_mm / h)) | 1)  # odd number of samples
    if n == 1:
        return np.asarray(values, dtype=float).copy()
    return uniform_filter1d(np.asarray(values, dtype=float), n, axis=-1, mode="nearest")


def smoothing_spline(values: ArrayLike, y_grid_mm: ArrayLike, lam: float = 1.0) -> NDArray:
    """Cubic smoothing spline of the depth along y (penalty ``lam`` [mm^3]; larger = smoother).

    Linear in ``values`` (the spline is a linear smoother); any leading batch dimensions.
    """
    y = np.asarray(y_grid_mm, dtype=float)
    vals = np.asarray(values, dtype=float)
    flat = vals.reshape(-1, vals.shape[-1])
    out = np.empty_like(flat)
    for i, row in enumerate(flat):
        out[i] = make_smoothing_spline(y, row, lam=lam)(y)
    return out.reshape(vals.shape)


@dataclass(frozen=True)
class Smoothing:
    """Smoothing of the worn depth per step.

    method : ``moving_average`` | ``spline`` | ``none``
    window_mm : moving-average window [mm]
    lam : smoothing-spline penalty [mm^3]
    clip_negative : set negative smoothed depths (spline undershoot) to zero
    """

    method: str = "moving_average"
    window_mm: float = 3.0
    lam: float = 2.0
    clip_negative: bool = True

    def __post_init__(self) -> None:
        if self.method not in SMOOTHING_METHODS:
            raise ValueError("smoothing method must be 'moving_average', 'spline' or 'none'")
        if self.window_mm <= 0 or self.lam <= 0:
            raise ValueError("window_mm and lam must be positive")

    def apply(self, values: ArrayLike, y_grid_mm: ArrayLike) -> NDArray[np.float64]:
        """Smoothed depth (linear in values unless ``clip_negative`` acts)."""
        if self.method == "none":
            out = np.asarray(values, dtype=float).copy()
        elif self.method == "moving_average":
            out = moving_average(values, y_grid_mm, self.window_mm)
        else:
            out = smoothing_spline(values, y_grid_mm, self.lam)
        return np.maximum(out, 0.0) if self.clip_negative else out
