"""An independent fleet generator for judging the discrepancy finder on data it was not built on.

``fleet_twin`` is the generator the finder was developed against. This module is a second,
deliberately different one, so that the finder's detection rates can be checked on data
whose shapes, scatter and layout it has never seen (issue 4: "the finder must not be tuned
to the generator"). It shares no code with ``fleet_twin`` and its effect injection is
re-implemented in its own way. What differs:

- **Track and table**: three routes of its own (a curvy ``valley`` line, the same line with
  flange greasing ``valley_greased``, and a mild ``plain`` line), and wear measures from
  analytic functions of curvature (``alt_measure``) evaluated at each class's exact radius;
  the curve-radius table handed to the model samples those functions at a few radii, so
  the model's 1/R interpolation is itself slightly wrong (as with any real table).
- **Layout**: three units of unequal length (4, 3 and 2 cars); every car is either a motor
  car (two motor bogies) or a trailer car (two trailer bogies), so ``bogie_type`` is constant
  within a vehicle; cars of one unit run different routes; per-vehicle loads.
- **Mileages**: each unit has its own number of depot visits and daily mileage (varying by
  weekday), so wheels have unequal mileages; about 12 % of the measurements are missing at
  random.
- **Scatter**: wheel rate factors uniform on [0.85, 1.15] times a vehicle factor uniform on
  [0.95, 1.05] (not log-normal); heteroscedastic area scatter (0.4 mm² + 4 % of the area).
- **Shapes**: one broad tread bump (centre +3..+11 mm, half-width 22..30 mm growing with
  wear) and a vertical flange-root bump centred near y = -37 mm; profiles sampled evenly
  in y (not arc length) with vertical noise that differs per instrument, and a rigid
  misalignment rotating about the flange back (y = -70 mm), not the tape circle.

Effects (``AltEffects``), each injected its own way:

``traction``             motor-car treads gain an ADDITIVE creep-wear rate equal to (m - 1)
                         times the fleet's mean trailer tread rate (not a multiplier)
``leading_share``        in ``mixed`` units axle 1 leads a share p (P recomputed from alt_measure)
``left_share``           a share q of every route's curved length bends left
``lubricated_flange``    flanges on greased routes wear m times the rate, m jittered +/-0.05
                         per wheel (greasing is never uniform)
``true_measure``         wear follows the other measure, normalised on the fleet mean
``running_in``           running-in: A = k (s + c s_r (1 - exp(-s / s_r))), s_r = 40,000 km
``seasonal_amplitude``   daily wear rate x (1 + a sin(2 pi (doy - 110) / 365.25)), summed
                         day by day with the daily mileage
``load_exponent``        rate x (1 + g (load - 14 t) / 14 t) (linear in load, not a power)
``instrument_scale``     (instrument, e): that instrument's lateral scale from its origin at
                         the flange back: y' = y + e (y + 70)
``instrument_offset``    (instrument, d [mm]): its flange part (y < -30) is shifted by d

Pure (numpy/pandas in, out), deterministic for a seed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vocabulary import REGIONS, WEAR_MEASURES
from wearcast.statistics.generators.twin_routes import split_directions
from wearcast.statistics.processing import process_profile
from wearcast.statistics.route_measure import analytic_wear_measure, curve_direction_shares
from wearcast.statistics.routes import Route, RouteClass
from wearcast.statistics.wear_tables import sample_wear_table

Array = NDArray[np.float64]
SPLIT_Y_MM = -30.0
TABLE_RADII_M = (180.0, 250.0, 350.0, 500.0, 800.0, 1200.0, 2500.0)
_FINE_Y = np.arange(-70.0, 60.0 + 1e-9, 0.05)


# --- routes and wear measures ------------------------------------------------------------------

def _classes(rows: tuple[tuple[float | None, float], ...]) -> tuple[RouteClass, ...]:
    out: list[RouteClass] = []
    for radius, share in rows:
        if radius is None:
            out += split_directions(None, 0.0, 100.0, share)
        else:  # half left, half right as described (the truth may differ: left_share)
            cant = float(min(150.0, round(8.0 * 70.0**2 / radius)))
            out += split_directions(radius, cant, 70.0, share)
    return tuple(out)


def alt_routes() -> tuple[dict[str, Route], dict[str, dict[str, Any]]]:
    """(Route per name, attributes per name): valley, valley_greased, plain."""
    valley = ((None, 0.42), (210.0, 0.14), (300.0, 0.18), (450.0, 0.12), (900.0, 0.09),
              (2000.0, 0.05))
    plain = ((None, 0.78), (600.0, 0.08), (1100.0, 0.09), (3000.0, 0.05))
    routes = {"valley": Route("valley", _classes(valley)),
              "valley_greased": Route("valley_greased", _classes(valley)),
              "plain": Route("plain", _classes(plain))}
    attrs = {"valley": {"flange_lubrication": False, "line": "mountain"},
             "valley_greased": {"flange_lubrication": True, "line": "mountain"},
             "plain": {"flange_lubrication": False, "line": "lowland"}}
    return routes, attrs


def alt_measure(bogie_type: str, wheelset: str, rail: str, radius_m: float | None,
                region: str, measure: str) -> float:
    """Analytic wear measure of one contact situation (tau_max [MPa] or t_gamma [N]).

    Curvature k = 1000 / R [1/km]. Tread: tangent level plus a saturating rise with k,
    steeper on the low rail; flange: only on the high rail, exponential onset below a
    radius that is larger for the leading wheelset. Motor bogies: t_gamma x1.6 in curves,
    x1.2 on tangent track; tau_max x1.03.
    """
    k = 0.0 if radius_m is None or rail == "tangent" else 1000.0 / radius_m
    lead = wheelset == "leading"
    if measure == "tau_max":
        t0, t1, f1, onset = 160.0, 95.0, 60.0, (1.2 if lead else 3.2)
        motor = 1.03
    else:
        t0, t1, f1, onset = 30.0, 60.0, 55.0, (1.2 if lead else 3.2)
        motor = 1.6 if k > 0 else 1.2
    if region == "tread":
        slope = 1.35 if rail == "low" else 1.0
        value = t0 + t1 * slope * (1.0 - np.exp(-k / 3.0)) * (1.0 if lead else 0.7)
    else:
        value = 0.0
        if rail == "high" and k > onset:
            value = f1 * (np.expm1(0.45 * (k - onset))) * (1.0 if lead else 0.3)
    return float(value * (motor if bogie_type == "motor" else 1.0))


def alt_wear_table(radii_m: tuple[float, ...] = TABLE_RADII_M) -> pd.DataFrame:
    """The curve-radius table (docs/conventions.md "Curve-radius table CSV") sampling
    ``alt_measure``, both measures."""
    return sample_wear_table(alt_measure, radii_m)


def _route_p(route: Route, bogie: str, axle: int, side: str, lead_share: float,
             left_share: float | None, measure: str) -> dict[str, float]:
    """Weighted measure per region with an axle-1 leading share and a true left share."""
    p_lead = lead_share if axle == 1 else 1.0 - lead_share
    shares = curve_direction_shares(route, left_share)
    out: dict[str, float] = {}
    for region in REGIONS:
        def value(ws: str, rail: str, radius_m: float | None, region: str = region) -> float:
            return alt_measure(bogie, ws, rail, radius_m, region, measure)

        p = analytic_wear_measure(route, side, value, shares)
        out[region] = p_lead * p["leading"] + (1 - p_lead) * p["trailing"]
    return out


# --- configuration -----------------------------------------------------------------------------

@dataclass(frozen=True)
class AltEffects:
    """Hidden effects (defaults: none). See the module docstring for each injection."""

    traction: float = 1.0
    leading_share: float | None = None
    left_share: float | None = None
    lubricated_flange: float = 1.0
    true_measure: str | None = None
    running_in: float = 0.0
    seasonal_amplitude: float = 0.0
    load_exponent: float = 0.0
    instrument_scale: tuple[str, float] | None = None
    instrument_offset: tuple[str, float] | None = None


@dataclass(frozen=True)
class AltUnit:
    unit_id: str
    cars: str                      # 'M' motor car / 'T' trailer car per vehicle
    routes: tuple[str, ...]        # route per car
    running_mode: str
    start_date: str
    km_per_day: float
    visits: int                    # number of depot visits (measurements per wheel)
    max_mileage_km: float
    instruments: tuple[str, ...]   # instrument per visit, cycled
    base_load_t: float


def default_units() -> tuple[AltUnit, ...]:
    return (
        AltUnit("U1", "MTTM", ("valley",) * 4, "mixed", "2020-09-07", 450.0, 7, 210_000.0,
                ("LP-1",), 14.5),
        AltUnit("U2", "MTM", ("valley_greased", "valley_greased", "valley"), "lead",
                "2021-03-22", 520.0, 6, 240_000.0, ("LP-2",), 13.0),
        AltUnit("U3", "MT", ("valley_greased", "plain"), "mixed", "2021-01-11", 380.0, 8,
                170_000.0, ("LP-1", "LP-2"), 15.5),
    )


@dataclass(frozen=True)
class AltConfig:
    """Fleet layout, model constants and scatter of the alternative generator."""

    units: tuple[AltUnit, ...] = field(default_factory=default_units)
    effects: AltEffects = AltEffects()
    measure: str = "tau_max"
    k_per_measure: tuple[float, float] = (5.0e-6, 1.9e-6)   # (flange, tread) mm²/km per unit P
    missing_share: float = 0.12
    area_noise_mm2: float = 0.4
    area_noise_rel: float = 0.04
    profile_step_mm: float = 0.4
    noise_mm: dict[str, float] = field(default_factory=lambda: {"LP-1": 0.010, "LP-2": 0.02})
    seed: int = 0


@dataclass(frozen=True)
class AltFleet:
    """Generated data: long-CSV ``profiles``, processed ``measurements`` with ``wear_curves``
    (n, g) [mm] on the processing grid, ``routes``/``route_attributes`` and the ``table``."""

    profiles: pd.DataFrame
    measurements: pd.DataFrame
    wear_curves: Array
    routes: dict[str, Route]
    route_attributes: dict[str, dict[str, Any]]
    table: pd.DataFrame


# --- shapes -----------------------------------------------------------------------------------

def _bump(y: Array, centre: float, half_width: float, lo: float, hi: float) -> Array:
    u = (y - centre) / half_width
    b = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 3, 0.0)
    return np.where((y >= lo) & (y < hi), b, 0.0)


def alt_wear_curve(y: Array, tread_mm2: float, flange_mm2: float, tread_centre: float,
                   flange_centre: float) -> Array:
    """Wear curve [mm]: a single broad tread bump and a flange-root bump, exact areas."""
    width = min(30.0, 22.0 + 0.08 * max(tread_mm2, 0.0))
    width = min(width, tread_centre - SPLIT_Y_MM - 0.5)
    tb = _bump(_FINE_Y, tread_centre, width, SPLIT_Y_MM, 60.0)
    fb = _bump(_FINE_Y, flange_centre, 6.5, -60.0, SPLIT_Y_MM)
    step = _FINE_Y[1] - _FINE_Y[0]
    w = tb * (tread_mm2 / (tb.sum() * step)) + fb * (flange_mm2 / (fb.sum() * step))
    return np.interp(y, _FINE_Y, w)


# --- generator --------------------------------------------------------------------------------

def _daily_km(unit: AltUnit, days: NDArray[np.integer[Any]]) -> Array:
    weekday = (days + 3) % 7          # 1970-01-01 was a Thursday -> 0 = Monday
    return unit.km_per_day * np.where(weekday >= 5, 0.6, 1.16)


def generate_alt_fleet(config: AltConfig | None = None) -> AltFleet:
    """Generate, measure and process the fleet (see the module docstring)."""
    cfg = config or AltConfig()
    fx = cfg.effects
    rng = np.random.default_rng(cfg.seed)
    routes, attrs = alt_routes()
    table = alt_wear_table()
    midx = WEAR_MEASURES.index(cfg.measure)
    wheels: list[dict[str, Any]] = []
    for unit in cfg.units:
        for v, (car, route_name) in enumerate(zip(unit.cars, unit.routes, strict=True), 1):
            vehicle = f"{unit.unit_id}-{v}"
            load = unit.base_load_t + (1.0 if car == "M" else 0.0) + rng.uniform(-2.0, 2.0)
            vfac = rng.uniform(0.95, 1.05)
            bogie = "motor" if car == "M" else "trailer"
            for b in (1, 2):
                for axle in (1, 2):
                    for side in ("left", "right"):
                        wheels.append(dict(
                            wheel_id=f"{vehicle}/{b}{axle}{side[0]}", vehicle_id=vehicle,
                            unit=unit, bogie_type=bogie, axle=axle, side=side,
                            route=route_name, load_t=round(load, 2),
                            factor=vfac * rng.uniform(0.85, 1.15, size=2)))
    # true rates per region [mm²/km]
    nominal_lead = {"mixed": 0.5, "lead": None}
    for w in wheels:
        unit = w["unit"]
        lead = nominal_lead[unit.running_mode]
        if lead is None:
            lead = 1.0
        elif fx.leading_share is not None:
            lead = fx.leading_share
        measure = fx.true_measure or cfg.measure
        w["p_true"] = _route_p(routes[w["route"]], w["bogie_type"], w["axle"], w["side"],
                               lead, fx.left_share, measure)
        w["p_model"] = _route_p(routes[w["route"]], w["bogie_type"], w["axle"], w["side"],
                                lead, None, cfg.measure)
    k = np.array(cfg.k_per_measure) if midx == 0 else np.array(cfg.k_per_measure) * 4.0
    if fx.true_measure is not None and fx.true_measure != cfg.measure:
        for r in REGIONS:   # normalise the other measure on the fleet mean
            num = np.mean([w["p_model"][r] for w in wheels])
            den = np.mean([w["p_true"][r] for w in wheels])
            for w in wheels:
                w["p_true"] = {**w["p_true"], r: w["p_true"][r] * num / max(den, 1e-12)}
    for w in wheels:
        w["rate"] = np.array([k[0] * w["p_true"]["flange"], k[1] * w["p_true"]["tread"]]) \
            * w["factor"]
    trailer_tread = np.mean([w["rate"][1] for w in wheels if w["bogie_type"] == "trailer"])
    for w in wheels:
        if w["bogie_type"] == "motor" and fx.traction != 1.0:
            w["rate"] = w["rate"] + np.array([0.0, (fx.traction - 1.0) * trailer_tread])
        if attrs[w["route"]]["flange_lubrication"] and fx.lubricated_flange != 1.0:
            m = fx.lubricated_flange + rng.uniform(-0.05, 0.05)
            w["rate"] = w["rate"] * np.array([max(m, 0.0), 1.0])
        if fx.load_exponent:
            w["rate"] = w["rate"] * max(0.05, 1.0 + fx.load_exponent * (w["load_t"] - 14.0)
                                        / 14.0)
    y_nom = np.arange(-68.0, 58.0, cfg.profile_step_mm)
    prof_rows, meas_rows, curves = [], [], []
    for w in wheels:
        unit = w["unit"]
        start = np.datetime64(unit.start_date, "D").astype(np.int64)
        n_days = int(unit.max_mileage_km / unit.km_per_day * 1.05) + 1
        days = start + np.arange(n_days)
        km = _daily_km(unit, days) * rng.uniform(0.97, 1.03)
        doy = (days - np.datetime64("1970-01-01", "D").astype(np.int64)) % 365.25
        season = 1.0 + fx.seasonal_amplitude * np.sin(2 * np.pi * (doy - 110.0) / 365.25)
        cum_km = np.cumsum(km)
        cum_wear = np.cumsum(km * season)          # season-weighted km
        visit_km = np.linspace(unit.max_mileage_km / unit.visits, unit.max_mileage_km,
                               unit.visits) * rng.uniform(0.93, 1.0, unit.visits)
        visit_km = np.sort(visit_km)
        keep = rng.uniform(size=unit.visits) >= cfg.missing_share
        keep[-1] = True if keep.sum() < 2 else keep[-1]
        tread_c = rng.uniform(3.0, 11.0)
        flange_c = rng.uniform(-38.5, -35.5)
        for i, s in enumerate(visit_km):
            if not keep[i]:
                continue
            d = int(np.searchsorted(cum_km, s))
            d = min(d, n_days - 1)
            s_eff = float(cum_wear[d])
            if fx.running_in:
                s_r = 40_000.0
                s_eff = s_eff + fx.running_in * s_r * (1.0 - np.exp(-s / s_r))
            true = w["rate"] * s_eff
            noisy = true * (1.0 + cfg.area_noise_rel * rng.standard_normal(2)) \
                + cfg.area_noise_mm2 * rng.standard_normal(2)
            noisy = np.maximum(noisy, 0.0)
            inst = unit.instruments[i % len(unit.instruments)]
            y = y_nom + rng.uniform(-0.1, 0.1, y_nom.size)
            z = s1002_height_mm(y) - alt_wear_curve(y, noisy[1], noisy[0], tread_c, flange_c)
            z = z + rng.normal(0.0, cfg.noise_mm.get(inst, 0.015), y.size)
            if fx.instrument_scale is not None and fx.instrument_scale[0] == inst:
                y = y + fx.instrument_scale[1] * (y + 70.0)
            if fx.instrument_offset is not None and fx.instrument_offset[0] == inst:
                y = np.where(y < SPLIT_Y_MM, y + fx.instrument_offset[1], y)
            ang = rng.uniform(-2e-3, 2e-3)
            yy, zz = y + 70.0, z
            y = np.cos(ang) * yy - np.sin(ang) * zz - 70.0 + rng.uniform(-0.5, 0.5)
            z = np.sin(ang) * yy + np.cos(ang) * zz + rng.uniform(-0.1, 0.1)
            date = str(np.datetime64(int(days[d]), "D"))
            meta = {"wheel_id": w["wheel_id"], "vehicle_id": w["vehicle_id"],
                    "bogie_type": w["bogie_type"], "axle": w["axle"], "side": w["side"],
                    "mileage_km": float(round(s, -1)), "measured_on": date,
                    "route_id": w["route"], "running_mode": unit.running_mode,
                    "instrument_id": inst, "load_t": w["load_t"], "unit": unit.unit_id}
            prof_rows.append(pd.DataFrame({**meta, "y_mm": np.round(y, 3),
                                           "z_mm": np.round(z, 3)}))
            p = process_profile(y, z)
            meas_rows.append({**meta, "route": w["route"],
                              "flange_area_mm2": p.areas.flange_mm2,
                              "tread_area_mm2": p.areas.tread_mm2,
                              "true_flange_area_mm2": float(true[0]),
                              "true_tread_area_mm2": float(true[1])})
            curves.append(np.nan_to_num(p.wear_mm, nan=0.0))
    cols = ["wheel_id", "vehicle_id", "bogie_type", "axle", "side", "mileage_km", "y_mm",
            "z_mm", "measured_on", "route_id", "running_mode", "instrument_id", "load_t", "unit"]
    return AltFleet(pd.concat(prof_rows, ignore_index=True)[cols], pd.DataFrame(meas_rows),
                    np.vstack(curves), routes, attrs, table)


#: Moderate strength of every cause (the hidden-effect tests on this generator).
MODERATE = {
    "none": AltEffects(),
    "traction": AltEffects(traction=1.4),
    "running_direction": AltEffects(leading_share=0.8),
    "curve_asymmetry": AltEffects(left_share=0.7),
    "flange_lubrication": AltEffects(lubricated_flange=0.5),
    "wear_measure": AltEffects(true_measure="t_gamma"),
    "nonlinear_progression": AltEffects(running_in=1.0),
    "seasonal_friction": AltEffects(seasonal_amplitude=0.3),
    "vehicle_load": AltEffects(load_exponent=1.5),
    "profile_misalignment": AltEffects(instrument_scale=("LP-2", 0.01)),
}
