"""Wear states: averaged wear-curve shapes ordered by wear area (seed 001 §2.1, §3.2, Fig. 9).

Seed 001's premise is that every wheel passes the same sequence of wear shapes, at a mileage
set by its wear rate; wear area is therefore the ordering variable and shape the grouping
check. Per region (flange: y < split, tread: y >= split) we

1. drop curves with non-positive area (no shape information),
2. sort by area and cut into ``n_states`` groups of equal count (area quantiles; equal counts
   give every state the same averaging noise, and the seed groups by "similar wear values"),
3. within each group reject shape outliers: the area-normalised shape u = w / A of each curve
   is compared with the group's median shape by the L1 distance ∫|u - median| dy (0..2);
   curves beyond median + 3 robust sigmas are left out (misaligned or atypical profiles),
4. average the remaining curves into the state and compute its area with the same
   integral that is used for interpolation.

The curve for an arbitrary area interpolates linearly between the neighbouring states (the
zero curve is state 0) and is exact in area because the area integral is linear; beyond the
largest state the largest state's shape is scaled and flagged as extrapolated.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import uniform_filter1d


def region_mask(grid_y_mm: ArrayLike, split_y_mm: float, region: str) -> NDArray[np.bool_]:
    """Grid points of a region: flange y < split, tread y >= split (docs/conventions.md)."""
    y = np.asarray(grid_y_mm, dtype=float)
    if region == "flange":
        return y < split_y_mm
    if region == "tread":
        return y >= split_y_mm
    raise ValueError(f"region: must be 'flange' or 'tread', got {region!r}")


def region_area_mm2(grid_y_mm: ArrayLike, curves_mm: ArrayLike, split_y_mm: float,
                    region: str) -> NDArray[np.float64]:
    """Wear area ∫ w dy [mm²] of one region, for one curve (g,) or many (..., g).

    The same integral as ``wear_curves.wear_areas_mm2`` (trapezoid rule, intervals with a NaN
    end left out, the interval straddling the split cut there with w interpolated linearly),
    vectorised over leading dimensions. It is linear in w, which makes the interpolation of
    :func:`wear_curve_at_area` exact in area.
    """
    y = np.asarray(grid_y_mm, dtype=float)
    w = np.asarray(curves_mm, dtype=float)
    region_mask(y, split_y_mm, region)  # validates the region name
    k = int(np.searchsorted(y, split_y_mm, side="left"))
    seg = 0.5 * (w[..., 1:] + w[..., :-1]) * np.diff(y)
    seg = np.where(np.isfinite(seg), seg, 0.0)
    if k >= y.size:
        flange, tread = seg.sum(axis=-1), np.zeros(w.shape[:-1])
    elif k == 0:
        flange, tread = np.zeros(w.shape[:-1]), seg.sum(axis=-1)
    elif y[k] == split_y_mm:
        flange, tread = seg[..., :k].sum(axis=-1), seg[..., k:].sum(axis=-1)
    else:
        t = (split_y_mm - y[k - 1]) / (y[k] - y[k - 1])
        w_split = w[..., k - 1] + t * (w[..., k] - w[..., k - 1])
        left = 0.5 * (w[..., k - 1] + w_split) * (split_y_mm - y[k - 1])
        right = 0.5 * (w_split + w[..., k]) * (y[k] - split_y_mm)
        flange = seg[..., : k - 1].sum(axis=-1) + np.where(np.isfinite(left), left, 0.0)
        tread = seg[..., k:].sum(axis=-1) + np.where(np.isfinite(right), right, 0.0)
    return flange if region == "flange" else tread


@dataclass(frozen=True)
class RegionStates:
    """Wear states of one region, ordered by area.

    Attributes
    ----------
    region : 'flange' or 'tread'
    areas_mm2 : (m,) state areas [mm²], strictly increasing
    curves_mm : (m, g) state wear curves on the whole grid [mm] (mean of the grouped
        measured curves); only the region's part (and the split interval) is used
    counts : (m,) number of measured curves averaged into each state
    """

    region: str
    areas_mm2: np.ndarray
    curves_mm: np.ndarray
    counts: np.ndarray

    def to_dict(self) -> dict[str, Any]:
        return {
            "region": self.region,
            "areas_mm2": self.areas_mm2.tolist(),
            "curves_mm": self.curves_mm.tolist(),
            "counts": self.counts.tolist(),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], n_grid: int) -> RegionStates:
        curves = np.asarray(data["curves_mm"], dtype=float).reshape(-1, n_grid)
        return cls(
            region=str(data["region"]),
            areas_mm2=np.asarray(data["areas_mm2"], dtype=float),
            curves_mm=curves,
            counts=np.asarray(data["counts"], dtype=int),
        )


@dataclass(frozen=True)
class WearStates:
    """Flange and tread wear states on a common lateral grid."""

    grid_y_mm: np.ndarray
    split_y_mm: float
    flange: RegionStates
    tread: RegionStates

    def region(self, region: str) -> RegionStates:
        if region == "flange":
            return self.flange
        if region == "tread":
            return self.tread
        raise ValueError(f"region: must be 'flange' or 'tread', got {region!r}")

    def to_dict(self) -> dict[str, Any]:
        return {
            "grid_y_mm": self.grid_y_mm.tolist(),
            "split_y_mm": self.split_y_mm,
            "flange": self.flange.to_dict(),
            "tread": self.tread.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> WearStates:
        grid = np.asarray(data["grid_y_mm"], dtype=float)
        return cls(
            grid_y_mm=grid,
            split_y_mm=float(data["split_y_mm"]),
            flange=RegionStates.from_dict(data["flange"], grid.size),
            tread=RegionStates.from_dict(data["tread"], grid.size),
        )


def _group_states(y: np.ndarray, curves: np.ndarray, areas: np.ndarray, mask: np.ndarray,
                  split: float, region: str, n_states: int | None, min_group_size: int,
                  max_states: int, outlier_sigmas: float) -> RegionStates:
    g = y.size
    valid = np.isfinite(areas) & (areas > 0) & np.any(np.isfinite(curves[:, mask]), axis=1)
    idx = np.flatnonzero(valid)
    if idx.size == 0:
        return RegionStates(region, np.zeros(0), np.zeros((0, g)), np.zeros(0, dtype=int))
    order = idx[np.argsort(areas[idx], kind="stable")]
    if n_states is None:
        n_states = max(1, min(max_states, order.size // max(1, min_group_size)))
    n_states = max(1, min(int(n_states), order.size))
    dy = np.gradient(y[mask]) if mask.sum() > 1 else np.ones(mask.sum())
    state_curves, counts = [], []
    for group in np.array_split(order, n_states):
        w = curves[group]
        shape = np.nan_to_num(w[:, mask]) / areas[group, None]
        median = np.median(shape, axis=0)
        dist = np.sum(np.abs(shape - median) * dy, axis=1)
        centre = np.median(dist)
        mad = 1.482602218505602 * np.median(np.abs(dist - centre))
        keep = dist <= centre + outlier_sigmas * mad if mad > 0 else np.ones(dist.size, bool)
        if keep.sum() < max(1, dist.size // 2):  # never reject more than half a group
            keep = dist <= np.quantile(dist, 0.5)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            mean = np.nanmean(w[keep], axis=0) if np.isnan(w).any() else w[keep].mean(axis=0)
        state_curves.append(np.nan_to_num(mean))  # no data anywhere in the group: no wear
        counts.append(int(keep.sum()))
    c = np.asarray(state_curves)
    a = region_area_mm2(y, c, split, region)
    n = np.asarray(counts)
    # merge states whose areas do not increase strictly (possible after rejection)
    keep_c, keep_a, keep_n = [c[0]], [a[0]], [n[0]]
    for ci, ai, ni in zip(c[1:], a[1:], n[1:], strict=True):
        if ai <= keep_a[-1] * (1 + 1e-9):
            tot = keep_n[-1] + ni
            keep_c[-1] = (keep_c[-1] * keep_n[-1] + ci * ni) / tot
            keep_a[-1] = float(region_area_mm2(y, keep_c[-1], split, region))
            keep_n[-1] = tot
        else:
            keep_c.append(ci)
            keep_a.append(ai)
            keep_n.append(ni)
    good = np.asarray(keep_a) > 0
    return RegionStates(
        region=region,
        areas_mm2=np.asarray(keep_a)[good],
        curves_mm=np.asarray(keep_c)[good],
        counts=np.asarray(keep_n, dtype=int)[good],
    )


def build_wear_states(
    grid_y_mm: ArrayLike,
    wear_curves_mm: ArrayLike,
    flange_areas_mm2: ArrayLike,
    tread_areas_mm2: ArrayLike,
    *,
    split_y_mm: float = -30.0,
    n_states: int | None = None,
    min_group_size: int = 5,
    max_states: int = 12,
    outlier_sigmas: float = 3.0,
) -> WearStates:
    """Group measured wear curves into flange and tread wear states (seed 001 §2.1).

    Parameters
    ----------
    grid_y_mm : (g,) common lateral grid [mm], ascending
    wear_curves_mm : (n, g) wear curves w = z_ref - z_worn on the grid [mm]
    flange_areas_mm2, tread_areas_mm2 : (n,) measured wear areas per region [mm²], used to
        order and group the curves
    split_y_mm : flange/tread split [mm] (seed 001 §3.1: -30)
    n_states : states per region (default: one per ``min_group_size`` curves, at most
        ``max_states``)
    outlier_sigmas : shape-outlier threshold in robust sigmas of the L1 shape distance

    Returns
    -------
    WearStates, each region's states ordered by area; a region without positive-area curves
    has no states.
    """
    y = np.asarray(grid_y_mm, dtype=float)
    w = np.asarray(wear_curves_mm, dtype=float)
    if y.ndim != 1 or y.size < 2 or np.any(np.diff(y) <= 0):
        raise ValueError("grid_y_mm: must be a 1-D strictly ascending grid")
    if w.ndim != 2 or w.shape[1] != y.size:
        raise ValueError(f"wear_curves_mm: must have shape (n, {y.size}), got {w.shape}")
    states = {}
    for region, areas in (("flange", flange_areas_mm2), ("tread", tread_areas_mm2)):
        a = np.asarray(areas, dtype=float).ravel()
        if a.size != w.shape[0]:
            raise ValueError(f"{region}_areas_mm2: needs one area per wear curve")
        states[region] = _group_states(
            y, w, a, region_mask(y, split_y_mm, region), split_y_mm, region, n_states,
            min_group_size, max_states, outlier_sigmas,
        )
    return WearStates(grid_y_mm=y, split_y_mm=float(split_y_mm), **states)


def interpolation_weights(states: WearStates, region: str, areas_mm2: ArrayLike
                          ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Weights of a region's states in the wear curves for many areas.

    The curve for area A is ``weights @ states.region(region).curves_mm``: linear in area
    between the neighbouring states (the zero curve below the first state), and beyond the
    largest state that state scaled to A (flagged as extrapolated). Seed 001 §2.1.

    Parameters
    ----------
    states : the fitted wear states
    region : 'flange' or 'tread'
    areas_mm2 : (n,) wanted wear areas [mm²], finite and >= 0

    Returns
    -------
    (weights (n, m) over the region's m states [-], extrapolated (n,) bool)
    """
    rs = states.region(region)
    flat = np.asarray(areas_mm2, dtype=float).ravel()
    if np.any(~np.isfinite(flat)) or np.any(flat < 0):
        raise ValueError("area_mm2: must be finite and >= 0")
    m = rs.areas_mm2.size
    if m == 0:
        return np.zeros((flat.size, 0)), flat > 0
    knots = np.concatenate([[0.0], rs.areas_mm2])
    i = np.clip(np.searchsorted(knots, flat, side="right") - 1, 0, m - 1)
    t = (flat - knots[i]) / (knots[i + 1] - knots[i])
    extrapolated = flat > rs.areas_mm2[-1] * (1 + 1e-12)
    t = np.where(extrapolated, 0.0, t)
    # columns over [zero curve, state 1 ... state m]: two non-zeros per row
    rows = np.arange(flat.size)
    weights = np.zeros((flat.size, m + 1))
    weights[rows, i] = 1.0 - t
    weights[rows, i + 1] = t
    weights[extrapolated] = 0.0
    weights[extrapolated, m] = flat[extrapolated] / rs.areas_mm2[-1]
    return weights[:, 1:], extrapolated


def wear_curves_at_areas(states: WearStates, region: str, areas_mm2: ArrayLike
                         ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Wear curves of one region for many areas (vectorised :func:`wear_curve_at_area`).

    Returns (curves (..., g) [mm], extrapolated (...) bool).
    """
    rs = states.region(region)
    a = np.asarray(areas_mm2, dtype=float)
    weights, extrapolated = interpolation_weights(states, region, a)
    g = states.grid_y_mm.size
    out = weights @ rs.curves_mm if weights.shape[1] else np.zeros((weights.shape[0], g))
    return out.reshape(*a.shape, g), extrapolated.reshape(a.shape)


def wear_curve_at_area(states: WearStates, region: str, area_mm2: float
                       ) -> tuple[NDArray[np.float64], bool]:
    """Wear curve of a region with the given wear area (seed 001 §2.1, Fig. 9).

    Parameters
    ----------
    states : the fitted wear states
    region : 'flange' or 'tread'
    area_mm2 : wanted wear area [mm²] (>= 0); 0 gives the zero curve

    Returns
    -------
    (curve (g,) [mm] on the whole grid, of which the region's part is meant, extrapolated):
    the curve interpolates linearly
    between the neighbouring states, so its area (:func:`region_area_mm2`) equals
    ``area_mm2``; beyond the largest state the largest state's shape is scaled to the area and
    ``extrapolated`` is True.
    """
    curves, flags = wear_curves_at_areas(states, region, np.asarray([area_mm2], dtype=float))
    return curves[0], bool(flags[0])


def join_regions(grid_y_mm: ArrayLike, flange_curves_mm: ArrayLike, tread_curves_mm: ArrayLike,
                 split_y_mm: float, window_mm: float = 4.0) -> NDArray[np.float64]:
    """Join flange and tread wear curves into one curve, smoothed across the split.

    Parameters
    ----------
    grid_y_mm : (g,) lateral grid [mm] (uniform spacing assumed for the moving average)
    flange_curves_mm, tread_curves_mm : (..., g) curves whose flange (y < split) and tread
        (y >= split) parts are used
    split_y_mm : flange/tread split [mm]
    window_mm : width of the moving average [mm]; only points within half a window of the
        split are replaced (0 disables smoothing)

    Returns
    -------
    (..., g) joined wear curve [mm]. Seed 001 §2.4: "the transition zone from the flange to
    the tread is smoothed out by using a moving average algorithm".
    """
    y = np.asarray(grid_y_mm, dtype=float)
    flange = np.asarray(flange_curves_mm, dtype=float)
    tread = np.asarray(tread_curves_mm, dtype=float)
    joined = np.where(y < split_y_mm, flange, tread)
    if window_mm <= 0 or y.size < 3:
        return joined
    step = float(np.median(np.diff(y)))
    n = max(1, int(round(window_mm / step)))
    if n % 2 == 0:
        n += 1
    if n < 3:
        return joined
    near = np.flatnonzero(np.abs(y - split_y_mm) <= 0.5 * window_mm)
    if near.size == 0:
        return joined
    # the moving average is only needed at the points near the split: filter the columns
    # their windows cover (at the grid's ends 'nearest' padding applies as on the whole grid)
    lo, hi = max(0, int(near[0]) - n // 2), min(y.size, int(near[-1]) + n // 2 + 1)
    smoothed = uniform_filter1d(joined[..., lo:hi], size=n, axis=-1, mode="nearest")
    joined[..., near] = smoothed[..., near - lo]
    return joined
