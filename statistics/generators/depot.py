"""A depot's measurement campaign, simulated day by day on a real calendar.

Written to test the discrepancy finder on data it was not built on: it imports nothing from
the finder and every effect is written from its physical description, in its own way.

The fleet
    Units of coupled cars; a car is either ``MT`` (one motor and one trailer bogie) or
    ``TT`` (two trailer bogies). Every car has a duty roster: a route it runs, changed on a
    few random dates (vehicles change route), and a daily mileage with a weekday pattern,
    random idle days and maintenance stops of a week or two.
The wear (every calendar day, per wheel and region)
    dA_r = k_r P_r(route of the day, wheelset position of the day, rail) km_day
    x wheel and vehicle random factors x the day's effects. P comes from analytic wear
    measures of curvature (``depot_measure``); the curve-radius table handed to the model
    samples them at a few radii (so the model's interpolation is itself slightly wrong).
    Random factors: per wheel exp(0.07 t_4) (heavy-tailed), per vehicle exp(N(0, 0.05)).
Measurements
    Depot visits at irregular intervals (gaps 20-90 days); ~10 % of the visits are missed,
    ~5 % of measurements are repeated on the same day; a wheel whose flange or tread wear
    passes a turning threshold, or at random (~1 % per visit), is reprofiled at that visit
    and its mileage since reprofiling restarts at 0. Each visit uses one of three
    instruments; with ``profiles=True`` every measurement is a measured profile (points
    evenly spaced in y, heavy-tailed vertical noise of the instrument, a few spikes, a rigid
    misalignment about the field-side end) processed by ``processing.process_profile``; with
    ``profiles=False`` the areas get heteroscedastic heavy-tailed noise
    (0.25 mm² + 3 % of the area, Student t with 3 degrees of freedom) and the wear curves
    are the true shapes at those areas (fast, for the area causes).

Effects (``DepotEffects``), each from its physical description
    ``traction``       creep from traction and braking adds tread wear on motor bogies: the
                       day's tread wear of a motor-bogie wheel x m (m jittered by 0.03 per
                       vehicle: traction control differs)
    ``leading_share``  units running both ways run each day's trips in one direction; axle 1
                       leads on a day with probability p (the nominal mix is 1/2)
    ``left_share``     the routes' curved length bends left in a share q (described: 1/2)
    ``greased_flange`` on greased routes flange wear x m on the days the lubricator works
                       (90 % of the days)
    ``measure_blend``  wear follows (1 - w) tau_max + w T_gamma (each normalised by its fleet
                       mean), an arithmetic blend
    ``hardening``      the wear rate decays as the tread work-hardens: rate x
                       (max(s, 2,000 km) / 60,000 km)^(beta - 1), s the mileage since
                       reprofiling
    ``seasonal``       rate x (1 + a cos(2 pi (day of year - peak) / 365.25)) on each calendar
                       day (leaf fall / wet rails), peak day ``season_peak_day``
    ``load_exponent``  the day's passenger load varies around the car's mean; wear rate x
                       (load / 14 t)^gamma
    ``instrument_scale``  (instrument, e): its lateral scale is off by e about the flange back
                       (y = -70 mm): y' = y + e (y + 70)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics.generators.twin_routes import split_directions
from wearcast.statistics.processing import process_profile
from wearcast.statistics.route_measure import analytic_wear_measure, curve_direction_shares
from wearcast.statistics.routes import Route, RouteClass
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM
from wearcast.statistics.wear_tables import sample_wear_table

Array = NDArray[np.float64]
SPLIT_Y_MM = -30.0
TABLE_RADII_M = (200.0, 300.0, 450.0, 700.0, 1000.0, 2000.0)
INSTRUMENTS = ("DP-A", "DP-B", "DP-C")
_FINE_Y = np.arange(-70.0, 60.0 + 1e-9, 0.05)


def depot_measure(bogie: str, wheelset: str, rail: str, radius_m: float | None, region: str,
                  measure: str) -> float:
    """Analytic wear measure of one contact situation (tau_max [MPa] or T_gamma [N]).

    Curvature c = 1000 / R [1/km]. Tread: a level plus a rise ~ c^0.8, 30 % more on the low
    rail; flange: high rail only, ~ (c - c0)^1.5 above an onset c0 (1.5 leading, 3.5
    trailing). Motor bogies: T_gamma x1.5 (x1.15 on tangent track), tau_max x1.02.
    """
    c = 0.0 if radius_m is None or rail == "tangent" else 1000.0 / radius_m
    lead = wheelset == "leading"
    if measure == "tau_max":
        t0, t1, f1 = 170.0, 28.0, 40.0
        motor = 1.02
    else:
        t0, t1, f1 = 22.0, 20.0, 70.0
        motor = 1.5 if c > 0 else 1.15
    if region == "tread":
        value = t0 + t1 * c ** 0.8 * (1.3 if rail == "low" else 1.0) * (1.0 if lead else 0.75)
    else:
        onset = 1.5 if lead else 3.5
        value = f1 * max(c - onset, 0.0) ** 1.5 * (1.0 if lead else 0.35) \
            if rail == "high" else 0.0
    return float(value * (motor if bogie == "motor" else 1.0))


def depot_wear_table(radii_m: tuple[float, ...] = TABLE_RADII_M) -> pd.DataFrame:
    """The curve-radius table (docs/conventions.md "Curve-radius table CSV") sampling
    ``depot_measure``."""
    return sample_wear_table(depot_measure, radii_m)


def _route(name: str, rows: tuple[tuple[float | None, float], ...]) -> Route:
    classes: list[RouteClass] = []
    for radius, share in rows:
        if radius is None:
            classes += split_directions(None, 0.0, 90.0, share)
        else:
            cant = float(min(130.0, round(9.0 * 65.0 ** 2 / radius)))
            classes += split_directions(radius, cant, 65.0, share)
    return Route(name, tuple(classes))


def depot_routes() -> tuple[dict[str, Route], dict[str, dict[str, Any]]]:
    """(Route per name, attributes): ``ridge`` (curvy), ``ridge_greased`` (same track,
    greased), ``coast`` (mild)."""
    ridge = ((None, 0.38), (240.0, 0.16), (330.0, 0.2), (520.0, 0.14), (1300.0, 0.12))
    coast = ((None, 0.7), (650.0, 0.12), (1500.0, 0.18))
    routes = {"ridge": _route("ridge", ridge), "ridge_greased": _route("ridge_greased", ridge),
              "coast": _route("coast", coast)}
    attrs = {"ridge": {"flange_lubrication": "no"}, "ridge_greased": {"flange_lubrication": "yes"},
             "coast": {"flange_lubrication": "no"}}
    return routes, attrs


@dataclass(frozen=True)
class DepotEffects:
    """Hidden effects (defaults: none); see the module docstring."""

    traction: float = 1.0
    leading_share: float | None = None
    left_share: float | None = None
    greased_flange: float = 1.0
    measure_blend: float = 0.0
    hardening: float = 1.0
    seasonal: float = 0.0
    season_peak_day: float = 290.0
    load_exponent: float = 0.0
    instrument_scale: tuple[str, float] | None = None


@dataclass(frozen=True)
class DepotCar:
    car_id: str
    kind: str                      # 'MT' or 'TT'
    routes: tuple[str, ...]        # candidate routes; the roster changes among them
    mean_load_t: float


@dataclass(frozen=True)
class DepotUnit:
    unit_id: str
    cars: tuple[DepotCar, ...]
    running_mode: str              # 'lead' (axle 1 always leads) or 'mixed'
    km_per_day: float


def default_depot_units() -> tuple[DepotUnit, ...]:
    """Five units, 18 cars (10 MT, 8 TT); two units run in ``lead`` mode."""
    return (
        DepotUnit("N1", (DepotCar("N1a", "MT", ("ridge", "coast"), 15.0),
                         DepotCar("N1b", "TT", ("ridge",), 13.0),
                         DepotCar("N1c", "MT", ("ridge", "ridge_greased"), 16.5)),
                  "mixed", 420.0),
        DepotUnit("N2", (DepotCar("N2a", "MT", ("ridge_greased",), 14.0),
                         DepotCar("N2b", "TT", ("ridge_greased", "coast"), 12.0),
                         DepotCar("N2c", "MT", ("coast", "ridge_greased"), 15.5)),
                  "lead", 510.0),
        DepotUnit("N3", (DepotCar("N3a", "TT", ("coast", "ridge"), 13.5),
                         DepotCar("N3b", "MT", ("ridge",), 17.0),
                         DepotCar("N3c", "TT", ("ridge", "ridge_greased"), 12.5),
                         DepotCar("N3d", "MT", ("coast",), 14.5)),
                  "mixed", 360.0),
        DepotUnit("N4", (DepotCar("N4a", "MT", ("ridge_greased", "ridge"), 16.0),
                         DepotCar("N4b", "TT", ("coast",), 11.5),
                         DepotCar("N4c", "MT", ("ridge",), 13.0),
                         DepotCar("N4d", "TT", ("ridge_greased",), 14.0)),
                  "mixed", 470.0),
        DepotUnit("N5", (DepotCar("N5a", "MT", ("coast", "ridge_greased"), 17.5),
                         DepotCar("N5b", "TT", ("ridge",), 12.0),
                         DepotCar("N5c", "TT", ("ridge_greased", "coast"), 15.0),
                         DepotCar("N5d", "MT", ("ridge_greased",), 13.5)),
                  "lead", 400.0),
    )


@dataclass(frozen=True)
class DepotConfig:
    """The campaign: units, calendar, wear constants, nuisance and effects."""

    units: tuple[DepotUnit, ...] = field(default_factory=default_depot_units)
    effects: DepotEffects = DepotEffects()
    start: str = "2021-03-01"
    days: int = 760
    k_mm2_per_km: tuple[float, float] = (4.0e-6, 1.6e-6)    # (flange, tread) per unit tau_max
    wheel_sd: float = 0.07
    vehicle_sd: float = 0.05
    missed_visit: float = 0.10
    repeated: float = 0.05
    profiles: bool = False
    profile_step_mm: float = 0.5
    seed: int = 0


@dataclass(frozen=True)
class DepotFleet:
    """Generated campaign: ``measurements`` (one row per measurement, processed areas),
    ``wear_curves`` (n, g) [mm] on the processing grid, ``profiles`` (long CSV) or None,
    routes, table."""

    measurements: pd.DataFrame
    wear_curves: Array
    profiles: pd.DataFrame | None
    routes: dict[str, Route]
    route_attributes: dict[str, dict[str, Any]]
    table: pd.DataFrame


def _position_measures(route: Route, bogie: str, side: str, left_share: float | None,
                       blend: float, norm: dict[str, float]) -> Array:
    """(2 wheelsets, 2 regions) route measure of a wheel (leading row 0, trailing row 1)."""
    shares = curve_direction_shares(route, left_share)
    out = np.zeros((2, 2))
    for j, region in enumerate(REGIONS):
        def blended(ws: str, rail: str, radius_m: float | None, region: str = region) -> float:
            tau = depot_measure(bogie, ws, rail, radius_m, region, "tau_max")
            gam = depot_measure(bogie, ws, rail, radius_m, region, "t_gamma")
            return (1.0 - blend) * tau + blend * gam * norm[region]

        p = analytic_wear_measure(route, side, blended, shares)
        out[:, j] = [p["leading"], p["trailing"]]
    return out


def _wheel_shape(y: Array, flange_mm2: float, tread_mm2: float, tread_centre: float,
                 flange_centre: float) -> Array:
    """True wear curve [mm]: a skewed tread hollow and a flange-face band, exact areas."""
    u = (_FINE_Y - tread_centre) / 18.0
    tread = np.where((_FINE_Y >= SPLIT_Y_MM) & (np.abs(u) < 1.6),
                     np.exp(-u * u) * (1.0 + 0.25 * np.tanh(2 * u)), 0.0)
    v = (_FINE_Y - flange_centre) / 4.5
    flange = np.where(_FINE_Y < SPLIT_Y_MM, np.exp(-v * v), 0.0)
    step = _FINE_Y[1] - _FINE_Y[0]
    w = tread * (tread_mm2 / max(tread.sum() * step, 1e-12)) \
        + flange * (flange_mm2 / max(flange.sum() * step, 1e-12))
    return np.interp(y, _FINE_Y, w)


def _daily_km(unit: DepotUnit, n_days: int, weekday0: int, rng: np.random.Generator) -> Array:
    weekday = (weekday0 + np.arange(n_days)) % 7
    km = unit.km_per_day * np.where(weekday >= 5, 0.55, 1.18) * rng.uniform(0.8, 1.2, n_days)
    km[rng.uniform(size=n_days) < 0.04] = 0.0                    # idle days
    for _ in range(int(rng.integers(1, 4))):                       # maintenance stops
        a = int(rng.integers(0, n_days))
        km[a:a + int(rng.integers(5, 16))] = 0.0
    return np.asarray(km)


def generate_depot_fleet(config: DepotConfig | None = None) -> DepotFleet:
    """Simulate the campaign (module docstring)."""
    cfg = config or DepotConfig()
    fx = cfg.effects
    rng = np.random.default_rng(cfg.seed)
    routes, attrs = depot_routes()
    table = depot_wear_table()
    start = np.datetime64(cfg.start, "D")
    day0 = int(start.astype(np.int64))
    n_days = cfg.days
    dates = start + np.arange(n_days).astype("timedelta64[D]")
    doy = np.array([(d - d.astype("datetime64[Y]")).astype(int) for d in dates], dtype=float)
    season = 1.0 + fx.seasonal * np.cos(2 * np.pi * (doy - fx.season_peak_day) / 365.25)
    # the T_gamma blend is normalised on the fleet's mean tau_max / T_gamma ratio per region
    norm: dict[str, float] = {}
    for j, region in enumerate(REGIONS):
        tau = [_position_measures(r, b, s, None, 0.0, {"flange": 1, "tread": 1})[0, j]
               for r in routes.values() for b in ("motor", "trailer") for s in ("left", "right")]
        gam = [_position_measures(r, b, s, None, 1.0, {"flange": 1, "tread": 1})[0, j]
               for r in routes.values() for b in ("motor", "trailer") for s in ("left", "right")]
        norm[region] = float(np.mean(tau) / max(np.mean(gam), 1e-12))
    k = np.array(cfg.k_mm2_per_km)
    weekday0 = int((day0 + 3) % 7)
    y_nom = np.arange(-69.5, 59.5, cfg.profile_step_mm)
    rows: list[dict[str, Any]] = []
    curves: list[Array] = []
    prof_rows: list[pd.DataFrame] = []
    for unit in cfg.units:
        km = _daily_km(unit, n_days, weekday0, rng)
        # direction of each day's trips: does axle 1 lead today?
        if unit.running_mode == "lead":
            axle1_leads = np.ones(n_days, dtype=bool)
        else:
            p = 0.5 if fx.leading_share is None else fx.leading_share
            axle1_leads = rng.uniform(size=n_days) < p
        visits = np.cumsum(rng.integers(20, 91, size=40))
        visits = visits[visits < n_days]
        instrument_of_visit = rng.choice(INSTRUMENTS, size=visits.size)
        for car in unit.cars:
            # duty roster: the car's route changes on a few random dates
            roster = np.full(n_days, car.routes[0], dtype=object)
            if len(car.routes) > 1:
                for cut in np.sort(rng.integers(60, n_days - 60, size=2)):
                    roster[cut:] = car.routes[int(rng.integers(0, len(car.routes)))]
            load = car.mean_load_t + rng.normal(0.0, 1.0, n_days)
            load_factor = (np.maximum(load, 5.0) / 14.0) ** fx.load_exponent
            v_factor = float(np.exp(rng.normal(0.0, cfg.vehicle_sd)))
            traction = fx.traction + (rng.normal(0.0, 0.03) if fx.traction != 1.0 else 0.0)
            bogies = ("motor", "trailer") if car.kind == "MT" else ("trailer", "trailer")
            for b_i, bogie in enumerate(bogies, start=1):
                for axle in (1, 2):
                    for side in ("left", "right"):
                        wheel_id = f"{car.car_id}.{b_i}{axle}{side[0]}"
                        w_factor = float(np.exp(cfg.wheel_sd * rng.standard_t(4)))
                        pm = {r: _position_measures(routes[r], bogie, side, fx.left_share,
                                                    fx.measure_blend, norm)
                              for r in set(roster)}
                        leads = axle1_leads if axle == 1 else ~axle1_leads
                        p_day = np.array([pm[r][0 if ld else 1] for r, ld in
                                          zip(roster, leads, strict=True)])   # (days, 2)
                        rate = k[None, :] * p_day * km[:, None] * w_factor * v_factor
                        rate = rate * (season * load_factor)[:, None]
                        if bogie == "motor":
                            rate[:, 1] *= traction
                        greased = np.array([attrs[r]["flange_lubrication"] == "yes"
                                            for r in roster])
                        works = rng.uniform(size=n_days) < 0.9
                        rate[:, 0] *= np.where(greased & works, fx.greased_flange, 1.0)
                        rows_w, curves_w, prof_w = _measure_wheel(
                            cfg, rng, unit, car, bogie, axle, side, wheel_id, rate, km, roster,
                            visits, instrument_of_visit, dates, load, y_nom)
                        rows += rows_w
                        curves += curves_w
                        prof_rows += prof_w
    meas = pd.DataFrame(rows)
    return DepotFleet(meas, np.vstack(curves),
                      pd.concat(prof_rows, ignore_index=True) if prof_rows else None,
                      routes, attrs, table)


def _measure_wheel(cfg: DepotConfig, rng: np.random.Generator, unit: DepotUnit, car: DepotCar,
                   bogie: str, axle: int, side: str, wheel_id: str, rate: Array, km: Array,
                   roster: NDArray[Any], visits: NDArray[np.integer[Any]],
                   instruments: NDArray[Any], dates: NDArray[Any], load: Array,
                   y_nom: Array) -> tuple[list[dict[str, Any]], list[Array], list[pd.DataFrame]]:
    fx = cfg.effects
    rows: list[dict[str, Any]] = []
    curves: list[Array] = []
    profs: list[pd.DataFrame] = []
    last = 0                       # day of the last reprofiling (the campaign starts new)
    tread_c = rng.uniform(0.0, 8.0)
    flange_c = rng.uniform(-40.0, -36.0)
    for v_i, day in enumerate(visits):
        seg = slice(last, int(day))
        s_day = np.cumsum(km[seg])
        harden = (np.maximum(s_day, 2000.0) / 60_000.0) ** (fx.hardening - 1.0)
        area = np.sum(rate[seg] * harden[:, None], axis=0)
        mileage = float(np.round(s_day[-1] if s_day.size else 0.0, -1))
        if rng.uniform() >= cfg.missed_visit:
            repeats = 2 if rng.uniform() < cfg.repeated else 1
            for _ in range(repeats):
                inst = str(instruments[v_i])
                meta = {"wheel_id": wheel_id, "vehicle_id": car.car_id, "unit": unit.unit_id,
                        "bogie_type": bogie, "axle": axle, "side": side,
                        "mileage_km": mileage, "measured_on": str(dates[int(day)]),
                        "route": str(roster[int(day) - 1]), "running_mode": unit.running_mode,
                        "instrument_id": inst,
                        "load_t": round(float(np.mean(load[seg])) if s_day.size else 14.0, 2),
                        "true_flange_area_mm2": float(area[0]),
                        "true_tread_area_mm2": float(area[1])}
                if cfg.profiles:
                    fa, ta, curve, prof = _measured_profile(cfg, rng, inst, area, tread_c,
                                                            flange_c, y_nom)
                    meta.update(flange_area_mm2=fa, tread_area_mm2=ta)
                    curves.append(curve)
                    profs.append(prof.assign(wheel_id=wheel_id, mileage_km=mileage,
                                             measured_on=str(meta["measured_on"])))
                else:
                    noise = (0.25 + 0.03 * area) * rng.standard_t(3, size=2)
                    fa, ta = (float(max(area[j] + noise[j], 0.0)) for j in range(2))
                    meta.update(flange_area_mm2=fa, tread_area_mm2=ta)
                    curves.append(_wheel_shape(DEFAULT_GRID_Y_MM, fa, ta, tread_c, flange_c))
                rows.append(meta)
        if area[0] > 70.0 or area[1] > 90.0 or rng.uniform() < 0.01:
            last = int(day)            # turned at this visit: a new life starts
            tread_c = rng.uniform(0.0, 8.0)
    return rows, curves, profs


def _measured_profile(cfg: DepotConfig, rng: np.random.Generator, instrument: str,
                      area: Array, tread_c: float, flange_c: float, y_nom: Array
                      ) -> tuple[float, float, Array, pd.DataFrame]:
    fx = cfg.effects
    y = y_nom + rng.uniform(-0.05, 0.05, y_nom.size)
    z = s1002_height_mm(y) - _wheel_shape(y, float(area[0]), float(area[1]), tread_c, flange_c)
    sigma = {"DP-A": 0.008, "DP-B": 0.012, "DP-C": 0.018}[instrument]
    z = z + sigma * rng.standard_t(3, size=y.size)
    spikes = rng.uniform(size=y.size) < 0.002
    z = np.where(spikes, z + rng.normal(0.0, 0.3, y.size), z)
    if fx.instrument_scale is not None and fx.instrument_scale[0] == instrument:
        y = y + fx.instrument_scale[1] * (y + 70.0)
    ang = rng.uniform(-1.5e-3, 1.5e-3)
    yy = y - 60.0
    y = np.cos(ang) * yy - np.sin(ang) * z + 60.0 + rng.uniform(-0.4, 0.4)
    z = np.sin(ang) * yy + np.cos(ang) * z + rng.uniform(-0.08, 0.08)
    p = process_profile(y, z)
    prof = pd.DataFrame({"y_mm": np.round(y, 3), "z_mm": np.round(z, 3),
                         "instrument_id": instrument})
    return (float(p.areas.flange_mm2), float(p.areas.tread_mm2),
            np.nan_to_num(p.wear_mm, nan=0.0), prof)
