"""Effect injectors for the fleet twin: one per cause of the discrepancy finder's catalogue.

Each function returns a hook for ``fleet_twin.FleetConfig`` (``wear_effects`` take
(WheelSpec, WearHistory) -> WearHistory; ``profile_effects`` modify one profile's points).
They wrap :mod:`wearcast.statistics.generators.fleet_twin` without changing it. Strength parameters:

- ``traction(m)``: motor-bogie tread areas x m.
- ``running_direction(table, p)``: axle 1 leads a share p of the distance in units of the
  given running mode (P = p P_lead + (1 - p) P_trail, seed 001 §4) instead of the nominal mix.
- ``curve_asymmetry(table, q)``: a share q of each route's curved length bends left.
- ``flange_lubrication(m)``: flange areas x m on routes whose attributes say lubricated.
- ``wear_measure(table, measure)``: wear follows the other measure (areas x P_other / P_nominal,
  normalised on a reference route so the fleet's magnitude stays similar).
- ``nonlinear_progression(beta)``: A x (s / s_ref)^(beta - 1), s_ref = 100,000 km.
- ``seasonal_friction(a)``: ``fleet_twin.seasonal_rate``.
- ``vehicle_load(gamma, load_ref_t)``: areas x (load / load_ref)^gamma.
- ``lateral_scale_error`` / ``flange_tread_offset``: one instrument's geometric error.

``moderate_effects(table)`` names every cause hidden at the strength the detection tests use.

``twin_measurements`` processes a generated fleet's profiles (clean, align, wear curve,
areas: ``processing.process_profile``) into the measurement frame and wear curves that
``discrepancy.diagnose`` and ``hybrid.calibrate`` read.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes
from wearcast.statistics.processing import process_profile
from wearcast.statistics.route_measure import curve_direction_shares, weighted_wear_measure
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import compile_wear_table

Array = NDArray[np.float64]


def traction(tread_multiplier: float) -> ft.WearEffect:
    """Motor bogies wear their treads ``tread_multiplier`` times faster."""
    return ft.scale_rate({"tread": tread_multiplier}, lambda w: w.bogie_type == "motor")


def flange_lubrication(flange_multiplier: float, attribute: str = "flange_lubrication"
                       ) -> ft.WearEffect:
    """Flanges on routes with a true ``attribute`` wear ``flange_multiplier`` times the rate."""
    return ft.scale_rate({"flange": flange_multiplier},
                         lambda w: bool(w.route.attributes.get(attribute, False)))


def vehicle_load(gamma: float, load_ref_t: float = 14.0) -> ft.WearEffect:
    """Wear areas x (load_t / load_ref_t)^gamma."""
    def effect(wheel: ft.WheelSpec, history: ft.WearHistory) -> ft.WearHistory:
        f = (wheel.load_t / load_ref_t) ** gamma
        return replace(history, tread_area_mm2=history.tread_area_mm2 * f,
                       flange_area_mm2=history.flange_area_mm2 * f)
    return effect


def nonlinear_progression(beta: float, reference_mileage_km: float = 100_000.0
                          ) -> ft.WearEffect:
    """A(s) x (s / s_ref)^(beta - 1): wear decelerates (beta < 1) or accelerates (> 1)."""
    def effect(wheel: ft.WheelSpec, history: ft.WearHistory) -> ft.WearHistory:
        s = np.maximum(history.mileage_km, 1e-9)
        g = (s / reference_mileage_km) ** (beta - 1.0)
        return replace(history, tread_area_mm2=history.tread_area_mm2 * g,
                       flange_area_mm2=history.flange_area_mm2 * g)
    return effect


def seasonal_friction(amplitude: float, peak_day_of_year: int = 15) -> ft.WearEffect:
    """Rate x (1 + a cos(2 pi (doy - peak) / 365.25)) (``fleet_twin.seasonal_rate``)."""
    return ft.seasonal_rate(amplitude, peak_day_of_year)


def _rescale_by_measure(wheel: ft.WheelSpec, history: ft.WearHistory,
                        new_p: dict[str, float]) -> ft.WearHistory:
    f = {r: (new_p[r] / wheel.measure_p[r]) if wheel.measure_p[r] > 0 else 1.0
         for r in REGIONS}
    return replace(history, tread_area_mm2=history.tread_area_mm2 * f["tread"],
                   flange_area_mm2=history.flange_area_mm2 * f["flange"])


def running_direction(table: pd.DataFrame, leading_share: float, *, mode: str = "mixed",
                      measure: str = "tau_max") -> ft.WearEffect:
    """In units running in ``mode``, axle 1 leads ``leading_share`` of the distance."""
    index = compile_wear_table(table)

    def effect(wheel: ft.WheelSpec, history: ft.WearHistory) -> ft.WearHistory:
        if wheel.running_mode != mode:
            return history
        p = leading_share if wheel.axle == 1 else 1.0 - leading_share
        new: dict[str, float] = {}
        for r in REGIONS:
            lead, trail = (weighted_wear_measure(
                wheel.route, index, bogie_type=wheel.bogie_type, axle=axle, side=wheel.side,
                running_mode="lead", region=r, measure=measure) for axle in (1, 2))
            new[r] = p * lead + (1.0 - p) * trail
        return _rescale_by_measure(wheel, history, new)
    return effect


def asymmetric_route(route: twin_routes.TwinRoute, left_share: float) -> twin_routes.TwinRoute:
    """The route with a share ``left_share`` of its curved length bending left
    (:func:`wearcast.statistics.route_measure.curve_direction_shares`)."""
    shares = curve_direction_shares(route, left_share)
    return replace(route, classes=tuple(replace(c, share=share)
                                        for c, share in zip(route.classes, shares, strict=True)))


def curve_asymmetry(table: pd.DataFrame, left_share: float, *,
                    measure: str = "tau_max") -> ft.WearEffect:
    """Wheels wear as if a share ``left_share`` of each route's curves bent left."""
    index = compile_wear_table(table)

    def effect(wheel: ft.WheelSpec, history: ft.WearHistory) -> ft.WearHistory:
        route = asymmetric_route(wheel.route, left_share)
        new: dict[str, float] = {r: weighted_wear_measure(route, index, bogie_type=wheel.bogie_type,
                                        axle=wheel.axle, side=wheel.side,
                                        running_mode=wheel.running_mode, region=r,
                                        measure=measure)
               for r in REGIONS}
        return _rescale_by_measure(wheel, history, new)
    return effect


def wear_measure(table: pd.DataFrame, true_measure: str = "t_gamma", *,
                 model_measure: str = "tau_max",
                 reference: twin_routes.TwinRoute | None = None) -> ft.WearEffect:
    """Wear follows ``true_measure`` instead of ``model_measure`` (P ratio per wheel).

    Normalised per region by the ratio for a trailer axle-1 left wheel on ``reference``
    (default the Aosta route, mixed mode) so the fleet's wear magnitude stays similar.
    """
    index = compile_wear_table(table)
    ref = reference or twin_routes.aosta_route()
    def reference_p(region: str, measure: str) -> float:
        return weighted_wear_measure(ref, index, bogie_type="trailer", axle=1, side="left",
                                     running_mode="mixed", region=region, measure=measure)

    norm = {r: reference_p(r, model_measure) / reference_p(r, true_measure) for r in REGIONS}

    def effect(wheel: ft.WheelSpec, history: ft.WearHistory) -> ft.WearHistory:
        new: dict[str, float] = {r: norm[r] * weighted_wear_measure(wheel.route, index,
                                                  bogie_type=wheel.bogie_type, axle=wheel.axle,
                                                  side=wheel.side,
                                                  running_mode=wheel.running_mode, region=r,
                                                  measure=true_measure)
               for r in REGIONS}
        return _rescale_by_measure(wheel, history, new)
    return effect


def lateral_scale_error(instrument_id: str, scale: float) -> ft.ProfileEffect:
    """One instrument stretches y about the tape circle by ``scale`` (fleet_twin's hook)."""
    return ft.lateral_scale_error(instrument_id, scale)


def flange_tread_offset(instrument_id: str, offset_mm: float, split_y_mm: float = -30.0
                        ) -> ft.ProfileEffect:
    """One instrument shifts the flange part (y < split) laterally by ``offset_mm``."""
    def effect(wheel: ft.WheelSpec, mileage_km: float, y: Array, z: Array
               ) -> tuple[Array, Array]:
        if wheel.instrument_id != instrument_id:
            return y, z
        return np.where(y < split_y_mm, y + offset_mm, y), z
    return effect


def moderate_effects(table: pd.DataFrame
                     ) -> dict[str, tuple[tuple[ft.WearEffect, ...], tuple[ft.ProfileEffect, ...]]]:
    """Every cause of the catalogue hidden at a moderate strength: cause code (and ``none``)
    -> (wear effects, profile effects) for :func:`scenario_config`.

    The strengths the hidden-effect tests detect (the finder's and the API's alike):
    motor treads x 1.3, axle 1 leading 80 %, 70 % of the curved length bending left,
    lubricated flanges x 0.5, wear following ``t_gamma``, progression exponent 0.75, seasonal
    amplitude 0.3, load exponent 1.5 and instrument MP-2's flange part shifted by 0.3 mm.
    ``table`` is the curve-radius table the twin is generated with.
    """
    return {
        "none": ((), ()),
        "traction": ((traction(1.3),), ()),
        "running_direction": ((running_direction(table, 0.8),), ()),
        "curve_asymmetry": ((curve_asymmetry(table, 0.7),), ()),
        "flange_lubrication": ((flange_lubrication(0.5),), ()),
        "wear_measure": ((wear_measure(table),), ()),
        "nonlinear_progression": ((nonlinear_progression(0.75),), ()),
        "seasonal_friction": ((seasonal_friction(0.3),), ()),
        "vehicle_load": ((vehicle_load(1.5),), ()),
        "profile_misalignment": ((), (flange_tread_offset("MP-2", 0.3),)),
    }


def to_route(route: twin_routes.TwinRoute) -> Route:
    """The statistics ``Route`` of a twin route (attributes are returned separately)."""
    return Route(route.name, route.classes)


def twin_measurements(twin: ft.FleetTwin) -> tuple[pd.DataFrame, Array]:
    """Process every generated profile: (measurement frame, wear curves (n, g) [mm]).

    The frame has one row per (wheel, mileage) with the long CSV's metadata, ``route``
    (= ``route_id``), ``flange_area_mm2``, ``tread_area_mm2`` and Sd/Sh/qR, in the form that
    ``hybrid.calibrate`` and ``discrepancy.diagnose`` read.
    """
    rows, curves = [], []
    meta_cols = [c for c in twin.profiles.columns if c not in ("y_mm", "z_mm")]
    for _, g in twin.profiles.groupby(["wheel_id", "mileage_km"], sort=False):
        p = process_profile(g["y_mm"].to_numpy(float), g["z_mm"].to_numpy(float))
        meta = g.iloc[0][meta_cols].to_dict()
        meta.update(route=meta.get("route_id"), flange_area_mm2=p.areas.flange_mm2,
                    tread_area_mm2=p.areas.tread_mm2, sd_mm=p.parameters.sd_mm,
                    sh_mm=p.parameters.sh_mm, qr_mm=p.parameters.qr_mm)
        rows.append(meta)
        curves.append(np.nan_to_num(p.wear_mm, nan=0.0))
    return pd.DataFrame(rows), np.vstack(curves)


def scenario_config(*, seed: int = 0, wear_effects: tuple[ft.WearEffect, ...] = (),
                    profile_effects: tuple[ft.ProfileEffect, ...] = (),
                    vehicles_per_unit: int = 3, points_per_profile: int = 200,
                    mileages_km: tuple[float, ...] = (15_000, 40_000, 70_000, 100_000,
                                                      135_000, 170_000)) -> ft.FleetConfig:
    """A four-unit test fleet with every covariate the catalogue needs.

    Units A/B run the Aosta line (seed 003 Table 3; the copy B and D run is marked
    flange-lubricated) in ``mixed`` mode, C the metro line (seed 000 Table 1) and D in ``lead``
    mode; loads 13 / 16 / 14.5 / 11.5 t; instruments MP-1 (A, D) and MP-2 (B, C)
    (mode, lubrication and instrument are orthogonal across units);
    different start dates and daily mileages so dates and mileage are not collinear.
    """
    aosta = twin_routes.aosta_route()
    lubricated = replace(twin_routes.aosta_route("aosta_lubricated"),
                         attributes={**aosta.attributes, "flange_lubrication": True})
    units = (
        ft.UnitConfig("A", aosta, vehicles=vehicles_per_unit, running_mode="mixed",
                      start_date="2021-02-01", km_per_day=520.0, load_t=13.0,
                      instrument_id="MP-1"),
        ft.UnitConfig("B", lubricated, vehicles=vehicles_per_unit, running_mode="mixed",
                      start_date="2021-07-15", km_per_day=430.0, load_t=16.0,
                      instrument_id="MP-2"),
        ft.UnitConfig("C", twin_routes.metro_route(), vehicles=vehicles_per_unit,
                      running_mode="lead",
                      start_date="2021-10-01", km_per_day=380.0, load_t=14.5,
                      instrument_id="MP-2"),
        ft.UnitConfig("D", lubricated, vehicles=vehicles_per_unit, running_mode="lead",
                      start_date="2022-04-20", km_per_day=600.0, load_t=11.5,
                      instrument_id="MP-1"),
    )
    return ft.FleetConfig(units=units, mileages_km=mileages_km, seed=seed,
                          points_per_profile=points_per_profile, wear_effects=wear_effects,
                          profile_effects=profile_effects,
                          calibration_factor={"tread": 1.5e-6, "flange": 2.5e-6})


def scenario_routes(config: ft.FleetConfig) -> tuple[dict[str, Route], dict[str, dict]]:
    """(Route per name, attributes per name) of a fleet configuration's units."""
    routes, attrs = {}, {}
    for unit in config.units:
        routes[unit.route.name] = to_route(unit.route)
        attrs[unit.route.name] = dict(unit.route.attributes)
    return routes, attrs
