"""Fleet twin: a generator of realistic wheel-profile measurements that obey the hybrid model.

The twin produces what a fleet's MiniProf campaign would deliver — one measured profile per
(wheel, mileage) in the long-CSV import format of docs/conventions.md — but from a known
truth, so that the statistical core can be tested against it and the discrepancy finder can
later be shown effects it has to find.

How a profile is made (all lengths in mm, mileage in km):

1. **Wear measure of the wheel's route** (seed 001 eq. 2): P = sum_i c_i P_i over the route's
   curve classes (``twin_routes``), P_i read from a curve-radius table
   (``twin_wear_table.synthetic_wear_table`` by default) for the wheel's bogie type,
   wheelset position (axle 1 leads in ``lead`` mode; ``mixed`` = half leading, half
   trailing), rail (high/low from the wheel's side and the curve's direction, tangent for
   straight track) and region; radii between table rows are interpolated linearly in
   curvature 1/R, wide curves beyond the last row towards the tangent value at 1/R = 0.
2. **Wear area** per region (seed 001 eqs. 3–4 read backwards): A(s) = c_s P s, times a
   per-wheel log-normal rate scatter and a small per-measurement scatter; optionally a power
   law A = c_s P s_ref (s / s_ref)^p for a nonlinear progression.
3. **Effects** (hooks for the discrepancy finder): each ``WearEffect`` maps a wheel's wear
   history (mileages, dates, areas) to a modified one, each ``ProfileEffect`` modifies the
   measured points of one profile (e.g. an instrument's systematic error).
4. **Wear-curve shape** for that area from a family of realistic shapes
   (``twin_wear_curves``).
5. **Worn profile** = S1002 - w, sampled at ``points_per_profile`` points evenly spaced in arc
   length from the flange back (y = -70) to the field side (y = +60) like a MiniProf trace,
   then moved by a small rigid misalignment (lateral, vertical shift and rotation about the
   tape-circle point) and perturbed by measurement noise normal to the surface.

Everything is pure (numpy/pandas in and out, no I/O) and deterministic for a given seed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics.generators.twin_routes import TwinRoute, aosta_route, metro_route
from wearcast.statistics.generators.twin_wear_curves import (
    FINE_Y_MM,
    flange_thinning_at_sd_mm,
    worn_profile_mm,
)
from wearcast.statistics.generators.twin_wear_table import TWIN_REGION_ORDER, synthetic_wear_table
from wearcast.statistics.route_measure import weighted_wear_measure
from wearcast.statistics.wear_tables import compile_wear_table

Array = NDArray[np.float64]


PROFILE_COLUMNS = [
    "wheel_id", "vehicle_id", "bogie_type", "axle", "side", "mileage_km", "y_mm", "z_mm",
    "measured_on", "route_id", "running_mode", "instrument_id", "load_t",
]


@dataclass(frozen=True)
class UnitConfig:
    """One unit (train set) of the twin fleet.

    route : the route the unit runs on (one route per unit)
    vehicles : cars per unit; each car carries one bogie per entry of ``FleetConfig.bogies``
    running_mode : 'lead' or 'mixed' (seed 001 §4)
    start_date : ISO date of the first measurement's reprofiling (mileage 0)
    km_per_day : mean daily mileage [km/day], for ``measured_on``
    load_t : axle load or vehicle load column [t]; instrument_id : the MiniProf's id
    covariates : extra columns written on every row of this unit
    """

    unit_id: str
    route: TwinRoute
    vehicles: int = 1
    running_mode: str = "mixed"
    start_date: str = "2021-01-04"
    km_per_day: float = 550.0
    load_t: float = 14.0
    instrument_id: str = "MP-1"
    covariates: Mapping[str, object] = field(default_factory=dict)


@dataclass(frozen=True)
class WheelSpec:
    """A generated wheel and its true wear rates (handed to the effect hooks)."""

    wheel_id: str
    vehicle_id: str
    unit_id: str
    bogie_type: str
    axle: int
    side: str
    route: TwinRoute
    running_mode: str
    instrument_id: str
    load_t: float
    measure_p: Mapping[str, float]          # weighted wear measure P per region
    rate_mm2_per_km: Mapping[str, float]    # true wear rate per region, scatter included
    covariates: Mapping[str, object]


@dataclass(frozen=True)
class WearHistory:
    """A wheel's true wear areas at its measurement mileages."""

    mileage_km: Array
    measured_on: NDArray[np.datetime64]
    tread_area_mm2: Array
    flange_area_mm2: Array


#: Hook: modify a wheel's wear history (traction, direction, lubrication, load, season, ...).
WearEffect = Callable[[WheelSpec, WearHistory], WearHistory]
#: Hook: modify one measured profile's points (wheel, mileage_km, y_mm, z_mm) -> (y_mm, z_mm).
ProfileEffect = Callable[[WheelSpec, float, Array, Array], tuple[Array, Array]]


@dataclass(frozen=True)
class FleetConfig:
    """Everything the twin needs; defaults give a fleet with realistic magnitudes.

    calibration_factor : c_s per region [mm^2/km per unit of the wear measure] (seed 001
        eq. 3); with the synthetic table and tau_max a motor wheel on the Aosta route wears
        ~60 mm^2 of tread and loses ~3–4 mm of Sd in 200,000 km
    rate_scatter : sigma of the per-wheel log-normal rate factor [-]
    area_scatter : sigma of a per-measurement relative area scatter [-]
    progression_exponent : p in A = k s_ref (s/s_ref)^p (1 = linear, seed 001 §2.3)
    noise_mm : measurement noise normal to the surface [mm]
    lateral_mm, vertical_mm, rotation_rad : bounds of the uniform rigid misalignment
    """

    units: tuple[UnitConfig, ...]
    bogies: tuple[str, ...] = ("motor", "trailer")
    axles: tuple[int, ...] = (1, 2)
    sides: tuple[str, ...] = ("left", "right")
    mileages_km: tuple[float, ...] = (20_000, 50_000, 85_000, 120_000, 160_000, 200_000)
    mileage_jitter_km: float = 3_000.0
    measure: str = "tau_max"
    calibration_factor: Mapping[str, float] = field(
        default_factory=lambda: {"tread": 1.5e-6, "flange": 6.0e-6})
    rate_scatter: float = 0.10
    area_scatter: float = 0.03
    progression_exponent: float = 1.0
    reference_mileage_km: float = 100_000.0
    points_per_profile: int = 400
    noise_mm: float = 0.015
    lateral_mm: float = 0.3
    vertical_mm: float = 0.05
    rotation_rad: float = 1.0e-3
    split_y_mm: float = -30.0
    decimals: int = 3
    seed: int = 0
    wear_effects: tuple[WearEffect, ...] = ()
    profile_effects: tuple[ProfileEffect, ...] = ()


@dataclass(frozen=True)
class FleetTwin:
    """Generated fleet: long-CSV ``profiles``, per-measurement ``truth``, the ``wheels``."""

    profiles: pd.DataFrame
    truth: pd.DataFrame
    wheels: tuple[WheelSpec, ...]


def scale_rate(factor: float | Mapping[str, float],
               when: Callable[[WheelSpec], bool] = lambda wheel: True) -> WearEffect:
    """Effect: multiply the wear areas of the wheels selected by ``when`` by ``factor``.

    ``factor`` is one number or one per region, e.g. traction ``{"tread": 1.3}`` for motor
    bogies, lubrication ``{"flange": 0.4}`` on lubricated routes, load scaling by ``load_t``.
    """
    factors = factor if isinstance(factor, Mapping) else {r: float(factor) for r in REGIONS}

    def effect(wheel: WheelSpec, history: WearHistory) -> WearHistory:
        if not when(wheel):
            return history
        return replace(history,
                       tread_area_mm2=history.tread_area_mm2 * factors.get("tread", 1.0),
                       flange_area_mm2=history.flange_area_mm2 * factors.get("flange", 1.0))

    return effect


def seasonal_rate(amplitude: float, peak_day_of_year: int = 15) -> WearEffect:
    """Effect: wear rate varies with the season, k(t) = k (1 + a cos(2 pi (doy - peak)/365)).

    Area increments between consecutive measurements are rescaled by the season factor of
    the interval's days (the wheel's mileage is assumed uniform in time).
    """

    def effect(wheel: WheelSpec, history: WearHistory) -> WearHistory:
        days = history.measured_on.astype("datetime64[D]").astype(np.int64)  # since 1970
        span_km = float(history.mileage_km[-1] - history.mileage_km[0])
        km_per_day = span_km / max(int(days[-1] - days[0]), 1) if span_km > 0 else 500.0
        start = int(days[0] - round(history.mileage_km[0] / km_per_day))
        edges = np.concatenate([[start], days])
        factors = []
        for a, b in zip(edges[:-1], edges[1:], strict=True):
            day = np.arange(a, max(b, a + 1))
            doy = (day + 0.5) % 365.25  # 1970-01-01 is day-of-year 0
            factors.append(np.mean(1.0 + amplitude
                                   * np.cos(2 * np.pi * (doy - peak_day_of_year) / 365.25)))
        f = np.asarray(factors)

        def reweight(area: Array) -> Array:
            return np.cumsum(np.diff(np.concatenate([[0.0], area])) * f)

        return replace(history, tread_area_mm2=reweight(history.tread_area_mm2),
                       flange_area_mm2=reweight(history.flange_area_mm2))

    return effect


def lateral_scale_error(instrument_id: str, scale: float) -> ProfileEffect:
    """Profile effect: one instrument stretches y about the tape circle by ``scale``."""

    def effect(wheel: WheelSpec, mileage_km: float, y: Array, z: Array) -> tuple[Array, Array]:
        if wheel.instrument_id != instrument_id:
            return y, z
        return y * scale, z

    return effect


# --------------------------------------------------------------------------------------------
# Generator
# --------------------------------------------------------------------------------------------

def arc_length_samples(n_points: int) -> Array:
    """y positions [mm] evenly spaced in arc length along S1002 from y = -70 to +60."""
    z = s1002_height_mm(FINE_Y_MM)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(FINE_Y_MM), np.diff(z)))])
    return np.interp(np.linspace(0.0, s[-1], n_points), s, FINE_Y_MM)


def fleet_wheels(config: FleetConfig) -> Iterator[WheelSpec]:
    """Every wheel of the fleet's layout, unit by unit, vehicle, bogie, axle, side (the order
    the generators draw their random numbers in), with ``measure_p`` and ``rate_mm2_per_km``
    not yet known (NaN). Wheel ids read ``<vehicle>-<M|T><axle><L|R>``."""
    unknown: dict[str, float] = {r: math.nan for r in TWIN_REGION_ORDER}
    for unit in config.units:
        for v in range(1, unit.vehicles + 1):
            vehicle_id = f"{unit.unit_id}{v}"
            for bogie in config.bogies:
                for axle in config.axles:
                    for side in config.sides:
                        yield WheelSpec(
                            wheel_id=f"{vehicle_id}-{bogie[0].upper()}{axle}{side[0].upper()}",
                            vehicle_id=vehicle_id, unit_id=unit.unit_id, bogie_type=bogie,
                            axle=axle, side=side, route=unit.route,
                            running_mode=unit.running_mode, instrument_id=unit.instrument_id,
                            load_t=unit.load_t, measure_p=dict(unknown),
                            rate_mm2_per_km=dict(unknown), covariates=dict(unit.covariates))


def _wheels(config: FleetConfig, table: pd.DataFrame,
            rng: np.random.Generator) -> list[WheelSpec]:
    index = compile_wear_table(table)
    wheels: list[WheelSpec] = []
    for wheel in fleet_wheels(config):
        p: dict[str, float] = {r: weighted_wear_measure(
            wheel.route, index, bogie_type=wheel.bogie_type, axle=wheel.axle, side=wheel.side,
            running_mode=wheel.running_mode, region=r, measure=config.measure)
            for r in REGIONS}
        factor = float(np.exp(rng.normal(0.0, config.rate_scatter)))
        rate: dict[str, float] = {
            r: config.calibration_factor[r] * p[r] * factor for r in REGIONS}
        wheels.append(replace(wheel, measure_p=p, rate_mm2_per_km=rate))
    return wheels


def _history(config: FleetConfig, unit: UnitConfig, wheel: WheelSpec,
             rng: np.random.Generator) -> WearHistory:
    mileage = np.asarray(config.mileages_km, dtype=float)
    mileage = np.round(np.maximum(mileage + rng.uniform(-1, 1, mileage.size)
                                  * config.mileage_jitter_km, 0.0), -1)
    mileage = np.maximum.accumulate(mileage)
    days = np.round(mileage / unit.km_per_day).astype(int)
    measured_on = np.datetime64(unit.start_date, "D") + days.astype("timedelta64[D]")
    s_ref = config.reference_mileage_km
    progression = s_ref * (mileage / s_ref) ** config.progression_exponent
    areas = {}
    for region in TWIN_REGION_ORDER:
        noise = np.exp(rng.normal(0.0, config.area_scatter, mileage.size))
        areas[region] = wheel.rate_mm2_per_km[region] * progression * noise
    return WearHistory(mileage, measured_on, areas["tread"], areas["flange"])


def _unit_of(config: FleetConfig, wheel: WheelSpec) -> UnitConfig:
    return next(u for u in config.units if u.unit_id == wheel.unit_id)


def iter_fleet(config: FleetConfig, wear_table: pd.DataFrame | None = None
               ) -> Iterator[tuple[WheelSpec, pd.DataFrame, pd.DataFrame]]:
    """Generate the fleet wheel by wheel: yields (wheel, its long-CSV rows, its truth rows).

    Use for large fleets (stream to disk); ``generate_fleet`` concatenates the whole fleet.
    """
    table = synthetic_wear_table() if wear_table is None else wear_table
    rng = np.random.default_rng(config.seed)
    wheels = _wheels(config, table, rng)
    y_nominal = arc_length_samples(config.points_per_profile)
    for wheel in wheels:
        unit = _unit_of(config, wheel)
        history = _history(config, unit, wheel, rng)
        for effect in config.wear_effects:
            history = effect(wheel, history)
        tread_shift = float(rng.uniform(-2.0, 2.0))
        flange_centre = round(-41.0 + float(rng.uniform(-1.0, 1.0)), 1)
        frames, truth = [], []
        for i, mileage in enumerate(history.mileage_km):
            a_tread = float(history.tread_area_mm2[i])
            a_flange = float(history.flange_area_mm2[i])
            z_true = worn_profile_mm(y_nominal, a_tread, a_flange, tread_shift, flange_centre,
                                     config.split_y_mm)
            y, z = measure_profile(config, y_nominal, z_true, rng)
            for profile_effect in config.profile_effects:
                y, z = profile_effect(wheel, float(mileage), y, z)
            frames.append(profile_rows(config, wheel, float(mileage),
                                       str(history.measured_on[i]), y, z))
            truth.append({
                "wheel_id": wheel.wheel_id, "vehicle_id": wheel.vehicle_id,
                "unit_id": wheel.unit_id, "bogie_type": wheel.bogie_type, "axle": wheel.axle,
                "side": wheel.side, "route_id": wheel.route.name,
                "running_mode": wheel.running_mode, "mileage_km": float(mileage),
                "measured_on": str(history.measured_on[i]),
                "tread_area_mm2": a_tread, "flange_area_mm2": a_flange,
                "flange_thinning_mm": flange_thinning_at_sd_mm(a_flange, flange_centre,
                                                               config.split_y_mm),
                "p_tread": wheel.measure_p["tread"], "p_flange": wheel.measure_p["flange"],
                "rate_tread_mm2_per_km": wheel.rate_mm2_per_km["tread"],
                "rate_flange_mm2_per_km": wheel.rate_mm2_per_km["flange"],
            })
        yield wheel, pd.concat(frames, ignore_index=True), pd.DataFrame(truth)


def profile_rows(config: FleetConfig, wheel: WheelSpec, mileage_km: float, measured_on: str,
                 y_mm: Array, z_mm: Array) -> pd.DataFrame:
    """The long-CSV rows (``PROFILE_COLUMNS`` + the unit's covariates) of one measured
    profile, points rounded to ``config.decimals`` [mm]."""
    return pd.DataFrame({
        "wheel_id": wheel.wheel_id, "vehicle_id": wheel.vehicle_id,
        "bogie_type": wheel.bogie_type, "axle": wheel.axle, "side": wheel.side,
        "mileage_km": csv_number(mileage_km), "y_mm": np.round(y_mm, config.decimals),
        "z_mm": np.round(z_mm, config.decimals), "measured_on": measured_on,
        "route_id": wheel.route.name, "running_mode": wheel.running_mode,
        "instrument_id": wheel.instrument_id, "load_t": wheel.load_t, **wheel.covariates,
    })


def csv_number(value: float) -> float | int:
    """Whole numbers as int (shorter CSV), others unchanged."""
    return int(value) if float(value).is_integer() else float(value)


def measure_profile(config: FleetConfig, y: Array, z: Array,
                    rng: np.random.Generator) -> tuple[Array, Array]:
    """Measured points (y, z) [mm] of a true profile y, z [mm]: rigid misalignment about the
    tape-circle point plus noise normal to the surface (``config`` noise and misalignment)."""
    dy = np.gradient(y)
    dz = np.gradient(z)
    length = np.hypot(dy, dz)
    normal_y, normal_z = -dz / length, dy / length
    noise = rng.normal(0.0, config.noise_mm, y.size)
    y = y + noise * normal_y
    z = z + noise * normal_z
    angle = rng.uniform(-1, 1) * config.rotation_rad
    shift_y = rng.uniform(-1, 1) * config.lateral_mm
    shift_z = rng.uniform(-1, 1) * config.vertical_mm
    c, s = math.cos(angle), math.sin(angle)
    return c * y - s * z + shift_y, s * y + c * z + shift_z


def generate_fleet(config: FleetConfig, wear_table: pd.DataFrame | None = None) -> FleetTwin:
    """Generate the whole fleet (see the module docstring for the model).

    Parameters
    ----------
    config : the fleet (units, routes, bogies, axles, sides, mileages, scatter, noise, seed,
        effect hooks)
    wear_table : curve-radius table (docs/conventions.md "Curve-radius table CSV"); default
    ``synthetic_wear_table()``

    Returns
    -------
    FleetTwin with ``profiles`` (long CSV: ``PROFILE_COLUMNS`` + unit covariates; one
    measurement per (wheel_id, mileage_km)), ``truth`` (true wear areas [mm^2], flange
    thinning at the new profile's Sd point [mm], P and rates per measurement) and ``wheels``.
    """
    wheels, profiles, truths = [], [], []
    for wheel, rows, truth in iter_fleet(config, wear_table):
        wheels.append(wheel)
        profiles.append(rows)
        truths.append(truth)
    return FleetTwin(pd.concat(profiles, ignore_index=True),
                     pd.concat(truths, ignore_index=True), tuple(wheels))


def metro_calibration_config(seed: int = 7) -> FleetConfig:
    """A small fleet that calibrates a model on the metro line (seed 000 Table 1) exactly: one
    car in ``lead`` mode, measured at 30,000, 80,000 and 130,000 km, no rate or area scatter,
    0.005 mm noise, 300 points a profile."""
    return FleetConfig(
        units=(UnitConfig("B", metro_route(), vehicles=1, running_mode="lead"),),
        mileages_km=(30_000, 80_000, 130_000), mileage_jitter_km=0.0,
        calibration_factor={"tread": 1.5e-6, "flange": 6.0e-6}, rate_scatter=0.0,
        area_scatter=0.0, noise_mm=0.005, points_per_profile=300, seed=seed)


def example_fleet_config(seed: int = 20240601, points_per_profile: int = 400) -> FleetConfig:
    """The bundled example fleet (``service/example_fleet``).

    Unit A runs the Aosta line (seed 003 Table 3) in ``mixed`` mode, unit B the metro line of
    seed 000 Table 1 in ``lead`` mode; two cars per unit, each with a motor and a trailer
    bogie, axles 1–2, both sides: 32 wheels x 6 mileages up to ~200,000 km.
    """
    return FleetConfig(
        units=(
            UnitConfig("A", aosta_route(), vehicles=2, running_mode="mixed",
                       start_date="2021-03-01", km_per_day=520.0, load_t=14.5,
                       instrument_id="MP-A"),
            UnitConfig("B", metro_route(), vehicles=2, running_mode="lead",
                       start_date="2021-06-14", km_per_day=380.0, load_t=13.0,
                       instrument_id="MP-B"),
        ),
        points_per_profile=points_per_profile,
        seed=seed,
    )
