"""Fleet twin: a generator of realistic wheel-profile measurements that obey the hybrid model.

The twin produces what a fleet's MiniProf campaign would deliver — one measured profile per
(wheel, mileage) in the long-CSV import format of docs/conventions.md — but from a known truth, so
that
the statistical core can be tested against it and the discrepancy finder can later be shown
effects it has to find.

How a profile is made (all lengths in mm, mileage in km):

1. **Wear measure of the wheel's route** (seed 001 eq. 2): P = sum_i c_i P_i over the route's
   curve classes, P_i read from a curve-radius table (docs/conventions.md "Curve-radius table CSV")
   for the wheel's bogie
   type, wheelset position (axle 1 leads in ``lead`` mode; ``mixed`` = half leading, half
   trailing), rail (high/low from the wheel's side and the curve's direction, tangent for
   straight track) and region; radii between table rows are interpolated linearly in
   curvature 1/R, wide curves beyond the last row towards the tangent value at 1/R = 0.
2. **Wear area** per region (seed 001 eqs. 3–4 read backwards): A(s) = c_s P s, times a
   per-wheel log-normal rate scatter and a small per-measurement scatter; optionally a power
   law A = c_s P s_ref (s / s_ref)^p for a nonlinear progression.
3. **Effects** (hooks for the discrepancy finder): each ``WearEffect`` maps a wheel's wear
   history (mileages, dates, areas) to a modified one, each ``ProfileEffect`` modifies the
   measured points of one profile (e.g. an instrument's systematic error).
4. **Wear-curve shape** for that area from a family of realistic shapes. Tread: hollow wear,
   a main bump around y = +4 mm and a smaller one around y = -12 mm (seed 001 Fig. 6/9 shows
   worn curves with two maxima), widening as wear grows. Flange: the flange face is thinned
   horizontally by a smooth bump d(y) on -52 < y < -30 (peak near y = -41), which moves the
   Sd point inwards by about d; the vertical wear curve is w = z_ref(y) - z_ref(y + d(y)).
   Wear of the tread lies entirely in y >= split and of the flange entirely in y < split, so
   each region's area is exact.
5. **Worn profile** = S1002 - w, sampled at ``points_per_profile`` points evenly spaced in arc
   length from the flange back (y = -70) to the field side (y = +60) like a MiniProf trace,
   then moved by a small rigid misalignment (lateral, vertical shift and rotation about the
   tape-circle point) and perturbed by measurement noise normal to the surface.

Everything is pure (numpy/pandas in and out, no I/O) and deterministic for a given seed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.profiles.s1002 import S1002_Y_MAX_MM, S1002_Y_MIN_MM, s1002_height_mm
from wearcast.physics.vocabulary import REGIONS, WEAR_MEASURES, Region
from wearcast.statistics.route_measure import weighted_wear_measure
from wearcast.statistics.routes import Route, RouteClass
from wearcast.statistics.wear_tables import TABLE_COLUMNS, compile_wear_table

Array = NDArray[np.float64]

#: The twin draws its random numbers and writes its table rows region by region in this order
#: (tread first); kept so that seeded fleets and the bundled example fleet stay the same.
TWIN_REGION_ORDER: tuple[Region, ...] = REGIONS[::-1]
WEAR_TABLE_COLUMNS = list(TABLE_COLUMNS)
PROFILE_COLUMNS = [
    "wheel_id", "vehicle_id", "bogie_type", "axle", "side", "mileage_km", "y_mm", "z_mm",
    "measured_on", "route_id", "running_mode", "instrument_id", "load_t",
]

# Fine lateral grid on which wear curves are built and areas integrated [mm].
_FINE_STEP_MM = 0.02
_FINE_Y_MM = np.linspace(S1002_Y_MIN_MM, S1002_Y_MAX_MM,
                         int(round((S1002_Y_MAX_MM - S1002_Y_MIN_MM) / _FINE_STEP_MM)) + 1)


# --------------------------------------------------------------------------------------------
# Routes
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class TwinRoute(Route):
    """A route (curve classes with shares summing to 1) plus free attributes."""

    attributes: Mapping[str, object] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        """The ``POST /v1/routes`` body for this route."""
        return {**self.to_dict(), "attributes": dict(self.attributes)}


def _split_directions(radius_m: float | None, cant_mm: float, speed_kmh: float,
                      share: float) -> list[RouteClass]:
    if radius_m is None:
        return [RouteClass(None, None, 0.0, speed_kmh, share)]
    return [RouteClass(radius_m, d, cant_mm, speed_kmh, share / 2.0) for d in ("left", "right")]


# Seed 003 (003_c55c21cb74d435ad), Table 3: Aosta – Pré-Saint-Didier line, statistical track
# description with n_class = 7, N_c = 20 curve tracks. Columns: representative radius R_c [m]
# (None = tangent, "inf" in the paper), superelevation H [mm], speed V [km/h], share p_k [%].
AOSTA_TABLE3 = (
    (162.0, 110.0, 57.0, 0.93), (162.0, 131.0, 60.0, 1.30),
    (195.0, 90.0, 60.0, 7.09), (195.0, 103.0, 60.0, 7.42), (195.0, 126.0, 60.0, 5.48),
    (237.0, 70.0, 60.0, 0.87), (237.0, 83.0, 60.0, 8.76), (237.0, 109.0, 60.0, 4.63),
    (237.0, 120.0, 60.0, 0.47),
    (293.0, 50.0, 60.0, 0.28), (293.0, 65.0, 60.0, 3.05), (293.0, 83.0, 60.0, 0.90),
    (293.0, 100.0, 60.0, 0.31),
    (376.0, 49.0, 60.0, 1.13), (376.0, 62.0, 60.0, 1.26),
    (774.0, 24.0, 60.0, 1.73), (774.0, 40.0, 60.0, 0.42),
    (3572.0, 5.0, 60.0, 2.40), (3572.0, 20.0, 60.0, 0.91),
    (None, 0.0, 130.0, 50.65),
)

# Seed 000 (000_67a233c1b13bf7f0), Table 1: track conditions of metro lines 1 and 2 (type B
# vehicle): radius band [m], share of track length [%], running speed [km/h].
METRO_TABLE1 = (
    (1200.0, math.inf, 75.0, 70.0),
    (800.0, 1200.0, 11.0, 70.0),
    (600.0, 800.0, 11.0, 60.0),
    (350.0, 600.0, 3.0, 40.0),
)


def aosta_route(name: str = "aosta") -> TwinRoute:
    """The Aosta – Pré-Saint-Didier line as 39 curve classes (seed 003 Table 3).

    Each of the 19 curved classes is split into equal left- and right-hand halves (the table
    gives no direction); shares are the printed p_k [%] normalised to sum to 1 (they sum to
    99.99 % as printed).
    """
    total = sum(row[3] for row in AOSTA_TABLE3)
    classes: list[RouteClass] = []
    for radius_m, cant_mm, speed_kmh, share_pct in AOSTA_TABLE3:
        classes += _split_directions(radius_m, cant_mm, speed_kmh, share_pct / total)
    return TwinRoute(name, tuple(classes), {
        "source": "seed 003 Table 3 (Aosta - Pre Saint Didier, n_class=7)",
        "line_type": "regional, mountain", "flange_lubrication": False,
    })


def metro_route(name: str = "metro", max_cant_mm: float = 120.0) -> TwinRoute:
    """Metro lines 1/2 of seed 000 Table 1 as curve classes.

    The band R > 1200 m (75 %) is taken as tangent track; each other band is represented by
    its mid radius. Cant is not printed: it is set to the equilibrium cant
    11.8 V^2 / R [mm] (V km/h, R m, standard gauge), capped at ``max_cant_mm``. Curves are
    split into equal left and right halves (the lines are built of S-curves, seed 000 §V).
    """
    classes: list[RouteClass] = []
    for r_min, r_max, share_pct, speed_kmh in METRO_TABLE1:
        if math.isinf(r_max):
            classes += _split_directions(None, 0.0, speed_kmh, share_pct / 100.0)
            continue
        radius_m = 0.5 * (r_min + r_max)
        cant_mm = min(max_cant_mm, round(11.8 * speed_kmh**2 / radius_m))
        classes += _split_directions(radius_m, float(cant_mm), speed_kmh, share_pct / 100.0)
    return TwinRoute(name, tuple(classes), {
        "source": "seed 000 Table 1 (metro lines 1 and 2, type B vehicle)",
        "line_type": "metro", "flange_lubrication": False,
    })


def tangent_route(name: str = "tangent", speed_kmh: float = 100.0) -> TwinRoute:
    """100 % tangent track (the application example of seed 001 Fig. 15)."""
    return TwinRoute(name, (RouteClass(None, None, 0.0, speed_kmh, 1.0),),
                     {"source": "seed 001 Fig. 15 (100 % tangent track)", "line_type": "tangent"})


# --------------------------------------------------------------------------------------------
# Curve-radius table and weighted wear measure
# --------------------------------------------------------------------------------------------

def synthetic_wear_table(radii_m: Sequence[float] = (150, 200, 250, 300, 400, 500, 700, 1000,
                                                     1500, 2000, 3000)) -> pd.DataFrame:
    """A smooth, synthetic curve-radius table in the docs/conventions.md CSV format.

    Stand-in for the physics core's tables; follows seed 001 Fig. 10 qualitatively:

    - flange: zero on tangent track and in wide curves; on the leading wheelset's high-rail
      wheel it rises from curvature 1/1500 m^-1 and grows fast as the radius falls
      (P ~ (kappa - kappa0)^1.3); the trailing wheelset's high-rail wheel flanges only below
      ~400 m and far less; low-rail wheels never flange.
    - tread: nonzero on tangent track, rising moderately with curvature, more on the low rail
      (longitudinal creep) than on the high rail.
    - motor bogies carry a higher T_gamma than trailer bogies (x1.8 in curves, x1.3 on
      tangent: traction creep and stiffer steering), tau_max is similar (x1.05).

    Units: tau_max [MPa] (maximum surface shear traction), t_gamma [N] (wear number).
    Returns a DataFrame with columns ``WEAR_TABLE_COLUMNS``; tangent rows have radius_m NaN.
    """
    rows: list[tuple[object, ...]] = []
    kappa = 1.0 / np.asarray(radii_m, dtype=float)  # [1/m]
    for bogie in ("motor", "trailer"):
        for wheelset in ("leading", "trailing"):
            for measure in WEAR_MEASURES:
                tangent = _synthetic_values(bogie, wheelset, "tangent", np.zeros(1), measure)
                for region in TWIN_REGION_ORDER:
                    rows.append((bogie, wheelset, "tangent", np.nan, region, measure,
                                 float(tangent[region][0])))
                for rail in ("high", "low"):
                    values = _synthetic_values(bogie, wheelset, rail, kappa, measure)
                    for region in TWIN_REGION_ORDER:
                        for r, v in zip(radii_m, values[region], strict=True):
                            rows.append((bogie, wheelset, rail, float(r), region, measure,
                                         round(float(v), 4)))
    return pd.DataFrame(rows, columns=WEAR_TABLE_COLUMNS)


def _synthetic_values(bogie: str, wheelset: str, rail: str, kappa: Array,
                      measure: str) -> dict[str, Array]:
    """Smooth synthetic wear measures vs curvature kappa [1/m] (see ``synthetic_wear_table``)."""
    k = kappa * 1000.0  # curvature in 1/km: 6.67 at R = 150 m
    leading = wheelset == "leading"
    if measure == "tau_max":  # [MPa]
        tread0, tread_slope, flange_scale = 180.0, 22.0, 110.0
        motor_curve, motor_tangent = 1.05, 1.05
    else:  # t_gamma [N]
        tread0, tread_slope, flange_scale = 25.0, 14.0, 90.0
        motor_curve, motor_tangent = 1.8, 1.3
    tread = tread0 + tread_slope * k * (1.25 if rail == "low" else 1.0 if rail == "high" else 0.0)
    if not leading:
        tread = tread0 + 0.8 * (tread - tread0)
    if rail == "high":
        k0 = 1000.0 / 1500.0 if leading else 1000.0 / 400.0
        scale = flange_scale if leading else 0.25 * flange_scale
        flange = scale * np.clip(k - k0, 0.0, None) ** 1.3
    else:
        flange = np.zeros_like(k)
    if bogie == "motor":
        factor = np.where(k > 0, motor_curve, motor_tangent)
        tread = tread * factor
        flange = flange * factor
    return {"tread": np.asarray(tread, dtype=float), "flange": np.asarray(flange, dtype=float)}


# --------------------------------------------------------------------------------------------
# Wear-curve shapes
# --------------------------------------------------------------------------------------------

def _hann(u: Array) -> Array:
    """Raised-cosine bump, 1 at u = 0, 0 for |u| >= 1."""
    return np.where(np.abs(u) < 1.0, 0.5 * (1.0 + np.cos(np.pi * np.clip(u, -1.0, 1.0))), 0.0)


def tread_wear_curve(y_mm: Array, area_mm2: float, centre_shift_mm: float = 0.0,
                     split_y_mm: float = -30.0) -> Array:
    """Hollow tread wear w(y) [mm] with exactly ``area_mm2`` over y >= split.

    A main bump at y = 4 + shift (half-width 20..28 mm, widening with wear) and a secondary
    bump at y = -12 + shift (half-width 9 mm, 35 % weight): seed 001 Fig. 6/9 (two maxima).
    Support is clipped to y in (split, +45) so that no tread wear leaks into the flange region.
    """
    y = np.asarray(y_mm, dtype=float)
    if area_mm2 <= 0.0:
        return np.zeros_like(y)
    half_width = 20.0 + 8.0 * np.tanh(area_mm2 / 80.0)
    shape = _hann((y - 4.0 - centre_shift_mm) / half_width)
    shape = shape + 0.35 * _hann((y + 12.0 - centre_shift_mm) / 9.0)
    shape = np.where((y > split_y_mm + 1.0) & (y < 45.0), shape, 0.0)
    fine = np.where((_FINE_Y_MM > split_y_mm + 1.0) & (_FINE_Y_MM < 45.0),
                    _hann((_FINE_Y_MM - 4.0 - centre_shift_mm) / half_width)
                    + 0.35 * _hann((_FINE_Y_MM + 12.0 - centre_shift_mm) / 9.0), 0.0)
    norm = float(np.trapezoid(fine, _FINE_Y_MM))
    return area_mm2 * shape / norm


def _flange_thinning(y: Array, amplitude_mm: Array | float, centre_mm: float) -> Array:
    # Half-width grows with amplitude so that 1 + d'(y) > 0 (the face stays a function of y).
    amplitude = np.asarray(amplitude_mm, dtype=float)
    half_width = 10.0 + 0.6 * amplitude
    return amplitude * _hann((y - centre_mm) / half_width)


def _flange_curve_from_amplitude(y: Array, amplitude_mm: Array | float, centre_mm: float,
                                 split_y_mm: float) -> Array:
    d = _flange_thinning(y, amplitude_mm, centre_mm)
    w = s1002_height_mm(y) - s1002_height_mm(np.clip(y + d, S1002_Y_MIN_MM, S1002_Y_MAX_MM))
    return np.where((y < split_y_mm) & (y > -55.0), np.clip(w, 0.0, None), 0.0)


_FLANGE_AMPLITUDES_MM = np.linspace(0.0, 9.0, 181)
_FLANGE_AREA_CACHE: dict[tuple[float, float], Array] = {}


def _flange_area_table(centre_mm: float, split_y_mm: float) -> Array:
    key = (round(centre_mm, 3), split_y_mm)
    if key not in _FLANGE_AREA_CACHE:
        mask = (_FINE_Y_MM > -56.0) & (_FINE_Y_MM < split_y_mm + 0.5)
        y = _FINE_Y_MM[mask]
        curves = _flange_curve_from_amplitude(y[None, :], _FLANGE_AMPLITUDES_MM[:, None],
                                              centre_mm, split_y_mm)
        _FLANGE_AREA_CACHE[key] = np.asarray(np.trapezoid(curves, y, axis=1), dtype=float)
    return _FLANGE_AREA_CACHE[key]


def flange_thinning_for_area(area_mm2: float, centre_mm: float = -41.0,
                             split_y_mm: float = -30.0) -> float:
    """Peak horizontal flange-face thinning d_max [mm] that gives a flange wear area [mm^2].

    About equal to the loss of flange thickness Sd for the default centre.
    """
    areas = _flange_area_table(centre_mm, split_y_mm)
    if area_mm2 > areas[-1]:
        raise ValueError(f"flange wear area {area_mm2:.1f} mm^2 exceeds the shape family's "
                         f"maximum {areas[-1]:.1f} mm^2 (about 9 mm of flange thinning)")
    return float(np.interp(area_mm2, areas, _FLANGE_AMPLITUDES_MM))


def flange_wear_curve(y_mm: Array, area_mm2: float, centre_mm: float = -41.0,
                      split_y_mm: float = -30.0) -> Array:
    """Flange-face wear w(y) [mm] with ``area_mm2`` over y < split.

    The face is thinned horizontally by d(y) (raised cosine, peak near y = -41 mm), so
    w = z_ref(y) - z_ref(y + d(y)) with z_ref the S1002 profile.
    """
    y = np.asarray(y_mm, dtype=float)
    if area_mm2 <= 0.0:
        return np.zeros_like(y)
    amplitude = flange_thinning_for_area(area_mm2, centre_mm, split_y_mm)
    return _flange_curve_from_amplitude(y, amplitude, centre_mm, split_y_mm)


def flange_thinning_at_sd_mm(flange_area_mm2: float, centre_mm: float = -41.0,
               split_y_mm: float = -30.0) -> float:
    """Horizontal flange-face thinning [mm] at y = -37.5 mm for a flange wear area [mm^2].

    y = -37.5 mm is where S1002's Sd is read (10 mm above the tape circle). The Sd of the worn
    profile differs from 32.5 mm minus this thinning because tread wear lowers the tape-circle
    height and so raises the Sd measuring height (EN 15313 definition).
    """
    if flange_area_mm2 <= 0.0:
        return 0.0
    amplitude = flange_thinning_for_area(flange_area_mm2, centre_mm, split_y_mm)
    return float(_flange_thinning(np.asarray([-37.5]), amplitude, centre_mm)[0])


def worn_profile_mm(y_mm: Array, tread_area_mm2: float, flange_area_mm2: float,
                    tread_shift_mm: float = 0.0, flange_centre_mm: float = -41.0,
                    split_y_mm: float = -30.0) -> Array:
    """Worn profile z(y) = S1002(y) - w_tread(y) - w_flange(y) [mm]."""
    y = np.asarray(y_mm, dtype=float)
    return (s1002_height_mm(y) - tread_wear_curve(y, tread_area_mm2, tread_shift_mm, split_y_mm)
            - flange_wear_curve(y, flange_area_mm2, flange_centre_mm, split_y_mm))


def wear_areas_mm2(y_mm: Array, z_mm: Array, split_y_mm: float = -30.0) -> tuple[float, float]:
    """(tread, flange) wear areas [mm^2] of an *aligned* profile against S1002 by trapezoid rule.

    A plain integral for checks on generated data; the statistical core's processing does
    cleaning and alignment for real measurements.
    """
    y = np.asarray(y_mm, dtype=float)
    order = np.argsort(y)
    y, w = y[order], (s1002_height_mm(y) - np.asarray(z_mm, dtype=float))[order]
    tread = y >= split_y_mm
    return float(np.trapezoid(w[tread], y[tread])), float(np.trapezoid(w[~tread], y[~tread]))


# --------------------------------------------------------------------------------------------
# Fleet configuration and effects
# --------------------------------------------------------------------------------------------

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
    z = s1002_height_mm(_FINE_Y_MM)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(_FINE_Y_MM), np.diff(z)))])
    return np.interp(np.linspace(0.0, s[-1], n_points), s, _FINE_Y_MM)


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
