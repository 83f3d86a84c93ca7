"""The discrepancy finder on the loop-driven generator (``fleet_twin_loop``; slow).

The truth is the physics wear loop (``wearcast.physics.wear_loop``): one quasi-static loop run
of the metro_b vehicle per bogie type, axle and side on one track geometry (tangent and 500 m
curves), each wheel's wear curve the loop's at its own mileage times its rate factor, with
the twin's scatter, processing and effect hooks. The hybrid model is calibrated with a table
of the loop's own mean rates per bogie type, wheelset and region (with the physics core's
table of the new profile the finder rightly names ``wear_measure``/``running_direction`` on
every dataset: the worn profiles share the wear differently). The effects are hidden in the
loop's areas; the finder must name them. On effect-free data it may name only the loop's own
nonlinear progression (the hybrid model's linear law is wrong for the loop; see the null test).
The sweep over seeds: ``benchmarks/detection_rates.py --generators loop``. Eight loop runs
take a few minutes, so these tests are marked slow.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
import pandas as pd
import pytest

from wearcast.statistics import hybrid
from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import fleet_twin_loop as fl
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.routes import RouteClass

pytestmark = pytest.mark.slow

CLASSES = ((None, 0.0, 70.0, 0.6), (500.0, 60.0, 60.0, 0.4))  # radius, cant, speed, share
TRUTH = fl.LoopTruth(vehicles={"motor": "metro_b", "trailer": "metro_b"}, law="archard_kth",
                     n_steps=6, mileage_scale=0.15)
MILEAGES_KM = (15_000.0, 40_000.0, 70_000.0, 100_000.0, 135_000.0, 170_000.0)
CACHE: dict[Any, Any] = {}


def route(name: str, lubricated: bool) -> ft.TwinRoute:
    classes: list[RouteClass] = []
    for radius_m, cant_mm, speed_kmh, share in CLASSES:
        if radius_m is None:
            classes.append(RouteClass(None, None, 0.0, speed_kmh, share))
        else:
            classes += [RouteClass(radius_m, d, cant_mm, speed_kmh, share / 2.0)
                        for d in ("left", "right")]
    return ft.TwinRoute(name, tuple(classes), {"flange_lubrication": lubricated})


def config(seed: int, effects: tuple[Any, ...]) -> ft.FleetConfig:
    line, greased = route("line", False), route("line_lubricated", True)
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
    return ft.FleetConfig(units=units, mileages_km=MILEAGES_KM, seed=seed,
                          points_per_profile=200, wear_effects=effects)


def area(sim: Any, loop_km: float, region: str) -> float:
    w = sim.wear_at(min(loop_km, sim.mileage_km[-1]))
    sel = sim.y_mm >= -30.0 if region == "tread" else sim.y_mm < -30.0
    return float(np.trapezoid(w[sel], sim.y_mm[sel]))


def rate_table(sims: dict[Any, Any]) -> pd.DataFrame:
    """Per bogie type, wheelset and region the loop's least-squares rate [mm^2/1,000 km] over
    the loop mileage the fleet spans, on every rail and under both measure names."""
    km = np.linspace(0.0, max(MILEAGES_KM) * TRUTH.mileage_scale, 21)[1:]
    rows = []
    for bogie in ("motor", "trailer"):
        for axle, wheelset in ((1, "leading"), (2, "trailing")):
            runs = [s for (_, b, a, _), s in sims.items() if b == bogie and a == axle]
            for region in ("flange", "tread"):
                a = np.mean([[area(s, k, region) for k in km] for s in runs], axis=0)
                rate = max(float(np.sum(a * km) / np.sum(km * km)) * 1e3, 0.0)
                for rail, radius in (("tangent", np.nan), ("high", 500.0), ("low", 500.0)):
                    for measure in ("tau_max", "t_gamma"):
                        rows.append({"bogie_type": bogie, "wheelset": wheelset, "rail": rail,
                                     "radius_m": radius, "region": region, "measure": measure,
                                     "value": rate})
    return pd.DataFrame(rows)


@lru_cache(maxsize=4)
def diagnosed(name: str, seed: int = 100):
    effects = {"none": (), "traction": (te.traction(1.3),),
               "seasonal_friction": (te.seasonal_friction(0.3),)}[name]
    cfg = config(seed, effects)
    loop = fl.generate_loop_fleet(cfg, TRUTH, cache=CACHE)
    df, curves = te.twin_measurements(loop.fleet)
    routes, attrs = te.scenario_routes(cfg)
    table = rate_table(dict(loop.simulations))
    cal = (df["vehicle_id"].str.startswith("A") & (df["bogie_type"] == "motor")).to_numpy()
    model = hybrid.calibrate(df[cal], routes, table, wear_curves_mm=curves[cal],
                             measure="tau_max", running_mode="mixed")
    return diagnose(model, df, curves, routes, table, route_attributes=attrs,
                    calibration_wheel_ids=set(df["wheel_id"][cal]), n_boot=300)


@pytest.mark.parametrize("cause", ["traction", "seasonal_friction"])
def test_loop_hidden_effect_is_named(cause):
    d = diagnosed(cause)
    assert d.verdict == cause, [(f.cause, round(f.gain.relative, 3), f.evidence["p_value"])
                                for f in d.findings]
    assert d.finding(cause).gain.ci95_low > 0.0


def test_loop_effect_free_data_names_nothing_but_the_loops_own_progression():
    # the loop's own wear is slightly nonlinear in mileage (tread exponent ~1.03-1.08, flange
    # ~0.97-0.99 over the fleet's range, fitted on the loop runs): on effect-free loop data
    # the finder names nonlinear_progression on a share of the seeds (8 of 20 in
    # benchmarks/detection_rates.py, held-out gain ~1 %, right at the materiality floor), which
    # is the hybrid model's linear law disagreeing with the loop. No other cause may be named.
    d = diagnosed("none")
    findings = [(f.cause, round(f.gain.relative, 3), f.evidence["p_value"]) for f in d.findings]
    assert d.verdict in ("none", "nonlinear_progression", "ambiguous"), findings
    if d.verdict == "ambiguous":
        assert d.candidates[0] == "nonlinear_progression", (d.candidates, findings)
    assert all(f.evidence["p_value"] > 0.04 for f in d.findings
               if f.cause != "nonlinear_progression"), findings
