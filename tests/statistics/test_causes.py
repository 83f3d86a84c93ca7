"""The cause catalogue: data needs, skip reasons and closed-form fits."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wearcast.statistics import causes as cz
from wearcast.statistics import fleet_twin as ft
from wearcast.statistics import hybrid
from wearcast.statistics import twin_effects as te
from wearcast.statistics.discrepancy import build_data, diagnose

TABLE = ft.synthetic_wear_table()


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
    fit = cz.Traction().fit(data, everything)
    # generator: tread x1.4 on motor bogies; 10 % per-wheel scatter over 32 wheels
    assert fit.params["tread_multiplier_motor"] == pytest.approx(1.4, abs=0.1)
    null = cz.NullArea().fit(data, everything)
    pred = cz.NullArea().predict(data, null)
    assert np.allclose(pred, data.base * np.exp(null.log_scale)[None, :])
    # an extension nests the null: its in-sample error is never larger
    assert cz.row_sse(data, cz.Traction().predict(data, fit)).sum() <= \
        cz.row_sse(data, cz.NullArea().predict(data, null)).sum() + 1e-9


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
