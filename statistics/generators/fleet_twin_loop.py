"""Fleet twin with the wear loop as its truth (issue 5): measured profiles whose wear-curve
shapes and areas over mileage come from :func:`wearcast.physics.wear_loop.simulate_wear`.

:mod:`wearcast.statistics.generators.fleet_twin` makes its truth from the hybrid model itself
(wear areas c_s P s and a family of hand-made shapes); a twin made that way cannot show what
the hybrid model gets wrong. This module keeps the twin's fleet layout, scatter, effect hooks and
measurement model (misalignment, noise normal to the surface, long-CSV frames), and replaces
the truth by the contact-mechanics route the seeds use:

1. One loop run per (route, bogie type, axle, side) -- fixed steps up to the largest mileage of
   the fleet times ``mileage_scale`` (vehicle preset per bogie type, curve classes of the
   unit's route, the tracked wheel ``axle``/``side``). ``running_mode = "mixed"`` averages the
   wear curves of the axle-1 and axle-2 runs of the same side (each axle leads half the
   distance; both loop runs are the leading/trailing positions of the quasi-static bogie).
2. A wheel's per-wheel log-normal rate factor f (``FleetConfig.rate_scatter``) scales its
   mileage: the true wear curve at s is the loop's w(f s * mileage_scale) (its shape evolves
   with the worn amount, as in the loop).
3. Region areas (tread y >= split, flange y < split) of that curve form the wear history;
   ``FleetConfig.wear_effects`` act on it, and each region of the curve is rescaled to the
   effected area (shape kept), with the per-measurement area scatter.
4. Worn profile = S1002 - w on MiniProf-like arc-length samples; the twin's
   ``measure_profile`` and ``profile_effects`` make the measured points.

``mileage_scale`` exists because the quasi-static contact with the KTH map wears sharp-curve
flanges much faster than measured wheels do (see ``benchmarks/reproduce_seeds.py`` and the
report of issue 5): it maps fleet mileage to loop mileage, with 1.0 meaning "as simulated".
Pure: numpy/pandas in and out, deterministic for a given seed.
"""

from __future__ import annotations

from collections.abc import Mapping, MutableMapping
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.profiles.parameters import flange_parameters
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vehicles import vehicle_preset
from wearcast.physics.vocabulary import CurveClass, Direction
from wearcast.physics.wear_laws import WearLaw
from wearcast.physics.wear_loop import WearSimulation, WearSteps, simulate_wear
from wearcast.statistics.generators.fleet_twin import (
    FleetConfig,
    FleetTwin,
    TwinRoute,
    WearHistory,
    WheelSpec,
    arc_length_samples,
    fleet_wheels,
    measure_profile,
    profile_rows,
)

Array = NDArray[np.float64]


@dataclass(frozen=True)
class LoopTruth:
    """How the loop makes the truth.

    vehicles : vehicle preset per bogie type (``physics.vehicles``)
    law : wear law name or WearLaw
    n_steps : fixed loop steps up to the largest (scaled) mileage
    mileage_scale : loop km per fleet km [-]
    loop : further keyword arguments of ``simulate_wear`` (smoothing, application, ...)
    """

    vehicles: Mapping[str, str] = field(
        default_factory=lambda: {"motor": "metro_b", "trailer": "metro_b"})
    law: str | WearLaw = "archard_kth"
    n_steps: int = 6
    mileage_scale: float = 1.0
    loop: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.n_steps < 1 or not self.mileage_scale > 0:
            raise ValueError("n_steps must be >= 1 and mileage_scale > 0")


@dataclass(frozen=True)
class LoopFleetTwin:
    """The generated fleet (``fleet``: profiles, truth, wheels) and the loop runs behind it,
    keyed by (route name, bogie type, axle, side)."""

    fleet: FleetTwin
    simulations: Mapping[tuple[str, str, int, str], WearSimulation]


def _loop_classes(route: TwinRoute) -> list[CurveClass]:
    return [CurveClass(c.radius_m, c.cant_mm, c.speed_kmh, cast(Direction, c.direction or "left"),
                       c.share)
            for c in route.classes]


def _region_areas(y: Array, w: Array, split_y_mm: float) -> tuple[float, float]:
    tread = y >= split_y_mm
    return float(np.trapezoid(w[tread], y[tread])), float(np.trapezoid(w[~tread], y[~tread]))


def _curve(sims: list[WearSimulation], loop_km: float) -> Array:
    return np.mean([s.wear_at(min(loop_km, s.mileage_km[-1])) for s in sims], axis=0)


def generate_loop_fleet(config: FleetConfig, truth: LoopTruth = LoopTruth(),
                        max_rate_factor: float = 1.5,
                        cache: MutableMapping[Any, WearSimulation] | None = None
                        ) -> LoopFleetTwin:
    """Generate the fleet of ``config`` with the wear loop as truth (module docstring).

    Parameters
    ----------
    config : fleet layout, mileages, scatter, noise, seed and effect hooks (the twin's)
    truth : vehicles, law, steps and mileage scale of the loop
    max_rate_factor : the loop runs to the largest mileage times this (rate factors above it
        are clipped; with rate_scatter 0.1 a factor above 1.5 has probability 5e-5)
    cache : optional dict shared by several calls (e.g. the seeds of a benchmark) that keeps
        each loop run keyed by everything it depends on (the truth, the step length, the
        route's curve classes, bogie type, axle, side); a loop run is deterministic, so the
        fleets are identical with and without it

    Returns
    -------
    LoopFleetTwin: ``fleet.profiles`` in the long-CSV format, ``fleet.truth`` one row per
    measurement (true areas [mm^2], Sd/Sh/qR [mm] of the true profile, loop mileage [km])
    """
    rng = np.random.default_rng(config.seed)
    top_km = (max(config.mileages_km) + config.mileage_jitter_km) * truth.mileage_scale \
        * max_rate_factor
    steps = WearSteps(mode="fixed", n_steps=truth.n_steps, step_km=top_km / truth.n_steps)
    sims: dict[tuple[str, str, int, str], WearSimulation] = {}

    def run(route: TwinRoute, bogie: str, axle: int, side: str) -> WearSimulation:
        key = (route.name, bogie, axle, side)
        if key not in sims:
            if bogie not in truth.vehicles:
                raise ValueError(f"truth.vehicles: no vehicle preset for bogie type {bogie!r}")
            shared = (repr(truth), steps.step_km, truth.n_steps, route.classes, bogie, axle,
                      side)
            if cache is not None and shared in cache:
                sims[key] = cache[shared]
            else:
                sims[key] = simulate_wear(vehicle_preset(truth.vehicles[bogie], bogie),
                                          _loop_classes(route), law=truth.law, steps=steps,
                                          axle=axle, side=side, **dict(truth.loop))
                if cache is not None:
                    cache[shared] = sims[key]
        return sims[key]

    y_nominal = arc_length_samples(config.points_per_profile)
    profiles, truths, wheels = [], [], []
    units = {u.unit_id: u for u in config.units}
    for wheel in fleet_wheels(config):
        unit = units[wheel.unit_id]
        axles = (1, 2) if unit.running_mode == "mixed" else (wheel.axle,)
        loop = [run(unit.route, wheel.bogie_type, a, wheel.side) for a in axles]
        factor = float(np.clip(np.exp(rng.normal(0.0, config.rate_scatter)),
                               0.0, max_rate_factor))
        rows, truth_rows = _wheel_rows(config, truth, wheel, unit, loop, factor,
                                       y_nominal, rng)
        wheels.append(wheel)
        profiles.append(rows)
        truths.append(truth_rows)
    fleet = FleetTwin(pd.concat(profiles, ignore_index=True),
                      pd.concat(truths, ignore_index=True), tuple(wheels))
    return LoopFleetTwin(fleet=fleet, simulations=sims)


def _wheel_rows(config: FleetConfig, truth: LoopTruth, wheel: WheelSpec, unit: Any,
                loop: list[WearSimulation], factor: float, y_nominal: Array,
                rng: np.random.Generator) -> tuple[pd.DataFrame, pd.DataFrame]:
    mileage = np.asarray(config.mileages_km, dtype=float)
    mileage = np.round(np.maximum(mileage + rng.uniform(-1, 1, mileage.size)
                                  * config.mileage_jitter_km, 0.0), -1)
    mileage = np.maximum.accumulate(mileage)
    days = np.round(mileage / unit.km_per_day).astype(int)
    measured_on = np.datetime64(unit.start_date, "D") + days.astype("timedelta64[D]")
    y_loop = loop[0].y_mm
    loop_km = mileage * factor * truth.mileage_scale
    curves = np.array([_curve(loop, km) for km in loop_km])
    areas = np.array([_region_areas(y_loop, w, config.split_y_mm) for w in curves])
    history = WearHistory(mileage, measured_on, areas[:, 0].copy(), areas[:, 1].copy())
    for effect in config.wear_effects:
        history = effect(wheel, history)
    tread_mask = y_loop >= config.split_y_mm
    frames, rows = [], []
    for i, km in enumerate(history.mileage_km):
        scatter = np.exp(rng.normal(0.0, config.area_scatter, 2))
        target = np.array([history.tread_area_mm2[i], history.flange_area_mm2[i]]) * scatter
        scale = np.where(areas[i] > 0, target / np.where(areas[i] > 0, areas[i], 1.0), 0.0)
        w = curves[i] * np.where(tread_mask, scale[0], scale[1])
        z_true_loop = s1002_height_mm(y_loop) - w
        params = flange_parameters(y_loop, z_true_loop)  # EN 15313, as the loop
        z_true = s1002_height_mm(y_nominal) - np.interp(y_nominal, y_loop, w)
        y, z = measure_profile(config, y_nominal, z_true, rng)
        for profile_effect in config.profile_effects:
            y, z = profile_effect(wheel, float(km), y, z)
        frames.append(profile_rows(config, wheel, float(km), str(history.measured_on[i]), y, z))
        a_tread, a_flange = _region_areas(y_loop, w, config.split_y_mm)
        rows.append({
            "wheel_id": wheel.wheel_id, "vehicle_id": wheel.vehicle_id,
            "unit_id": wheel.unit_id, "bogie_type": wheel.bogie_type, "axle": wheel.axle,
            "side": wheel.side, "route_id": wheel.route.name,
            "running_mode": wheel.running_mode, "mileage_km": float(km),
            "measured_on": str(history.measured_on[i]), "loop_mileage_km": float(loop_km[i]),
            "rate_factor": factor, "tread_area_mm2": a_tread, "flange_area_mm2": a_flange,
            "max_depth_mm": float(w.max()), "sd_mm": params.sd_mm, "sh_mm": params.sh_mm,
            "qr_mm": params.qr_mm})
    return pd.concat(frames, ignore_index=True), pd.DataFrame(rows)
