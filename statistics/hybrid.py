"""The hybrid wear model of seed 001: route weighting, calibration and prediction.

* Weighted wear measure of a route (seed 001 eq. 2): P = sum_i c_i P_i, c_i the route share
  of curve class i, P_i the curve-radius table value for the wheel's bogie type, wheelset
  position, rail and region (:mod:`wearcast.statistics.route_measure`).
* Calibration (eq. 3): k_m = c_s P_m. With calibration wheels that see different P_j (other
  bogie types, axles, sides or routes) we fit the through-origin slope of wear area against
  P_j s_j over all calibration measurements (the same robust fan-shaped fit as the wear rate,
  :mod:`wearcast.statistics.wear_rates`); when all P_j are equal to P_m this slope is exactly
  k_m / P_m. The relative standard error and spread of that slope are kept as the relative
  uncertainty of c_s.
* Prediction (eq. 4): k_s = c_s P_s per region, A(s) = A_0 + k_s s, wear curves from the
  wear states, flange and tread joined with a moving average (§2.4), worn profile
  z = z_ref - w, and Sd/Sh/qR per mileage.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vocabulary import REGIONS, RUNNING_MODES, WEAR_MEASURES
from wearcast.statistics.profile_parameters import (
    BACK_FACE_Y_MM,
    BatchGrid,
    flange_parameters_batch,
)
from wearcast.statistics.route_measure import UnknownBogieTypeError, weighted_wear_measure
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM, DEFAULT_SPLIT_Y_MM
from wearcast.statistics.wear_rates import WearRate, fit_ratio, fit_wear_rate, normal_quantile
from wearcast.statistics.wear_states import (
    WearStates,
    build_wear_states,
    interpolation_weights,
    join_regions,
)
from wearcast.statistics.wear_tables import WearTable, compile_wear_table

#: Profiles for Sd/Sh/qR alone are built up to this y [mm] (flange tip, face and the Sd and
#: qR points of any plausibly worn flange) plus the tape circle; see ``parameters_at_areas``.
PARAMETER_MAX_Y_MM = -10.0
QUANTILES = (0.1, 0.5, 0.9)
MEASUREMENT_COLUMNS = (
    "wheel_id", "bogie_type", "axle", "side", "mileage_km", "route",
    "flange_area_mm2", "tread_area_mm2",
)


def _check_choice(value: Any, allowed: Sequence[Any], name: str) -> None:
    if value not in allowed:
        raise ValueError(f"{name}: must be one of {tuple(allowed)}, got {value!r}")


@dataclass(frozen=True)
class RegionCalibration:
    """Calibration of one region (seed 001 eq. 3).

    Attributes
    ----------
    c_s : calibration factor [mm²/(km · measure unit)]
    c_s_rel_std_error : relative standard error of c_s [-]
    c_s_rel_spread : relative spread of individual measurements' c_s [-]
    p_m : mean weighted wear measure of the calibration measurements
    rate : the calibration fleet's wear rate k_m (area over mileage)
    """

    c_s: float
    c_s_rel_std_error: float
    c_s_rel_spread: float
    p_m: float
    rate: WearRate

    @property
    def c_s_rel_predictive(self) -> float:
        """Relative std of a single wheel's rate: hypot(rel. spread, rel. std error)."""
        return math.hypot(self.c_s_rel_std_error, self.c_s_rel_spread)

    def to_dict(self) -> dict[str, Any]:
        return {
            "c_s": self.c_s,
            "c_s_rel_std_error": self.c_s_rel_std_error,
            "c_s_rel_spread": self.c_s_rel_spread,
            "p_m": self.p_m,
            "rate": self.rate.to_dict(),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RegionCalibration:
        return cls(
            c_s=float(data["c_s"]),
            c_s_rel_std_error=float(data["c_s_rel_std_error"]),
            c_s_rel_spread=float(data["c_s_rel_spread"]),
            p_m=float(data["p_m"]),
            rate=WearRate.from_dict(data["rate"]),
        )


@dataclass(frozen=True)
class HybridModel:
    """A calibrated hybrid model: wear states plus per-region calibration factors."""

    measure: str
    running_mode: str
    states: WearStates
    flange: RegionCalibration
    tread: RegionCalibration
    bogie_types: tuple[str, ...]
    join_window_mm: float = 4.0
    reference_profile: str = "S1002"

    def region(self, region: str) -> RegionCalibration:
        _check_choice(region, REGIONS, "region")
        return self.flange if region == "flange" else self.tread

    @property
    def grid_y_mm(self) -> np.ndarray:
        return self.states.grid_y_mm

    @property
    def split_y_mm(self) -> float:
        return self.states.split_y_mm

    @cached_property
    def reference_z_mm(self) -> np.ndarray:
        """The reference (new) profile z_ref on the model's grid [mm], computed once."""
        z = s1002_height_mm(self.grid_y_mm)
        z.setflags(write=False)
        return z

    @cached_property
    def joined_state_curves_mm(self) -> tuple[np.ndarray, np.ndarray]:
        """Each region's state curves after joining (seed 001 §2.4), computed once [mm].

        Joining (region masks, then the moving average across the split) is linear in the
        flange and tread curves, so the joined wear curve for any areas is
        ``W_flange @ J_flange + W_tread @ J_tread`` with the states' interpolation weights
        W (:func:`wear_states.interpolation_weights`) and these (m, g) arrays J.
        """
        g = self.grid_y_mm.size
        out = []
        for region in REGIONS:
            curves = self.states.region(region).curves_mm.reshape(-1, g)
            zero = np.zeros_like(curves)
            pair = (curves, zero) if region == "flange" else (zero, curves)
            joined = join_regions(self.grid_y_mm, pair[0], pair[1], self.split_y_mm,
                                  self.join_window_mm)
            joined.setflags(write=False)
            out.append(joined)
        return out[0], out[1]

    @cached_property
    def parameter_columns(self) -> np.ndarray:
        """Grid indices that Sd/Sh/qR of the model's profiles normally depend on.

        The contiguous part y <= PARAMETER_MAX_Y_MM (flange tip, flange face, Sd and qR
        points) and the two points around the tape circle y = 0;
        :func:`parameters_at_areas` checks every result and recomputes a profile on the
        whole grid when its flank points are not inside that part.
        """
        y = self.grid_y_mm
        prefix = np.flatnonzero(y <= PARAMETER_MAX_Y_MM)
        j = int(np.searchsorted(y, 0.0, side="right")) - 1
        tape = [c for c in (j, j + 1) if prefix.size and prefix[-1] < c < y.size]
        cols = np.concatenate([prefix, np.asarray(tape, dtype=int)]).astype(int)
        cols.setflags(write=False)
        return cols

    @cached_property
    def parameter_kernel(self) -> ParameterKernel:
        """What :func:`parameters_at_areas` needs on :attr:`parameter_columns`, computed
        once per model: the joined state curves there, the reference heights and grid."""
        return ParameterKernel.build(self)

    @cached_property
    def parameter_surface(self) -> ParameterSurface:
        """Sd/Sh/qR on a grid of (flange, tread) areas, computed once per model, for a
        cheap bilinear first guess of where a wear path crosses a limit
        (:class:`ParameterSurface`)."""
        return ParameterSurface.build(self)

    def to_dict(self) -> dict[str, Any]:
        return {
            "measure": self.measure,
            "running_mode": self.running_mode,
            "states": self.states.to_dict(),
            "flange": self.flange.to_dict(),
            "tread": self.tread.to_dict(),
            "bogie_types": list(self.bogie_types),
            "join_window_mm": self.join_window_mm,
            "reference_profile": self.reference_profile,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> HybridModel:
        return cls(
            measure=str(data["measure"]),
            running_mode=str(data["running_mode"]),
            states=WearStates.from_dict(data["states"]),
            flange=RegionCalibration.from_dict(data["flange"]),
            tread=RegionCalibration.from_dict(data["tread"]),
            bogie_types=tuple(data["bogie_types"]),
            join_window_mm=float(data.get("join_window_mm", 4.0)),
            reference_profile=str(data.get("reference_profile", "S1002")),
        )


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
    heights there [mm], the columns' grid for the batched Sd/Sh/qR and the last lateral
    position [mm] at which a flank point found on the columns is the whole grid's."""

    flange: StateInterpolant
    tread: StateInterpolant
    y_mm: NDArray
    reference_z_mm: NDArray
    y_safe_mm: float
    grid: BatchGrid | None
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
        return cls(regions[0], regions[1], y, ref, y_safe, BatchGrid.build(y), ref_minus)

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


def _route_lookup(route_by_wheel: Route | Mapping[Any, Route], row_route: Any,
                  wheel_id: Any) -> Route:
    if isinstance(route_by_wheel, Route):
        return route_by_wheel
    if row_route is not None and row_route in route_by_wheel:
        return route_by_wheel[row_route]
    if wheel_id in route_by_wheel:
        return route_by_wheel[wheel_id]
    raise ValueError(f"route: no route given for wheel {wheel_id!r} (route {row_route!r})")


def calibrate(
    measurements: pd.DataFrame,
    route_by_wheel: Route | Mapping[Any, Route],
    table: pd.DataFrame | WearTable,
    *,
    wear_curves_mm: ArrayLike,
    measure: str,
    running_mode: str,
    grid_y_mm: ArrayLike = DEFAULT_GRID_Y_MM,
    split_y_mm: float = DEFAULT_SPLIT_Y_MM,
    n_states: int | None = None,
    join_window_mm: float = 4.0,
) -> HybridModel:
    """Calibrate the hybrid model on measured wheels with known routes (seed 001 §2.3).

    Parameters
    ----------
    measurements : one row per measurement with columns ``wheel_id, bogie_type, axle (1|2),
        side (left|right), mileage_km`` [km since reprofiling], ``route`` (route name; may be
        absent when ``route_by_wheel`` is one Route), ``flange_area_mm2, tread_area_mm2``
    route_by_wheel : one Route for all, or a mapping from route name (the ``route`` column)
        or else from ``wheel_id`` to Route
    table : curve-radius table
    wear_curves_mm : (n, g) wear curves of the measurements on ``grid_y_mm`` [mm]
    measure : 'tau_max' or 't_gamma'
    running_mode : 'lead' or 'mixed'
    grid_y_mm, split_y_mm : common lateral grid and flange/tread split [mm]

    Returns
    -------
    HybridModel with wear states, per-region wear rate k_m, mean P_m and c_s (module
    docstring: the through-origin slope of area on P_j s_j, = k_m / P_m for equal P_j).
    """
    _check_choice(measure, WEAR_MEASURES, "measure")
    _check_choice(running_mode, RUNNING_MODES, "running_mode")
    if not isinstance(measurements, pd.DataFrame):
        raise ValueError("measurements: must be a pandas DataFrame")
    need = [c for c in MEASUREMENT_COLUMNS if c not in measurements.columns]
    if "route" in need and isinstance(route_by_wheel, Route):
        need.remove("route")
    if need:
        raise ValueError(f"{need[0]}: column missing from measurements")
    if measurements.empty:
        raise ValueError("measurements: no rows")
    wt = compile_wear_table(table)
    if measure not in wt.measures:
        raise ValueError(f"measure: the wear table has no {measure!r} rows")
    df = measurements.reset_index(drop=True)
    mileage = pd.to_numeric(df["mileage_km"], errors="coerce").to_numpy(dtype=float)
    if not np.all(np.isfinite(mileage)) or np.any(mileage < 0):
        raise ValueError("mileage_km: must be finite and >= 0")
    curves = np.asarray(wear_curves_mm, dtype=float)
    grid = np.asarray(grid_y_mm, dtype=float)
    if curves.shape != (len(df), grid.size):
        raise ValueError(
            f"wear_curves_mm: must have shape ({len(df)}, {grid.size}), got {curves.shape}"
        )
    areas = {
        r: pd.to_numeric(df[f"{r}_area_mm2"], errors="coerce").to_numpy(dtype=float)
        for r in REGIONS
    }
    for r, a in areas.items():
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{r}_area_mm2: must be finite")
    axles = pd.to_numeric(df["axle"], errors="coerce")
    routes_col = df["route"] if "route" in df.columns else pd.Series([None] * len(df))
    # P_j for every distinct wheel position, not per row
    keys = list(zip(routes_col, df["wheel_id"], df["bogie_type"].astype(str), axles,
                    df["side"], strict=True))
    cache: dict[tuple[Any, ...], dict[str, float]] = {}
    p = {r: np.empty(len(df)) for r in REGIONS}
    for j, (route_name, wheel_id, bogie, axle, side) in enumerate(keys):
        route = _route_lookup(route_by_wheel, route_name, wheel_id)
        key = (route, bogie, axle, side)
        if key not in cache:
            if bogie not in wt.bogie_types:
                raise UnknownBogieTypeError(
                    f"bogie_type: {bogie!r} (row {j}) is not in the wear table"
                )
            cache[key] = {
                r: weighted_wear_measure(
                    route, wt, bogie_type=bogie, axle=int(axle) if axle in (1, 2) else axle,
                    side=side, running_mode=running_mode, region=r, measure=measure,
                )
                for r in REGIONS
            }
        for r in REGIONS:
            p[r][j] = cache[key][r]
    regions = {}
    for r in REGIONS:
        informative = (mileage > 0) & (p[r] > 0)
        if informative.sum() < 2:
            raise ValueError(
                f"{r}: need at least 2 measurements with mileage > 0 on routes where the "
                f"weighted wear measure P_m > 0 to calibrate c_s"
            )
        fit = fit_ratio(p[r] * mileage, areas[r])
        rate = fit_wear_rate(mileage, areas[r])
        scale = abs(fit.slope) if fit.slope != 0 else 1.0
        regions[r] = RegionCalibration(
            c_s=fit.slope,
            c_s_rel_std_error=fit.std_error / scale,
            c_s_rel_spread=fit.spread / scale,
            p_m=float(np.mean(p[r][informative])),
            rate=rate,
        )
    states = build_wear_states(
        grid, curves, areas["flange"], areas["tread"], split_y_mm=split_y_mm, n_states=n_states
    )
    return HybridModel(
        measure=measure,
        running_mode=running_mode,
        states=states,
        flange=regions["flange"],
        tread=regions["tread"],
        bogie_types=wt.bogie_types,
        join_window_mm=join_window_mm,
    )


def _nan_to_none(values: np.ndarray) -> list[float | None]:
    return [float(v) if math.isfinite(v) else None for v in np.asarray(values, dtype=float)]


@dataclass(frozen=True)
class Prediction:
    """Prediction for one wheel on one route (seed 001 §2.4).

    Arrays over mileage have length M; ``*_area_mm2`` and ``*_rate_mm2_per_km`` carry the
    quantiles in ``quantiles`` (default P10/P50/P90) along their first axis. Curves, profile
    and parameters are those of the median (P50) areas.
    """

    mileage_km: np.ndarray
    quantiles: tuple[float, ...]
    weighted_measure: dict[str, float]
    flange_rate_mm2_per_km: np.ndarray
    tread_rate_mm2_per_km: np.ndarray
    flange_area_mm2: np.ndarray
    tread_area_mm2: np.ndarray
    grid_y_mm: np.ndarray
    wear_mm: np.ndarray
    z_mm: np.ndarray
    sd_mm: np.ndarray
    sh_mm: np.ndarray
    qr_mm: np.ndarray
    extrapolated: np.ndarray
    start_areas_mm2: dict[str, float] = field(default_factory=dict)

    @property
    def any_extrapolated(self) -> bool:
        return bool(np.any(self.extrapolated))

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "mileage_km": self.mileage_km.tolist(),
            "quantiles": list(self.quantiles),
            "weighted_measure": dict(self.weighted_measure),
            "flange_rate_mm2_per_km": self.flange_rate_mm2_per_km.tolist(),
            "tread_rate_mm2_per_km": self.tread_rate_mm2_per_km.tolist(),
            "flange_area_mm2": self.flange_area_mm2.tolist(),
            "tread_area_mm2": self.tread_area_mm2.tolist(),
            "grid_y_mm": self.grid_y_mm.tolist(),
            "wear_mm": self.wear_mm.tolist(),
            "z_mm": self.z_mm.tolist(),
            "sd_mm": _nan_to_none(self.sd_mm),
            "sh_mm": _nan_to_none(self.sh_mm),
            "qr_mm": _nan_to_none(self.qr_mm),
            "extrapolated": self.extrapolated.tolist(),
            "start_areas_mm2": dict(self.start_areas_mm2),
        }
        return out


def region_rates(model: HybridModel, route: Route, table: pd.DataFrame | WearTable, *,
                 bogie_type: str, axle: int, side: str,
                 quantiles: Sequence[float] = QUANTILES,
                 weighted_measures: Mapping[str, float] | None = None,
                 ) -> tuple[dict[str, float], dict[str, NDArray]]:
    """Weighted measures P_s and rate quantiles k_s,q = c_s P_s (1 + z_q u) per region.

    u is the relative predictive uncertainty of c_s (standard error and spread of the
    calibration); rates are clipped at 0. Seed 001 eq. 4. ``weighted_measures`` gives P_s
    per region when the caller has it already (:func:`model_weighted_measures` of the same
    model, route, table and wheel position); otherwise it is computed.
    """
    if bogie_type not in model.bogie_types:
        raise UnknownBogieTypeError(
            f"bogie_type: the model covers {model.bogie_types}, not {bogie_type!r}"
        )
    if weighted_measures is None:
        weighted_measures = model_weighted_measures(model, route, table, bogie_type=bogie_type,
                                                    axle=axle, side=side)
    z = normal_quantile(np.asarray(quantiles, dtype=float))
    p_s: dict[str, float] = {}
    rates: dict[str, NDArray] = {}
    for r in REGIONS:
        cal = model.region(r)
        p_s[r] = float(weighted_measures[r])
        k = cal.c_s * p_s[r]
        rates[r] = np.maximum(0.0, k * (1.0 + z * cal.c_s_rel_predictive))
    return p_s, rates


def model_weighted_measures(model: HybridModel, route: Route,
                            table: pd.DataFrame | WearTable, *, bogie_type: str, axle: int,
                            side: str) -> dict[str, float]:
    """P_s per region (seed 001 eq. 2) with the model's running mode and wear measure."""
    return {
        r: weighted_wear_measure(route, table, bogie_type=bogie_type, axle=axle, side=side,
                                 running_mode=model.running_mode, region=r,
                                 measure=model.measure)
        for r in REGIONS
    }


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
    if kernel.grid is not None and np.isfinite(z).all():
        params = kernel.grid.parameters(z)
    else:
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


def predict(
    model: HybridModel,
    route: Route,
    table: pd.DataFrame | WearTable,
    *,
    bogie_type: str,
    axle: int,
    side: str,
    mileage_km: ArrayLike,
    start_areas_mm2: Mapping[str, float] | None = None,
    quantiles: Sequence[float] = QUANTILES,
    weighted_measures: Mapping[str, float] | None = None,
) -> Prediction:
    """Predict wear areas, wear curve, worn profile and Sd/Sh/qR of a wheel on a route.

    Parameters
    ----------
    model : calibrated hybrid model
    route : the route to predict for (its classes must lie within the table's radii)
    table : curve-radius table with the model's measure (compile it once for speed)
    bogie_type, axle (1|2), side ('left'|'right') : the wheel's position
    mileage_km : (M,) mileages [km] from the start state
    start_areas_mm2 : measured areas {'flange': ..., 'tread': ...} [mm²] of the start state
        (default: new profile, 0)
    quantiles : area quantiles to report (the curves use the median)
    weighted_measures : P_s per region if known already (see :func:`region_rates`)

    Returns
    -------
    Prediction. k_s = c_s P_s (seed 001 eq. 4), A(s) = A_0 + k_s s.
    """
    s = np.atleast_1d(np.asarray(mileage_km, dtype=float))
    if s.ndim != 1 or np.any(~np.isfinite(s)) or np.any(s < 0):
        raise ValueError("mileage_km: must be a list of finite mileages >= 0")
    q = tuple(float(v) for v in quantiles)
    if 0.5 not in q:
        raise ValueError("quantiles: must include 0.5 (the median drives the wear curves)")
    start: dict[str, float] = {r: 0.0 for r in REGIONS}
    if start_areas_mm2:
        for r, v in start_areas_mm2.items():
            _check_choice(r, REGIONS, "start_areas_mm2")
            if not math.isfinite(float(v)) or float(v) < 0:
                raise ValueError(f"start_areas_mm2.{r}: must be finite and >= 0")
            start[r] = float(v)
    p_s, rates = region_rates(model, route, table, bogie_type=bogie_type, axle=axle, side=side,
                              quantiles=q, weighted_measures=weighted_measures)
    areas = {r: start[r] + rates[r][:, None] * s[None, :] for r in REGIONS}
    median = q.index(0.5)
    wear, z, params, extrapolated = profile_at_areas(
        model, areas["flange"][median], areas["tread"][median]
    )
    return Prediction(
        mileage_km=s,
        quantiles=q,
        weighted_measure=p_s,
        flange_rate_mm2_per_km=rates["flange"],
        tread_rate_mm2_per_km=rates["tread"],
        flange_area_mm2=areas["flange"],
        tread_area_mm2=areas["tread"],
        grid_y_mm=model.grid_y_mm,
        wear_mm=wear,
        z_mm=z,
        sd_mm=params[:, 0],
        sh_mm=params[:, 1],
        qr_mm=params[:, 2],
        extrapolated=extrapolated,
        start_areas_mm2=start,
    )
