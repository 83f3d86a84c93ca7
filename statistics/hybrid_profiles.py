"""Worn profiles and Sd/Sh/qR of a hybrid model (seed 001 §2.4) at given region wear areas:
wear curves from the wear states, flange and tread joined with a moving average, worn profile
z = z_ref - w, and the per-model kernels and surfaces that make Sd/Sh/qR fast to evaluate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics.profile_parameters import (
    BACK_FACE_Y_MM,
    flange_parameters_batch,
)
from wearcast.statistics.wear_states import interpolation_weights

if TYPE_CHECKING:
    from wearcast.statistics.hybrid import HybridModel


#: Profiles for Sd/Sh/qR alone are built up to this y [mm] (flange tip, face and the Sd and
#: qR points of any plausibly worn flange) plus the tape circle; see ``parameters_at_areas``.
PARAMETER_MAX_Y_MM = -10.0


@dataclass(frozen=True)
class StateInterpolant:
    """One region's joined state curves as line pieces in the area: the curve for area A
    [mm²] in piece i is ``offset_mm[i] + A · slope_mm[i]`` [mm], (m + 1, c). Piece i < m
    interpolates linearly between state i - 1 and i (state -1 the zero curve at area 0),
    piece m scales the last state beyond its area (as
    :func:`wear_states.interpolation_weights`). ``knots_mm2`` (m + 1,) holds 0 and the
    state areas."""

    knots_mm2: NDArray
    offset_mm: NDArray
    slope_mm: NDArray

    @classmethod
    def build(cls, knots_mm2: NDArray, curves_mm: NDArray) -> StateInterpolant:
        """From the state areas with 0 first (m + 1,) [mm²] and the curves with the zero
        curve first (m + 1, c) [mm]."""
        m = knots_mm2.size - 1
        slope = np.zeros_like(curves_mm)
        offset = np.zeros_like(curves_mm)
        if m > 0:
            dk = np.diff(knots_mm2)[:, None]
            slope[:m] = np.diff(curves_mm, axis=0) / dk
            offset[:m] = curves_mm[:m] - knots_mm2[:m, None] * slope[:m]
            slope[m] = curves_mm[m] / knots_mm2[m]
        for a in (knots_mm2, offset, slope):
            a.setflags(write=False)
        return cls(knots_mm2, offset, slope)

    def pieces(self, areas_mm2: NDArray) -> tuple[NDArray, NDArray]:
        """(piece index (n,), extrapolated (n,)) of areas (n,) [mm²]."""
        a = areas_mm2
        if not np.isfinite(a).all() or (a < 0).any():
            raise ValueError("area_mm2: must be finite and >= 0")
        knots = self.knots_mm2
        m = knots.size - 1
        extrapolated = a > knots[m] * (1 + 1e-12)
        i = np.minimum(np.searchsorted(knots, a, side="right") - 1, max(m - 1, 0))
        i[extrapolated] = m
        return i, extrapolated

    def __call__(self, areas_mm2: NDArray) -> tuple[NDArray, NDArray]:
        """(curves (n, c) [mm], extrapolated (n,)) for areas (n,) [mm²]."""
        i, extrapolated = self.pieces(areas_mm2)
        return self.offset_mm[i] + areas_mm2[:, None] * self.slope_mm[i], extrapolated


@dataclass(frozen=True)
class ParameterKernel:
    """Per-model constants of :func:`parameters_at_areas` (no request data): the state
    interpolants of both regions on :attr:`HybridModel.parameter_columns`, the reference
    heights there [mm] and the last lateral position [mm] at which a flank point found on
    the columns is the whole grid's."""

    flange: StateInterpolant
    tread: StateInterpolant
    y_mm: NDArray
    reference_z_mm: NDArray
    y_safe_mm: float
    #: reference minus the flange pieces' offsets, (m_f + 1, c) [mm]
    _ref_minus_flange_offset: NDArray = field(repr=False)

    @classmethod
    def build(cls, model: HybridModel) -> ParameterKernel:
        cols = model.parameter_columns
        y = model.grid_y_mm[cols]
        regions = []
        for region, joined in zip(REGIONS, model.joined_state_curves_mm, strict=True):
            rs = model.states.region(region)
            curves = np.vstack([np.zeros((1, cols.size)), joined[:, cols]])
            knots = np.concatenate([[0.0], rs.areas_mm2])
            regions.append(StateInterpolant.build(knots, curves))
        # the flank crossings use the grid point after the crossing: both points must lie
        # before the last two prefix points for the prefix to give the whole-grid result
        n_prefix = int(np.count_nonzero(y <= PARAMETER_MAX_Y_MM))
        y_safe = float(y[n_prefix - 2]) if n_prefix >= 2 else -math.inf
        ref = np.ascontiguousarray(model.reference_z_mm[cols])
        ref_minus = ref[None, :] - regions[0].offset_mm
        for a in (y, ref, ref_minus):
            a.setflags(write=False)
        return cls(regions[0], regions[1], y, ref, y_safe, ref_minus)

    def profiles(self, flange_area_mm2: NDArray, tread_area_mm2: NDArray
                 ) -> tuple[NDArray, NDArray]:
        """Worn profiles z = z_ref - w on the columns (M, c) [mm] and extrapolation flags
        (M,) for region areas (M,) [mm²]."""
        i_f, ef = self.flange.pieces(flange_area_mm2)
        i_t, et = self.tread.pieces(tread_area_mm2)
        z = self._ref_minus_flange_offset[i_f]
        z -= flange_area_mm2[:, None] * self.flange.slope_mm[i_f]
        z -= self.tread.offset_mm[i_t]
        z -= tread_area_mm2[:, None] * self.tread.slope_mm[i_t]
        return z, ef | et


#: Undefined parameters on the surface (Sd, Sh, qR) [mm]: far beyond any limit, so that
#: the interpolated margins count as crossed (an undefined parameter counts as crossed).
_SURFACE_UNDEFINED_MM = np.array([-1e3, 1e3, -1e3])


@dataclass(frozen=True)
class ParameterSurface:
    """Sd, Sh, qR [mm] of the worn profiles on a grid of region areas (no request data).

    The axes hold 0, every state area and ``n_points`` even steps up to ``extent`` times
    the last state area of the region [mm²]; ``params_mm`` (n_f, n_t, 3) are the exact
    :func:`parameters_at_areas` values at the nodes (undefined ones replaced by
    ``_SURFACE_UNDEFINED_MM``). With state areas on the axes every cell lies within one
    piece of both state interpolants, so the bilinear interpolant of :meth:`at` is close to
    the exact parameters; it is an estimate only, to be checked with the exact evaluation.
    """

    flange_mm2: NDArray
    tread_mm2: NDArray
    params_mm: NDArray
    #: per cell (flattened (i, j) -> i (n_t - 1) + j): c0, c1, c2, c3 (.., 4, 3) of the
    #: bilinear form c0 + u c1 + v (c2 + u c3), u and v the cell's local coordinates
    _cells: NDArray = field(repr=False)
    _inv_step_f: NDArray = field(repr=False)
    _inv_step_t: NDArray = field(repr=False)

    @classmethod
    def build(cls, model: HybridModel, n_points: int = 96, extent: float = 4.0
              ) -> ParameterSurface:
        axes = []
        for region in REGIONS:
            knots = np.concatenate([[0.0], model.states.region(region).areas_mm2])
            top = max(extent * float(knots[-1]), 1.0)
            axes.append(np.unique(np.concatenate([knots, np.linspace(0.0, top, n_points)])))
        fa, ta = np.meshgrid(axes[0], axes[1], indexing="ij")
        params, _ = parameters_at_areas(model, fa.ravel(), ta.ravel())
        params = np.where(np.isfinite(params), params, _SURFACE_UNDEFINED_MM)
        p = params.reshape(axes[0].size, axes[1].size, 3)
        p00, p01, p10, p11 = p[:-1, :-1], p[:-1, 1:], p[1:, :-1], p[1:, 1:]
        cells = np.stack([p00, p10 - p00, p01 - p00, p11 - p10 - p01 + p00], axis=2)
        cells = np.ascontiguousarray(cells.reshape(-1, 4, 3))
        inv = [1.0 / np.diff(ax) for ax in axes]
        for arr in (*axes, p, cells, *inv):
            arr.setflags(write=False)
        return cls(axes[0], axes[1], p, cells, inv[0], inv[1])

    def at(self, flange_area_mm2: NDArray, tread_area_mm2: NDArray
           ) -> tuple[NDArray, NDArray]:
        """Bilinearly interpolated Sd, Sh, qR (M, 3) [mm] and whether each point lies on
        the surface (M,) for areas (M,) [mm²] >= 0 (off it: extrapolated from the edge
        cell, not to be used)."""
        f_ax, t_ax = self.flange_mm2, self.tread_mm2
        i = np.searchsorted(f_ax, flange_area_mm2, side="right") - 1
        np.minimum(i, f_ax.size - 2, out=i)  # i >= 0: areas >= 0 = axis[0]
        j = np.searchsorted(t_ax, tread_area_mm2, side="right") - 1
        np.minimum(j, t_ax.size - 2, out=j)
        u = ((flange_area_mm2 - f_ax[i]) * self._inv_step_f[i])[:, None]
        v = ((tread_area_mm2 - t_ax[j]) * self._inv_step_t[j])[:, None]
        c = self._cells[i * (t_ax.size - 1) + j]
        params = c[:, 0] + u * c[:, 1] + v * (c[:, 2] + u * c[:, 3])
        return params, (flange_area_mm2 <= f_ax[-1]) & (tread_area_mm2 <= t_ax[-1])


def profile_at_areas(model: HybridModel, flange_area_mm2: ArrayLike, tread_area_mm2: ArrayLike
                     ) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Wear curves, worn profiles and Sd/Sh/qR for given region areas (vectorised over M).

    Returns (wear (M, g) [mm], z (M, g) [mm], params (M, 3) [mm] as Sd, Sh, qR,
    extrapolated (M,) bool).
    """
    wear, extrapolated = _joined_wear(model, flange_area_mm2, tread_area_mm2, None)
    z = model.reference_z_mm[None, :] - wear
    params = flange_parameters_batch(model.grid_y_mm, z).stacked()
    return wear, z, params, extrapolated


def _joined_wear(model: HybridModel, flange_area_mm2: ArrayLike, tread_area_mm2: ArrayLike,
                 columns: NDArray | None) -> tuple[NDArray, NDArray]:
    """Joined wear curves (M, g) [mm] (or only ``columns`` of them) and extrapolation flags
    for region areas (M,) [mm²]: state interpolation weights times the joined states."""
    fa = np.atleast_1d(np.asarray(flange_area_mm2, dtype=float))
    ta = np.atleast_1d(np.asarray(tread_area_mm2, dtype=float))
    wf, ef = interpolation_weights(model.states, "flange", fa)
    wt_, et = interpolation_weights(model.states, "tread", ta)
    jf, jt = model.joined_state_curves_mm
    if columns is not None:
        jf, jt = jf[:, columns], jt[:, columns]
    return wf @ jf + wt_ @ jt, ef | et


def parameters_at_areas(model: HybridModel, flange_area_mm2: ArrayLike,
                        tread_area_mm2: ArrayLike) -> tuple[NDArray, NDArray]:
    """Sd, Sh, qR (M, 3) [mm] and extrapolation flags (M,) of the worn profiles for region
    areas (M,) [mm²], without building the whole profiles.

    The same values as :func:`profile_at_areas`: the profiles are built on
    :attr:`HybridModel.parameter_columns` only; a profile whose Sd or qR point is not well
    inside them (or whose parameters are undefined there) is recomputed on the whole grid.
    """
    kernel = model.parameter_kernel
    fa = np.atleast_1d(np.asarray(flange_area_mm2, dtype=float)).ravel()
    ta = np.atleast_1d(np.asarray(tread_area_mm2, dtype=float)).ravel()
    z, extrapolated = kernel.profiles(fa, ta)
    params = flange_parameters_batch(kernel.y_mm, z).stacked()
    y_sd = params[:, 0] + BACK_FACE_Y_MM
    y_qr = y_sd - params[:, 2]
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(params).all(axis=1) & (y_sd < kernel.y_safe_mm) & \
            (y_qr < kernel.y_safe_mm)
    redo = np.flatnonzero(~ok)
    if redo.size:
        params[redo] = profile_at_areas(model, fa[redo], ta[redo])[2]
    return params, extrapolated
