"""The discrepancy finder on data from an independent generator (issue 4: not tuned to the twin).

``wearcast.statistics.generators.fleet_twin_alt`` differs from ``fleet_twin`` in everything the
finder
could have been tuned to: wear-curve shapes, scatter distributions (uniform wheel and vehicle
factors, heteroscedastic area noise), fleet layout (3 units of 4/3/2 motor or trailer cars,
unequal mileages, ~12 % missing measurements), its own routes and analytic wear measures,
and its own way of injecting each effect (additive traction wear, running-in instead of a
power law, a sine season peaking in April, a load factor linear in load, an instrument scale
error about the flange back). The model is calibrated as a user would (unit U1's motor
cars, tau_max, mixed running) and the verdict must name the hidden cause; effect-free data
must give 'none'. The sweep over seeds and strengths: ``benchmarks/detection_rates.py --alt``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from wearcast.statistics import hybrid
from wearcast.statistics.discrepancy import apply_extension, diagnose
from wearcast.statistics.generators import fleet_twin_alt as fa


def run_alt(effects: fa.AltEffects, seed: int = 0, n_boot: int = 400):
    fleet = fa.generate_alt_fleet(fa.AltConfig(effects=effects, seed=seed))
    df, curves = fleet.measurements, fleet.wear_curves
    cal = (df["unit"].eq("U1") & df["bogie_type"].eq("motor")).to_numpy()
    model = hybrid.calibrate(df[cal], fleet.routes, fleet.table, wear_curves_mm=curves[cal],
                             measure="tau_max", running_mode="mixed")
    diagnosis = diagnose(model, df, curves, fleet.routes, fleet.table,
                         calibration_wheel_ids=set(df["wheel_id"][cal]),
                         route_attributes=fleet.route_attributes, n_boot=n_boot)
    return fleet, model, diagnosis


@lru_cache(maxsize=16)
def cached(cause: str, seed: int = 0):
    return run_alt(fa.MODERATE[cause], seed)


CAUSES = [c for c in fa.MODERATE if c != "none"]


def test_generator_layout_differs_from_the_twin():
    fleet = cached("none")[0]
    df = fleet.measurements
    assert df["unit"].nunique() == 3
    assert sorted(df.groupby("unit")["vehicle_id"].nunique().tolist()) == [2, 3, 4]
    # bogie type is constant within a vehicle (motor cars and trailer cars)
    assert (df.groupby("vehicle_id")["bogie_type"].nunique() == 1).all()
    # missing measurements: wheels have unequal numbers of measurements
    assert df.groupby("wheel_id").size().nunique() > 2
    # both measures in the table; the areas come from processed profiles
    assert set(fleet.table["measure"]) == {"tau_max", "t_gamma"}
    assert np.all(np.isfinite(fleet.wear_curves))


@pytest.mark.parametrize("cause", CAUSES)
def test_alt_hidden_effect_is_named(cause):
    diagnosis = cached(cause)[2]
    assert diagnosis.verdict == cause, [(f.cause, round(f.gain.relative, 3),
                                         f.evidence["p_value"]) for f in diagnosis.findings]
    finding = diagnosis.finding(cause)
    assert finding.gain.relative >= 0.05 and finding.gain.ci95_low > 0.0
    assert finding.gain.after_error < finding.gain.before_error


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_alt_effect_free_data_gives_none(seed):
    diagnosis = cached("none", seed)[2]
    assert diagnosis.verdict == "none", [(f.cause, round(f.gain.relative, 3),
                                          f.evidence["p_value"]) for f in diagnosis.findings]


def test_alt_misalignment_correction_reduces_the_instrument_signature():
    # fleet_twin_alt: LP-2 stretches y by 1 % about the flange back (y' = y + e (y + 70)).
    # Rigid alignment absorbs part of it (shift, rotation) and the three-term geometric basis
    # is not orthogonal (scale and flange offset trade off), so the individual coefficients
    # are not identifiable to a tolerance worth asserting; what must hold is that the
    # correction is relative to the calibration instrument and that applying it brings LP-2's
    # wear curves closer to the model (the rest of their shape residual is the generator's
    # own tread/flange shapes, which no instrument correction can remove).
    fleet, model, diagnosis = cached("profile_misalignment")
    finding = diagnosis.finding("profile_misalignment")
    params = finding.extension["parameters"]
    assert params["reference_instrument"] == "LP-1"
    assert all(v == 0.0 for v in params["corrections"]["LP-1"].values())
    extended = apply_extension(model, finding)
    df, curves = fleet.measurements, fleet.wear_curves
    corrected = extended.correct_wear_curves(df, curves)
    lp2 = df["instrument_id"].eq("LP-2").to_numpy()
    np.testing.assert_array_equal(corrected[~lp2], curves[~lp2])
    from wearcast.statistics.residuals import shape_residuals

    areas = df[["flange_area_mm2", "tread_area_mm2"]].to_numpy()[lp2]
    before = np.mean(shape_residuals(model, areas, curves[lp2]) ** 2)
    after = np.mean(shape_residuals(model, areas, corrected[lp2]) ** 2)
    assert after < 0.9 * before
    # the saved model predicts exactly as the base model (the correction is for the data)
    assert extended.for_wheel(fleet.routes["valley"], fleet.table, bogie_type="motor", axle=1,
                              side="left") == model


def test_design_effect_limits():
    from wearcast.statistics.discrepancy import design_effect

    rng = np.random.default_rng(0)
    vehicle = np.repeat(np.arange(12), 8)
    # independent wheels: deff ~ 1; identical wheels within a vehicle: deff = wheels per vehicle
    deff, g = design_effect(rng.normal(size=96), vehicle)
    assert g == 12 and deff < 1.6
    deff, _ = design_effect(np.repeat(rng.normal(size=12), 8), vehicle)
    assert deff == pytest.approx(8.0)
    # a covariate's systematic part is not counted as clustering
    level = np.where(vehicle < 6, "motor", "trailer")
    values = np.where(level == "motor", 5.0, 0.0) + rng.normal(size=96)
    assert design_effect(values, vehicle, level)[0] < 1.6
    assert design_effect(values, vehicle)[0] > 4.0


def test_vehicle_level_test_keeps_its_size_under_clustering():
    # null: held-out error differences with a strong vehicle random effect (ICC 0.5) and a
    # vehicle-level covariate without effect; the design-effect t-test must reject at
    # alpha = 5 % in about 5 % of 400 simulated data sets (binomial 2-sigma bound ~ 8 %)
    from wearcast.statistics.discrepancy import _pvalue

    rng = np.random.default_rng(1)
    vehicle = np.repeat([f"v{i}" for i in range(9)], 8)
    wheel = np.array([f"w{i}" for i in range(72)])
    cov = np.repeat(np.where(np.arange(9) % 2 == 0, "motor", "trailer"), 8)
    rejections = 0
    for _ in range(400):
        d = np.repeat(rng.normal(size=9), 8) + rng.normal(size=72)
        p, _how = _pvalue(d, np.zeros(72), wheel, vehicle, cov)
        rejections += p < 0.05
    assert rejections / 400 <= 0.08
