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

from tests.statistics.conftest import max_t_null_p_values, nested_layout
from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.extension import apply_extension
from wearcast.statistics.generators import fleet_twin_alt as fa
from wearcast.statistics.generators import scenarios


def run_alt(effects: fa.AltEffects, seed: int = 0, n_boot: int = 400):
    s = scenarios.alt_scenario(effects, seed)
    args, kwargs = s.finder_arguments()
    return s.fleet, s.model, diagnose(*args, **kwargs, n_boot=n_boot)


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
    if cause == "vehicle_load" and diagnosis.verdict == "ambiguous":
        # fleet_twin_alt's motor cars are 1 t heavier than its trailer cars, so a load law
        # also raises motor treads: with 9 vehicles the margin over traction is not always
        # significant, and the finder says so instead of guessing. The load must still lead.
        assert diagnosis.candidates[0] == "vehicle_load"
        assert diagnosis.finding("vehicle_load").gain.relative > 0.2
        return
    assert diagnosis.verdict == cause, [(f.cause, round(f.gain.relative, 3),
                                         f.evidence["p_value"]) for f in diagnosis.findings]
    finding = diagnosis.finding(cause)
    assert finding.gain.relative >= 0.05 and finding.gain.ci95_low > 0.0
    assert finding.gain.after_error < finding.gain.before_error


# seeds 104 and 108 are benchmarks/detection_rates.py's effect-free alt datasets on which the
# finder said ``ambiguous`` (seasonal at adjusted p = 0.040, traction at 0.030) while its
# nuisance-only datasets permuted each wheel's residuals: the area noise of fleet_twin_alt is
# larger in log terms for the small early areas, and the wild resampling keeps it there
@pytest.mark.parametrize("seed", [0, 1, 2, 104, 108])
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


def test_resampled_null_keeps_its_size_under_clustering():
    # null: residuals with a strong vehicle random effect (ICC ~0.5), wheel effects and
    # heavy-tailed measurement noise, and a vehicle-level covariate without effect; the
    # resampled max-T test (nuisance model, folds by vehicle) must reject at alpha = 5 % in
    # about 5 % of 100 simulated data sets (binomial 2-sigma bound ~ 10 %)
    rng = np.random.default_rng(1)
    n_veh, per_veh, per_wheel = 9, 8, 4
    vehicle, wheel = nested_layout(n_veh, per_veh, per_wheel)
    level = (vehicle % 2 == 0).astype(float)

    def residuals() -> np.ndarray:
        return (np.repeat(rng.normal(0, 0.2, n_veh), per_veh * per_wheel)
                + np.repeat(rng.normal(0, 0.1, n_veh * per_veh), per_wheel)
                + 0.1 * rng.standard_t(3, vehicle.size))[:, None]

    p_values = max_t_null_p_values(level, vehicle, wheel, residuals, 100, rng)
    assert np.sum(p_values < 0.05) <= 10
