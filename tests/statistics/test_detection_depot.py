"""The discrepancy finder on the depot campaign generator (data it was not built on).

``wearcast.statistics.generators.depot`` simulates every calendar day: heavy-tailed wheel
factors, vehicle factors, heteroscedastic heavy-tailed area noise, irregular visits, missed
and repeated measurements, reprofiling mid-series, cars changing route, three instruments,
each effect injected from its own physical description (e.g. the running direction as the
direction of each day's trips, greasing that works on 90 % of the days, a daily passenger
load). The model is calibrated as a user would (unit N1's motor bogies, tau_max, mixed) and
the verdict must name the hidden cause; effect-free data must give ``none``.
The sweep over seeds and strengths: ``benchmarks/detection_rates.py --generators depot``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from tests.statistics.conftest import findings_summary
from wearcast.statistics import causes as cz
from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.discrepancy_data import build_data
from wearcast.statistics.generators import depot as dp
from wearcast.statistics.generators import scenarios

MODERATE = {
    "traction": dp.DepotEffects(traction=1.3),
    "seasonal_friction": dp.DepotEffects(seasonal=0.3),
    "wear_measure": dp.DepotEffects(measure_blend=0.6),
    "running_direction": dp.DepotEffects(leading_share=0.7),
    "vehicle_load": dp.DepotEffects(load_exponent=2.0),
}


def case(effects: dp.DepotEffects, seed: int = 0):
    s = scenarios.depot_scenario(effects, seed)
    return s.fleet, s.measurements, s.calibration, s.model


@lru_cache(maxsize=8)
def diagnosed(cause: str, seed: int = 0):
    effects = MODERATE.get(cause, dp.DepotEffects())
    fleet, df, cal, model = case(effects, seed)
    return diagnose(model, df, fleet.wear_curves, fleet.routes, fleet.table,
                    calibration_wheel_ids=set(df["wheel_id"][cal]),
                    route_attributes=fleet.route_attributes, n_boot=300, n_null=99)


def test_campaign_has_the_nuisance_it_promises():
    fleet = dp.generate_depot_fleet(dp.DepotConfig(seed=3))
    df = fleet.measurements
    # irregular dates, repeated measurements (same wheel, same day), reprofiling mid-series
    assert df.groupby(["wheel_id", "measured_on"]).size().max() == 2
    lives = cz.life_ids(df, df["mileage_km"].to_numpy(float))
    assert len(set(lives)) > df["wheel_id"].nunique()
    gaps = df.drop_duplicates(["wheel_id", "measured_on"]).assign(
        d=lambda f: f["measured_on"].astype("datetime64[ns]")).sort_values(
        ["wheel_id", "d"]).groupby("wheel_id")["d"].diff().dt.days.dropna()
    assert gaps.min() >= 20 and gaps.nunique() > 20
    # route changes within a car, three instruments, motor bogies only in MT cars
    assert (df.groupby("vehicle_id")["route"].nunique() > 1).any()
    assert df["instrument_id"].nunique() == 3
    kinds = df.groupby("vehicle_id")["bogie_type"].nunique()
    assert (kinds == 2).any() and (kinds == 1).any()      # MT cars and TT cars
    assert np.all(np.isfinite(fleet.wear_curves))


@pytest.mark.parametrize("cause", ["traction", "seasonal_friction", "wear_measure"])
def test_depot_hidden_effect_is_named(cause):
    d = diagnosed(cause)
    assert d.verdict == cause, findings_summary(d)
    assert d.runner_up is not None and d.margin is not None and d.margin > 0
    assert d.margin_p_value is not None and d.margin_p_value < 0.05


def test_depot_null_gives_none():
    d = diagnosed("none")
    assert d.verdict == "none", findings_summary(d)


@pytest.mark.parametrize("seed, runner_up", [(106, None), (111, None), (119, None),
                                              (107, "wear_measure"), (109, "wear_measure")])
def test_weak_depot_traction_is_named_and_its_null_gives_none(seed, runner_up):
    # traction 1.1 (each car's own multiplier jittered by 0.03) on campaigns the finder
    # before stop 26 missed (106, 111: none at adjusted p 0.18, 0.075; 119: ambiguous with
    # wear_measure, margin p 0.05): traction is now tested on the held-out error after the
    # vehicles' random log-scale (``finder_scoring.SCORE_METRIC``), so the contrast of a
    # car's motor and trailer bogies is no longer drowned by the cars' own rate factors.
    # 107 and 109 the finder before stop 29 called ``ambiguous`` with wear_measure (the
    # depot's motor bogies have their own T_gamma/tau_max ratio, so a blend of the measures
    # also raises motor treads). 107: wear_measure itself is not significant (adjusted p 0.67,
    # gain 0.5 %), so it is no rival (``finder_scoring.MARGIN_RIVALS``); 109: wear_measure is
    # significant, and traction's margin over it in the vehicle metric is tested by the
    # bootstrap alone (p 0.03; the sign-flip over the cars gave 0.49,
    # ``finder_scoring.WITHIN_VEHICLE_MARGIN``); both report it as the runner-up, with no
    # candidates. Effect-free data of the same seeds still give ``none``
    for effects, expected in ((dp.DepotEffects(traction=1.1), "traction"),
                              (dp.DepotEffects(), "none")):
        args, kwargs = scenarios.depot_scenario(effects, seed).finder_arguments()
        d = diagnose(*args, **kwargs, n_boot=300)
        assert d.verdict == expected, (expected, d.runner_up, d.margin, d.candidates,
                                       findings_summary(d))
        if expected == "traction" and runner_up is not None:
            assert d.runner_up == runner_up and d.candidates == ()


@pytest.mark.slow
def test_weak_depot_traction_detection_over_twenty_campaigns():
    # the benchmark's cell (seeds 100-119): at least 17 of 20 named (measured 17 of 20;
    # 15 of 20 before the margin's rivals and within-vehicle bootstrap, 13 of 20 before
    # stop 26)
    named = 0
    for seed in range(100, 120):
        args, kwargs = scenarios.depot_scenario(dp.DepotEffects(traction=1.1),
                                                seed).finder_arguments()
        named += diagnose(*args, **kwargs, n_boot=300).verdict == "traction"
    assert named >= 17


def test_depot_effect_size_interval_covers_the_injected_multiplier():
    d = diagnosed("traction")
    ci = d.finding("traction").extension["intervals"]["tread_multiplier_motor"]
    assert ci["ci95_low"] <= 1.3 <= ci["ci95_high"]


@pytest.mark.slow
def test_traction_interval_coverage_over_runs():
    # the 95 % interval of the motor-tread multiplier (vehicle-clustered sandwich, t with
    # vehicles - 1 df) covers the injected 1.2 in at least 90 % of 20 campaigns
    covered = 0
    for seed in range(20):
        fleet, df, cal, model = case(dp.DepotEffects(traction=1.2), seed)
        data = build_data(model, df, fleet.wear_curves, fleet.routes, fleet.table,
                          route_attributes=fleet.route_attributes)
        null = cz.NullArea().fit(data, np.ones(data.n, bool))
        data.set_robust_weights(data.e - data.phi * null.log_scale_[None, :])
        est = cz.Traction().fit(data, np.ones(data.n, bool), cluster=df["vehicle_id"].to_numpy())
        ci = est.intervals()["tread_multiplier_motor"]
        covered += ci["ci95_low"] <= 1.2 <= ci["ci95_high"]
    assert covered >= 18


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_depot_detection_over_more_seeds(seed):
    for cause in ["none", *MODERATE]:
        assert diagnosed(cause, seed).verdict == cause


def test_structure_outside_the_catalogue_is_reported_with_its_size():
    # one instrument over-reads both wear areas by 25 % (a calibration error of its area
    # computation, not a geometric one): no cause of the catalogue has this form, so the
    # verdict must say where the residuals are structured and by how much, not 'none'
    fleet, df, cal, model = case(dp.DepotEffects(), seed=4)
    df = df.copy()
    sel = df["instrument_id"].eq("DP-B").to_numpy()
    for col in ("flange_area_mm2", "tread_area_mm2"):
        df.loc[sel, col] *= 1.25
    d = diagnose(model, df, None, fleet.routes, fleet.table,
                 calibration_wheel_ids=set(df["wheel_id"][cal]),
                 route_attributes=fleet.route_attributes, n_boot=300, n_null=99)
    assert d.verdict == "outside_catalogue", [(f.cause, f.gain.relative) for f in d.findings]
    top = d.unexplained[0]
    assert top["by"] == "instrument" and top["p_value"] <= 0.01
    level = next(lv for lv in top["levels"] if lv["level"] == "DP-B")
    assert 10.0 < level["tread_rate_change_pct"] < 40.0
