"""The cause catalogue: data needs, skip reasons and closed-form fits."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wearcast.statistics import causes as cz
from wearcast.statistics import hybrid
from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.discrepancy_data import build_data
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.generators import twin_wear_table

TABLE = twin_wear_table.synthetic_wear_table()


@pytest.fixture(scope="module")
def scenario():
    cfg = te.scenario_config(seed=7, vehicles_per_unit=1,
                             wear_effects=(te.traction(1.4),))
    df, curves = te.twin_measurements(ft.generate_fleet(cfg, TABLE))
    routes, attrs = te.scenario_routes(cfg)
    model = hybrid.calibrate(df, routes, TABLE, wear_curves_mm=curves, measure="tau_max",
                             running_mode="mixed")
    return model, df, curves, routes, attrs


def test_catalogue_has_every_design_cause():
    assert set(cz.CAUSE_CODES) == {
        "traction", "running_direction", "curve_asymmetry", "flange_lubrication",
        "wear_measure", "nonlinear_progression", "seasonal_friction", "vehicle_load",
        "profile_misalignment"}
    for cause in cz.CATALOGUE:
        assert cause.explanation and cause.needs



def test_moderate_effects_hide_every_catalogue_cause_once():
    # the twin's hidden-effect scenarios name exactly the catalogue (and the effect-free case),
    # each with one wear or one profile effect
    effects = te.moderate_effects(TABLE)
    assert list(effects) == ["none", *cz.CAUSE_CODES]
    assert effects["none"] == ((), ())
    for code in cz.CAUSE_CODES:
        wear, profile = effects[code]
        assert len(wear) + len(profile) == 1, code
    assert effects["profile_misalignment"][0] == ()

def test_every_cause_applies_to_a_complete_dataset(scenario):
    model, df, curves, routes, attrs = scenario
    data = build_data(model, df, curves, routes, TABLE, route_attributes=attrs)
    assert {c.code: c.skip_reason(data) for c in cz.CATALOGUE} == \
        {c: None for c in cz.CAUSE_CODES}


def test_missing_covariates_are_skipped_with_reasons(scenario):
    model, df, curves, routes, _ = scenario
    thin = df.drop(columns=["load_t", "measured_on", "instrument_id"])
    thin = thin[thin["bogie_type"] == "trailer"]
    table = TABLE[TABLE["measure"] == "tau_max"]
    d = diagnose(model, thin, None, routes, table)
    assert set(d.skipped) == {"traction", "flange_lubrication", "wear_measure",
                              "seasonal_friction", "vehicle_load", "profile_misalignment"}
    assert "load_t" in d.skipped["vehicle_load"]
    assert "lubricated" in d.skipped["flange_lubrication"]


def test_traction_fit_recovers_the_multiplier_and_null_only_rescales(scenario):
    model, df, curves, routes, attrs = scenario
    data = build_data(model, df, curves, routes, TABLE, route_attributes=attrs)
    everything = np.ones(data.n, dtype=bool)
    fit = cz.Traction().fit(data, everything, cluster=df["vehicle_id"].to_numpy())
    # generator: tread x1.4 on motor bogies; 10 % per-wheel scatter over 32 wheels
    assert fit.public()["tread_multiplier_motor"] == pytest.approx(1.4, abs=0.1)
    ci = fit.intervals()["tread_multiplier_motor"]
    assert ci["ci95_low"] < ci["value"] < ci["ci95_high"]
    null = cz.NullArea().fit(data, everything)
    pred = null.predict(data)
    assert np.allclose(pred, data.base * np.exp(null.log_scale_)[None, :])

    def sse(p):
        e = np.log((np.clip(data.measured, 0, None) + data.floor)
                   / (np.clip(p, 0, None) + data.floor))
        return float(np.sum(e ** 2))

    # an extension nests the null: its in-sample error is (to linearisation) not larger
    assert sse(fit.predict(data)) <= sse(pred) * 1.001


def test_fit_and_saved_parameters_predict_identically(scenario):
    # one implementation: a cause rebuilt from its public parameters predicts as the fit
    model, df, curves, routes, attrs = scenario
    data = build_data(model, df, curves, routes, TABLE, route_attributes=attrs)
    everything = np.ones(data.n, dtype=bool)
    for cause in cz.CATALOGUE:
        if cause.metric == "shape":
            continue
        fit = cause.fit(data, everything)
        again = cause.from_params(fit.public())
        again.log_scale_ = fit.log_scale_
        np.testing.assert_allclose(again.predict(data), fit.predict(data), rtol=1e-9,
                                   err_msg=cause.code)


def test_season_features_follow_each_interval_on_the_calendar():
    # one wheel, 1 km/day from 2021-01-01, measured at irregular dates: each interval's
    # feature is the mileage-weighted mean of cos/sin over its own days
    frame = pd.DataFrame({"wheel_id": ["w"] * 3,
                          "measured_on": ["2021-03-01", "2021-04-15", "2021-12-31"]})
    s = np.array([59.0, 104.0, 364.0])
    x = cz.season_features(frame, s)
    w = cz.OMEGA_PER_DAY
    t0 = (pd.Timestamp("2021-01-01") - pd.Timestamp("1970-01-01")).days
    days = t0 + np.arange(364) + 0.5
    for i, end in enumerate(s.astype(int)):
        assert x[i, 0] == pytest.approx(np.mean(np.cos(w * days[:end])), abs=2e-3)
        assert x[i, 1] == pytest.approx(np.mean(np.sin(w * days[:end])), abs=2e-3)


def test_season_weighted_by_the_wear_each_interval_adds():
    # the season multiplies the wear rate: each interval counts with the wear it added.
    frame = pd.DataFrame({"wheel_id": ["w"] * 3,
                          "measured_on": ["2021-03-01", "2021-04-15", "2021-12-31"]})
    s = np.array([59.0, 104.0, 364.0])
    # wear linear in mileage: the mileage-weighted features, in every column
    x = cz.accrual_season_features(frame, s, np.column_stack([2.0 * s, 0.5 * s]))
    mileage = cz.season_features(frame, s)
    np.testing.assert_allclose(x[:, 0, :], mileage, atol=1e-12)
    np.testing.assert_allclose(x[:, 1, :], mileage, atol=1e-12)
    # a running-in wear: all of it in the first interval -> every later measurement carries
    # the first interval's season only; the mileage weights would average it away
    front = np.array([10.0, 10.0, 10.0])
    y = cz.accrual_season_features(frame, s, front[:, None])[:, 0, :]
    np.testing.assert_allclose(y, np.repeat(y[:1], 3, axis=0), atol=1e-12)
    assert abs(mileage[2, 0] - y[2, 0]) > 0.3
    # A = sum_i (1 + a cos_i + b sin_i) dA_i over the intervals, divided by A: for wear
    # growing as sqrt(s) the features are the wear-weighted means of the interval means
    grow = np.sqrt(s)
    z = cz.accrual_season_features(frame, s, grow[:, None])[:, 0, :]
    w = cz.OMEGA_PER_DAY
    t0 = (pd.Timestamp("2021-01-01") - pd.Timestamp("1970-01-01")).days
    days = t0 + np.arange(364) + 0.5
    edges = np.concatenate([[0], s.astype(int)])
    inc = np.diff(np.concatenate([[0.0], grow]))
    cos_i = np.array([np.mean(np.cos(w * days[a:b]))
                      for a, b in zip(edges[:-1], edges[1:], strict=True)])
    assert z[2, 0] == pytest.approx(np.sum(inc * cos_i) / grow[2], abs=2e-3)


def test_reprofiling_mid_series_starts_a_new_life():
    frame = pd.DataFrame({"wheel_id": ["w"] * 4, "measured_on": ["2021-01-10", "2021-03-01",
                                                                 "2021-05-01", "2021-07-01"]})
    lives = cz.life_ids(frame, np.array([5_000.0, 30_000.0, 8_000.0, 40_000.0]))
    assert len(set(lives[:2])) == 1 and len(set(lives[2:])) == 1 and lives[0] != lives[2]


def test_season_features_average_out_over_whole_years():
    frame = pd.DataFrame({"wheel_id": ["w", "w"], "measured_on": ["2022-01-01", "2023-01-01"]})
    # 1 km/day from 2021-01-01: the first interval is exactly one year, the second two
    x = cz.season_features(frame, np.array([365.0, 730.0]))
    assert np.allclose(x, 0.0, atol=5e-3)


def test_lubrication_flags_from_route_attributes_or_column():
    frame = pd.DataFrame({"wheel_id": ["a", "b"]})
    flags = cz.lubrication_flags(frame, np.array(["r1", "r2"]),
                                 {"r1": {"flange_lubrication": "yes"}, "r2": {"x": 1}})
    assert flags.tolist() == [True, False]
    frame["lubricated"] = [False, True]
    assert cz.lubrication_flags(frame, np.array(["r1", "r2"]), None).tolist() == [False, True]
    assert cz.lubrication_flags(frame.drop(columns="lubricated"), np.array(["r1", "r2"]),
                                None) is None


def test_unknown_cause_code_is_refused():
    with pytest.raises(ValueError, match="cause"):
        cz.cause_by_code("gremlins")
