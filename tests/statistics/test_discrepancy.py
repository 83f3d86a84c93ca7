"""diagnose -> Diagnosis, apply_extension, figures and HTML report (pure API)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from wearcast.statistics import finder_scoring as fs
from wearcast.statistics import hybrid
from wearcast.statistics.discrepancy import ExtendedModel, apply_extension
from wearcast.statistics.discrepancy_report import diagnosis_figures, report_html
from wearcast.statistics.generators import twin_effects as te

_spec = importlib.util.spec_from_file_location(
    "_diagnose_helpers", Path(__file__).with_name("_diagnose_helpers.py"))
helpers = sys.modules.get("_diagnose_helpers") or importlib.util.module_from_spec(_spec)
if "_diagnose_helpers" not in sys.modules:
    sys.modules["_diagnose_helpers"] = helpers
    _spec.loader.exec_module(helpers)


def test_max_t_adjustment_and_sign_flip():
    rng = np.random.default_rng(0)
    null = rng.normal(size=(3, 999))
    null[2] *= 5.0                       # a flexible candidate with a wide null
    raw, adj = fs.min_p(np.array([4.0, 0.0, 4.0]), null)
    assert raw[0] < 0.01 and adj[0] < 0.01      # far beyond its own null
    assert raw[1] > 0.3 and adj[1] >= raw[1]
    assert adj[2] > 0.2                  # the same gain is ordinary for the wide candidate
    assert fs.sign_flip_p(np.ones(10), 0, rng) == pytest.approx(1 / 1024)
    assert fs.sign_flip_p(np.array([1.0, -1.0] * 5), 0, rng) > 0.4


def test_nuisance_draws_keep_the_vehicle_and_wheel_variation():
    rng = np.random.default_rng(1)
    vehicle = np.repeat(np.arange(12), 40)
    wheel = np.repeat(np.arange(96), 5)
    r = (np.repeat(rng.normal(0, 0.2, 12), 40) + np.repeat(rng.normal(0, 0.1, 96), 5)
         + rng.normal(0, 0.05, 480))[:, None]
    nm = fs.NuisanceModel.fit(r, np.ones_like(r), vehicle, wheel)
    d = nm.draws(50, rng).reshape(480, 1, 50)
    veh_means = np.array([[d[vehicle == v, 0, b].mean() for v in range(12)] for b in range(50)])
    assert 0.1 < veh_means.std(axis=1).mean() < 0.3


def test_traction_extension_predicts_motor_treads_faster():
    model, df, _, routes, diagnosis = helpers.cached("traction")
    ext = apply_extension(model, diagnosis.finding("traction"))
    assert isinstance(ext, ExtendedModel)
    route = routes["aosta"]
    motor = ext.predict(route, helpers.TABLE, bogie_type="motor", axle=1, side="left",
                        mileage_km=[100_000.0])
    trailer = ext.predict(route, helpers.TABLE, bogie_type="trailer", axle=1, side="left",
                          mileage_km=[100_000.0])
    base_m = hybrid.predict(model, route, helpers.TABLE, bogie_type="motor", axle=1,
                            side="left", mileage_km=[100_000.0])
    base_t = hybrid.predict(model, route, helpers.TABLE, bogie_type="trailer", axle=1,
                            side="left", mileage_km=[100_000.0])
    ratio_ext = motor.tread_area_mm2[1, 0] / trailer.tread_area_mm2[1, 0]
    ratio_base = base_m.tread_area_mm2[1, 0] / base_t.tread_area_mm2[1, 0]
    m = diagnosis.finding("traction").extension["parameters"]["tread_multiplier_motor"]
    assert ratio_ext / ratio_base == pytest.approx(m, rel=1e-9)
    again = ExtendedModel.from_dict(json.loads(json.dumps(ext.to_dict())))
    assert again.rate_factors(route, helpers.TABLE, bogie_type="motor", axle=1, side="left") \
        == ext.rate_factors(route, helpers.TABLE, bogie_type="motor", axle=1, side="left")


def test_running_direction_extension_is_usable_for_prediction():
    model, _, _, routes, diagnosis = helpers.cached("running_direction")
    ext = apply_extension(model, diagnosis.finding("running_direction"))
    a1 = ext.predict(routes["aosta"], helpers.TABLE, bogie_type="trailer", axle=1,
                     side="left", mileage_km=[100_000.0], covariates={"running_mode": "mixed"})
    a2 = ext.predict(routes["aosta"], helpers.TABLE, bogie_type="trailer", axle=2,
                     side="left", mileage_km=[100_000.0], covariates={"running_mode": "mixed"})
    # axle 1 leads 80 %: its flange wears more than axle 2's (base model: equal)
    assert a1.flange_area_mm2[1, 0] > 1.5 * a2.flange_area_mm2[1, 0]


def test_wear_measure_extension_is_a_plain_hybrid_model():
    model, _, _, routes, diagnosis = helpers.cached("wear_measure")
    ext = apply_extension(model, diagnosis.finding("wear_measure"))
    assert isinstance(ext, hybrid.HybridModel) and ext.measure == "t_gamma"
    out = hybrid.predict(ext, routes["metro"], helpers.TABLE, bogie_type="motor", axle=1,
                         side="right", mileage_km=[50_000.0])
    assert np.all(np.isfinite(out.tread_area_mm2))


def test_nonlinear_extension_bends_the_wear_curve():
    model, _, _, routes, diagnosis = helpers.cached("nonlinear_progression")
    ext = apply_extension(model, diagnosis.finding("nonlinear_progression"))
    out = ext.predict(routes["aosta"], helpers.TABLE, bogie_type="motor", axle=1, side="left",
                      mileage_km=[50_000.0, 100_000.0])
    # beta ~ 0.75: doubling the mileage multiplies the area by ~2^0.75, not 2
    ratio = out.tread_area_mm2[1, 1] / out.tread_area_mm2[1, 0]
    assert ratio == pytest.approx(2 ** 0.75, abs=0.1)


def test_report_and_figures():
    diagnosis = helpers.verdict_of("traction")
    figs = diagnosis_figures(diagnosis)
    assert set(figs) == {"residuals", "predicted_vs_measured"}
    assert all(s.lstrip().startswith("<?xml") and "<svg" in s for s in figs.values())
    page = report_html(diagnosis, figs)
    assert "traction" in page and page.count("<svg") == 2
    assert "Verdict: <b>traction</b>" in page


def test_diagnosis_to_dict_contract():
    d = helpers.verdict_of("flange_lubrication").to_dict()
    assert d["verdict"] == "flange_lubrication"
    f = d["findings"][0]
    assert set(f) >= {"cause", "summary", "evidence", "extension", "gain"}
    assert set(f["gain"]) >= {"before_error", "after_error", "relative", "ci95_low",
                              "ci95_high"}
    assert set(f["evidence"]) >= {"effect_size", "p_value", "subgroup", "interval"}
    json.dumps(d)


def test_scenario_routes_have_attributes():
    cfg = te.scenario_config(seed=0)
    routes, attrs = te.scenario_routes(cfg)
    assert attrs["aosta_lubricated"]["flange_lubrication"] is True
    assert set(routes) == {"aosta", "aosta_lubricated", "metro"}
