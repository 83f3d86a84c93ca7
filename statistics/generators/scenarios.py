"""Calibrated scenarios on the synthetic generators, shared by the tests and the benchmarks.

A scenario is what a user of the discrepancy finder would have: a generated fleet's
measurements and wear curves, its routes and their attributes, the curve-radius table, and a
hybrid model calibrated on one unit's motor bogies (``tau_max``, ``mixed``) as a user would.
The finder itself (:func:`wearcast.statistics.discrepancy.diagnose`) is not imported here:
callers pass :meth:`Scenario.finder_arguments` to it.

* :func:`twin_scenario`: the fleet twin (:mod:`.fleet_twin` with :mod:`.twin_effects`),
  calibrated on unit A's motor bogies;
* :func:`alt_scenario`: :mod:`.fleet_twin_alt`, calibrated on unit U1's motor cars;
* :func:`depot_scenario`: :mod:`.depot`, calibrated on unit N1's motor bogies;
* :func:`measured_vehicle_series` and :func:`cached_vehicle_simulator`: vehicle-averaged FT/qR
  series "measured" from a whole-vehicle wear-loop run, for the physics diagnosis.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vehicle_wear_simulation import (
    VehicleWearOptions,
    VehicleWearSimulation,
    simulate_vehicle_wear,
)
from wearcast.physics.vocabulary import CurveClass
from wearcast.statistics import hybrid
from wearcast.statistics.discrepancy_progression import ExpectedProgression, SimulatedWheel
from wearcast.statistics.generators import depot as dp
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import fleet_twin_alt as fa
from wearcast.statistics.generators import fleet_twin_loop as fl
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.generators import twin_routes, twin_wear_table
from wearcast.statistics.routes import Route, RouteClass


@dataclass(frozen=True)
class Scenario:
    """A generated fleet and the model a user would calibrate on it.

    measurements : one row per (wheel, mileage) in the form ``hybrid.calibrate`` reads
    wear_curves_mm : (n, g) wear curves [mm] of those rows
    routes, route_attributes : route per name and its attributes (e.g. flange lubrication)
    table : the curve-radius table the model uses
    calibration : (n,) rows the model was calibrated on
    model : the calibrated hybrid model (``tau_max``, ``mixed``)
    fleet : the generator's own result (twin, alt or depot fleet)
    """

    measurements: pd.DataFrame
    wear_curves_mm: NDArray[np.float64]
    routes: Mapping[str, Route]
    route_attributes: Mapping[str, Mapping[str, Any]]
    table: pd.DataFrame
    calibration: NDArray[np.bool_]
    model: hybrid.HybridModel
    fleet: Any

    @property
    def calibration_wheel_ids(self) -> set[Any]:
        return set(self.measurements["wheel_id"][self.calibration])

    def finder_arguments(self) -> tuple[tuple[Any, ...], dict[str, Any]]:
        """Positional and keyword arguments of ``discrepancy.diagnose`` for this scenario."""
        return ((self.model, self.measurements, self.wear_curves_mm, self.routes, self.table),
                {"calibration_wheel_ids": self.calibration_wheel_ids,
                 "route_attributes": self.route_attributes})


def calibrated(measurements: pd.DataFrame, wear_curves_mm: NDArray[np.float64],
               routes: Mapping[str, Route], route_attributes: Mapping[str, Mapping[str, Any]],
               table: pd.DataFrame, calibration: NDArray[np.bool_], fleet: Any) -> Scenario:
    """The scenario with a model calibrated on the ``calibration`` rows (tau_max, mixed)."""
    model = hybrid.calibrate(measurements[calibration], routes, table,
                             wear_curves_mm=wear_curves_mm[calibration], measure="tau_max",
                             running_mode="mixed")
    return Scenario(measurements, wear_curves_mm, routes, route_attributes, table, calibration,
                    model, fleet)


def twin_scenario(wear_effects: Sequence[ft.WearEffect] = (),
                  profile_effects: Sequence[ft.ProfileEffect] = (), *, seed: int = 0,
                  table: pd.DataFrame | None = None, max_wheels: int | None = None,
                  **config: Any) -> Scenario:
    """The four-unit twin of ``twin_effects.scenario_config`` (``config`` passed on), its
    profiles processed, calibrated on unit A's motor bogies; ``max_wheels`` keeps the first
    wheels by id."""
    table = twin_wear_table.synthetic_wear_table() if table is None else table
    cfg = te.scenario_config(seed=seed, wear_effects=tuple(wear_effects),
                             profile_effects=tuple(profile_effects), **config)
    twin = ft.generate_fleet(cfg, table)
    df, curves = te.twin_measurements(twin)
    if max_wheels is not None:
        keep = df["wheel_id"].isin(sorted(df["wheel_id"].unique())[:max_wheels]).to_numpy()
        df, curves = df[keep].reset_index(drop=True), curves[keep]
    routes, attrs = te.scenario_routes(cfg)
    cal = (df["vehicle_id"].str.startswith("A") & (df["bogie_type"] == "motor")).to_numpy()
    return calibrated(df, curves, routes, attrs, table, cal, twin)


def alt_scenario(effects: fa.AltEffects, seed: int = 0) -> Scenario:
    """:mod:`.fleet_twin_alt` with ``effects``, calibrated on unit U1's motor cars."""
    fleet = fa.generate_alt_fleet(fa.AltConfig(effects=effects, seed=seed))
    df = fleet.measurements
    cal = (df["unit"].eq("U1") & df["bogie_type"].eq("motor")).to_numpy()
    return calibrated(df, fleet.wear_curves, fleet.routes, fleet.route_attributes, fleet.table,
                      cal, fleet)


def depot_scenario(effects: dp.DepotEffects, seed: int = 0) -> Scenario:
    """:mod:`.depot` with ``effects`` (profiles only for an instrument scale), calibrated on
    unit N1's motor bogies."""
    fleet = dp.generate_depot_fleet(dp.DepotConfig(
        effects=effects, seed=seed, profiles=effects.instrument_scale is not None))
    df = fleet.measurements
    cal = (df["unit"].eq("N1") & df["bogie_type"].eq("motor")).to_numpy()
    return calibrated(df, fleet.wear_curves, fleet.routes, fleet.route_attributes, fleet.table,
                      cal, fleet)


def cached_vehicle_simulator(route: Sequence[CurveClass], vehicle: str = "metro_b", *,
                             law: str = "usfd", mileage_km: float = 3000.0,
                             depth_per_step_mm: float = 1.0,
                             on_run: Callable[[Mapping[str, Any], float], None] | None = None,
                             segments: Sequence[Mapping[str, Any]] | None = None,
                             rail_tonnages_mt: Sequence[float] = (),
                             ) -> Callable[[Mapping[str, Any]], VehicleWearSimulation]:
    """``simulate(parameters)`` for the physics diagnosis: one whole-vehicle loop run per
    parameter set (``VehicleWearOptions`` fields), cached; ``on_run`` is told of each new run
    and its wall time [s].

    Two parameters are not options of the run: ``curve_classes`` (n) runs on ``segments``
    binned into n classes (``statistics.routes.route_from_segments``) instead of ``route``;
    ``rail_tonnage_mt`` (T) runs on the vehicle's rail worn by its own passages on ``route``
    to T Mt (``physics.rail_tonnage.rails_worn_to_tonnages``, computed once for T and every
    tonnage of ``rail_tonnages_mt``: one chain of rail steps).
    """
    cache: dict[tuple[tuple[str, Any], ...], VehicleWearSimulation] = {}
    contacts: dict = {}  # first contact updates shared by the runs
    rails: dict[float, Any] = {}

    def worn_rail(tonnage_mt: float) -> Any:
        if tonnage_mt not in rails:
            from wearcast.physics.rail_tonnage import rails_worn_to_tonnages

            rails.update(rails_worn_to_tonnages(
                vehicle, list(route), (*rail_tonnages_mt, tonnage_mt), law=law).rails)
        return rails[tonnage_mt]

    def simulate(params: Mapping[str, Any]) -> VehicleWearSimulation:
        key = tuple(sorted(params.items()))
        if key not in cache:
            start = time.perf_counter()
            options = dict(params)
            classes: Sequence[CurveClass] = route
            n_class = options.pop("curve_classes", None)
            if n_class is not None:
                from wearcast.statistics.routes import route_from_segments

                if segments is None:
                    raise ValueError("curve_classes: needs the route's segments")
                classes = [c.curve_class() for c in
                           route_from_segments(segments, n_class=int(n_class)).classes]
            tonnage = options.pop("rail_tonnage_mt", None)
            if tonnage:
                options["rail"] = worn_rail(float(tonnage))
            cache[key] = simulate_vehicle_wear(vehicle, classes, law=law,
                                               mileage_km=mileage_km,
                                               depth_per_step_mm=depth_per_step_mm,
                                               options=VehicleWearOptions(**options),
                                               contact_cache=contacts)
            if on_run is not None:
                on_run(params, time.perf_counter() - start)
        return cache[key]

    return simulate


def curvy_segments(seed: int = 0, n_curves: int = 40) -> list[dict[str, Any]]:
    """Segments of a synthetic line for the curve-classes cause: ``n_curves`` curves of
    150-800 m radius (uniform in curvature), 100-400 m long, alternately right and left, cant
    100 mm, 50 km/h, and tangent track 1.5x their length at 80 km/h. The loop's wear rate
    steps near 400 m (flange contact), so how the curves are binned moves the flange/tread
    split (``statistics.routes.route_from_segments``)."""
    rng = np.random.default_rng(seed)
    segments: list[dict[str, Any]] = []
    for i in range(n_curves):
        radius_m = float(1.0 / rng.uniform(1.0 / 800.0, 1.0 / 150.0))
        segments.append({"length_m": float(rng.uniform(100.0, 400.0)), "radius_m": radius_m,
                         "direction": "left" if i % 2 else "right", "cant_mm": 100.0,
                         "speed_kmh": 50.0})
    total = sum(s["length_m"] for s in segments)
    return [*segments, {"length_m": 1.5 * total, "radius_m": None, "direction": None,
                        "cant_mm": 0.0, "speed_kmh": 80.0}]


def measured_vehicle_series(truth: VehicleWearSimulation, *, n_vehicles: int = 5,
                            wear_scale: float = 1.2, noise_mm: float = 0.02,
                            seed: int = 7, flange_height: bool = False) -> pd.DataFrame:
    """Vehicle-averaged flange thickness and qR [mm] "measured" from a loop run.

    Per vehicle: 0 km and four mileages uniform in 200–1500 km; the truth is the run's mean
    Sd and qR at ``wear_scale`` times the mileage, plus Gaussian noise of ``noise_mm``.
    Columns ``vehicle, distance_km, FT_mm, QR_mm`` (what ``diagnose_physics`` reads), and
    ``FH_mm`` (the mean Sh, same noise) with ``flange_height`` — as seed 003 Table 2 and
    EN 15313 depot measurements give it.
    """
    rng = np.random.default_rng(seed)
    fh_rng = np.random.default_rng([seed, 1])  # FH's own noise: the other rows stay the same
    rows = []
    for v in range(n_vehicles):
        km = np.concatenate([[0.0], np.sort(rng.uniform(200.0, 1500.0, 4))])
        ft_mm = np.interp(wear_scale * km, truth.mileage_km, truth.mean("sd_mm"))
        qr_mm = np.interp(wear_scale * km, truth.mileage_km, truth.mean("qr_mm"))
        columns = {"FT_mm": ft_mm + rng.normal(0, noise_mm, km.size),
                   "QR_mm": qr_mm + rng.normal(0, noise_mm, km.size)}
        if flange_height:
            columns["FH_mm"] = (np.interp(wear_scale * km, truth.mileage_km, truth.mean("sh_mm"))
                                + fh_rng.normal(0, noise_mm, km.size))
        rows.append(pd.DataFrame({"vehicle": f"V{v}", "distance_km": km, **columns}))
    return pd.concat(rows, ignore_index=True)


# --- the loop-driven fleet (fleet_twin_loop) of the detection benchmark and its tests ---

def _loop_classes(radius_m: float | None, cant_mm: float, speed_kmh: float, share: float
                  ) -> list[RouteClass]:
    if radius_m is None:
        return [RouteClass(None, None, 0.0, speed_kmh, share)]
    return [RouteClass(radius_m, d, cant_mm, speed_kmh, share / 2.0) for d in ("left", "right")]


# (radius [m] or None, cant [mm], speed [km/h], share): tangent track and 500 m curves, half
# bending left (the loop runs one step per class and wheel; a wear-loop run of this route
# costs about a minute on the shared machine, so every unit runs the same track geometry)
LOOP_CLASSES = ((None, 0.0, 70.0, 0.6), (500.0, 60.0, 60.0, 0.4))
LOOP_TRUTH = fl.LoopTruth(vehicles={"motor": "metro_b", "trailer": "metro_b"},
                          law="archard_kth", n_steps=6, mileage_scale=0.15)
LOOP_MILEAGES_KM = (15_000.0, 40_000.0, 70_000.0, 100_000.0, 135_000.0, 170_000.0)
LOOP_MEASURE = "tau_max"   # the loop table carries the loop's rates under both names
def loop_route(name: str, lubricated: bool = False) -> twin_routes.TwinRoute:
    classes: list[RouteClass] = []
    for radius_m, cant_mm, speed_kmh, share in LOOP_CLASSES:
        classes += _loop_classes(radius_m, cant_mm, speed_kmh, share)
    return twin_routes.TwinRoute(name, tuple(classes), {"flange_lubrication": lubricated})


def loop_config(seed: int, wear_effects: tuple[Any, ...] = (),
                profile_effects: tuple[Any, ...] = ()) -> ft.FleetConfig:
    """The fleet twin's four-unit layout (modes, loads, instruments, lubrication, dates) on
    one track geometry the loop can run (LOOP_CLASSES), a dry and a lubricated line."""
    line = loop_route("line")
    greased = loop_route("line_lubricated", lubricated=True)
    units = (
        ft.UnitConfig("A", line, vehicles=3, running_mode="mixed", start_date="2021-02-01",
                      km_per_day=520.0, load_t=13.0, instrument_id="MP-1"),
        ft.UnitConfig("B", greased, vehicles=3, running_mode="mixed", start_date="2021-07-15",
                      km_per_day=430.0, load_t=16.0, instrument_id="MP-2"),
        ft.UnitConfig("C", line, vehicles=3, running_mode="lead", start_date="2021-10-01",
                      km_per_day=380.0, load_t=14.5, instrument_id="MP-2"),
        ft.UnitConfig("D", greased, vehicles=3, running_mode="lead", start_date="2022-04-20",
                      km_per_day=600.0, load_t=11.5, instrument_id="MP-1"),
    )
    return ft.FleetConfig(units=units, mileages_km=LOOP_MILEAGES_KM, seed=seed,
                          points_per_profile=200, wear_effects=wear_effects,
                          profile_effects=profile_effects)


def loop_wear_areas(sim: Any, loop_km: NDArray) -> dict[str, NDArray]:
    """Worn area of each region of one loop run at loop mileages (held at its end) [mm^2]:
    the per-step areas integrated once, then interpolated."""
    wheel = SimulatedWheel("", 1, sim.y_mm, sim.profiles_mm, sim.mileage_km)
    return wheel.region_areas_mm2(np.asarray(loop_km, dtype=float))


def _loop_mean_areas(runs: Mapping[tuple[str, int], Sequence[Any]], top_km: float
                     ) -> tuple[NDArray, dict[tuple[str, str, str], NDArray]]:
    """(20 mileages up to ``top_km`` [loop km], the mean worn area of the runs of each
    (bogie type, wheelset, region) there [mm^2]): what the rate table and the progression of
    the same runs are both made from."""
    km = np.linspace(0.0, top_km, 21)[1:]
    areas = {}
    for bogie in ("motor", "trailer"):
        for axle, wheelset in ((1, "leading"), (2, "trailing")):
            sims = runs.get((bogie, axle), ())
            if not sims:
                raise ValueError(f"no loop run for the {bogie} bogie's axle {axle}")
            per_run = [loop_wear_areas(s, km) for s in sims]
            for region in ("flange", "tread"):
                areas[(bogie, wheelset, region)] = np.mean([a[region] for a in per_run],
                                                           axis=0)
    return km, areas


def loop_rate_table(runs: Mapping[tuple[str, int], Sequence[Any]], top_km: float) -> pd.DataFrame:
    """The curve-radius table of the loop's own wear rates: per bogie type and axle (``runs``:
    the loop runs of that position) and region the least-squares rate through the origin of the
    mean worn area over 20 mileages up to ``top_km`` [mm^2 per 1,000 km], on every rail and
    under both measure names (one track geometry: the route's measure is then that rate)."""
    km, areas = _loop_mean_areas(runs, top_km)
    rows = []
    for (bogie, wheelset, region), area in areas.items():
        rate = float(np.sum(area * km) / np.sum(km * km)) * 1e3
        for rail, radius in (("tangent", np.nan), ("high", 500.0), ("low", 500.0)):
            for measure in ("tau_max", "t_gamma"):
                rows.append({"bogie_type": bogie, "wheelset": wheelset, "rail": rail,
                             "radius_m": radius, "region": region,
                             "measure": measure, "value": max(rate, 0.0)})
    return pd.DataFrame(rows)


def loop_expected_progression(runs: Mapping[tuple[str, int], Sequence[Any]], top_km: float,
                              mileage_scale: float) -> ExpectedProgression:
    """The progression shape of the loop runs behind ``loop_rate_table`` (same runs, same 20
    mileages up to ``top_km`` [loop km]): per bogie type, wheelset and region the mean worn
    area over the least-squares linear growth through the origin, on the fleet's km (loop km
    / ``mileage_scale``). What a user gets from simulating the route with the wear loop; the
    finder's null for wear that is as nonlinear as the physics says
    (``discrepancy_progression``)."""
    km, areas = _loop_mean_areas(runs, top_km)
    return ExpectedProgression.from_areas(km / mileage_scale, areas,
                                          source="the wear loop on the same track")


def seed003_classes(table: pd.DataFrame) -> list[CurveClass]:
    """Seed 003 Table 3's statistical track (columns ``R_c_m`` [m, NaN = tangent], ``H_mm``,
    ``V_kmh``, ``p_k_pct``) as loop classes: each curve class in both directions with half its
    share."""
    out = []
    columns = [table[c].to_numpy(float) for c in ("R_c_m", "H_mm", "V_kmh", "p_k_pct")]
    for radius, cant, speed, share_pct in zip(*columns, strict=True):
        if not np.isfinite(radius):
            out.append(CurveClass(None, 0.0, float(speed), share=float(share_pct) / 100.0))
            continue
        for direction in ("left", "right"):
            out.append(CurveClass(float(radius), float(cant), float(speed), direction,
                                  float(share_pct) / 200.0))
    return out
