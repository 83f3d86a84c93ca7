"""The hybrid wear model of seed 001 and its calibration.

* Calibration (eq. 3): k_m = c_s P_m. With calibration wheels that see different P_j (other
  bogie types, axles, sides or routes) we fit the through-origin slope of wear area against
  P_j s_j over all calibration measurements (the same robust fan-shaped fit as the wear rate,
  :mod:`wearcast.statistics.wear_rates`); when all P_j are equal to P_m this slope is exactly
  k_m / P_m. The relative standard error and spread of that slope are kept as the relative
  uncertainty of c_s. P is the weighted wear measure of a route (eq. 2,
  :mod:`wearcast.statistics.route_measure`).
* Prediction (eq. 4) is :mod:`wearcast.statistics.hybrid_prediction`; worn profiles and
  Sd/Sh/qR at given areas are :mod:`wearcast.statistics.hybrid_profiles`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vocabulary import REGIONS, RUNNING_MODES, WEAR_MEASURES
from wearcast.statistics import hybrid_profiles
from wearcast.statistics.frames import check_frame
from wearcast.statistics.hybrid_profiles import (
    ParameterKernel,
    ParameterSurface,
)
from wearcast.statistics.route_measure import (
    UnknownBogieTypeError,
    check_choice,
    weighted_wear_measure,
)
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM, DEFAULT_SPLIT_Y_MM
from wearcast.statistics.wear_rates import WearRate, fit_ratio, fit_wear_rate, predictive_std
from wearcast.statistics.wear_states import (
    WearStates,
    build_wear_states,
    join_regions,
)
from wearcast.statistics.wear_tables import WearTable, compile_wear_table

QUANTILES = (0.1, 0.5, 0.9)
MEASUREMENT_COLUMNS = (
    "wheel_id", "bogie_type", "axle", "side", "mileage_km", "route",
    "flange_area_mm2", "tread_area_mm2",
)


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
        """Relative std of a single wheel's rate [-] (:func:`.wear_rates.predictive_std`)."""
        return predictive_std(self.c_s_rel_spread, self.c_s_rel_std_error)

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
        check_choice(region, REGIONS, "region")
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
        prefix = np.flatnonzero(y <= hybrid_profiles.PARAMETER_MAX_Y_MM)
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
    check_choice(measure, WEAR_MEASURES, "measure")
    check_choice(running_mode, RUNNING_MODES, "running_mode")
    check_frame(measurements, [c for c in MEASUREMENT_COLUMNS
                               if c != "route" or not isinstance(route_by_wheel, Route)],
                field="measurements", what="measurements")
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
