"""diagnose -> Diagnosis, apply_extension, figures and HTML report (pure API)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.statistics.conftest import max_t_null_p_values, nested_layout
from wearcast.statistics import finder_scoring as fs
from wearcast.statistics import hybrid, hybrid_prediction
from wearcast.statistics.discrepancy_report import diagnosis_figures, report_html
from wearcast.statistics.extension import ExtendedModel, apply_extension
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


def test_resampled_null_keeps_its_size_under_noise_that_shrinks_with_mileage():
    # null: vehicle and wheel effects and measurement noise ten times larger at the first of
    # six measurements than at the last (log-area noise of small early areas, as in
    # fleet_twin_alt and depot), and a candidate that tilts each wheel's series (the
    # nonlinear-progression feature, log mileage centred per wheel). Permuting a wheel's
    # residuals would move the large early noise to late rows and shrink the null spread of
    # the tilt; the wild resampling keeps every residual at its row, so the max-T test
    # rejects in about 5 % of 200 data sets (binomial 2-sigma bound ~ 8 %)
    rng = np.random.default_rng(2)
    n_veh, per_veh, per_wheel = 9, 8, 6
    vehicle, wheel = nested_layout(n_veh, per_veh, per_wheel)
    t = np.tile(np.arange(1, per_wheel + 1), n_veh * per_veh).astype(float)
    x = np.log(t) - np.log(t).reshape(-1, per_wheel).mean(axis=1).repeat(per_wheel)

    def residuals() -> np.ndarray:
        return (np.repeat(rng.normal(0, 0.1, n_veh), per_veh * per_wheel)
                + np.repeat(rng.normal(0, 0.1, n_veh * per_veh), per_wheel)
                + 0.3 / t * rng.standard_normal(vehicle.size))[:, None]

    p_values = max_t_null_p_values(x, vehicle, wheel, residuals, 200, rng)
    assert np.sum(p_values <= 0.05) <= 16


def test_wild_draws_keep_every_residual_at_its_row():
    rng = np.random.default_rng(4)
    vehicle = np.repeat(np.arange(3), 4)
    wheel = np.repeat(np.arange(6), 2)
    r = rng.normal(size=(12, 2))
    nm = fs.NuisanceModel.fit(r, np.ones_like(r), vehicle, wheel)
    d = nm.draws(20, rng, scheme="wild").reshape(12, 2, 20)
    # each row of a draw is +- its vehicle's effect +- its wheel's effect +- its own residual
    options = [sv * nm.vehicle_effect + sw * nm.wheel_effect + se * nm.residual
               for sv in (-1, 1) for sw in (-1, 1) for se in (-1, 1)]
    for b in range(20):
        assert all(any(np.allclose(d[i, :, b], o[i]) for o in options) for i in range(12))
    with pytest.raises(ValueError, match="scheme"):
        nm.draws(2, rng, scheme="shuffle")


def test_traction_extension_predicts_motor_treads_faster():
    model, df, _, routes, diagnosis = helpers.cached("traction")
    ext = apply_extension(model, diagnosis.finding("traction"))
    assert isinstance(ext, ExtendedModel)
    route = routes["aosta"]
    motor = ext.predict(route, helpers.TABLE, bogie_type="motor", axle=1, side="left",
                        mileage_km=[100_000.0])
    trailer = ext.predict(route, helpers.TABLE, bogie_type="trailer", axle=1, side="left",
                          mileage_km=[100_000.0])
    base_m = hybrid_prediction.predict(model, route, helpers.TABLE, bogie_type="motor", axle=1,
                                       side="left", mileage_km=[100_000.0])
    base_t = hybrid_prediction.predict(model, route, helpers.TABLE, bogie_type="trailer", axle=1,
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
    out = hybrid_prediction.predict(ext, routes["metro"], helpers.TABLE, bogie_type="motor", axle=1,
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
