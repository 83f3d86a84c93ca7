"""The wear-curve shape cause (profile_misalignment) tested in the metric of its nuisance.

An instrument's geometric signature is constant over a wheel's measurements, so it must
stand out against the wheel-to-wheel scatter of the mean signature, which is strongly
correlated between the basis directions (``discrepancy._noise_whitened``). Tested on two
generators that hide the error differently: the twin's flange-tread offset of one
instrument (0.2 mm, the strength the curve-space statistic named on 3 of 20 seeds) and
fleet_twin_alt's lateral scale error about the flange back (0.5 %).
"""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.statistics import finder_scoring as fs
from wearcast.statistics.discrepancy import _instrument_centred, _noise_whitened, diagnose
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import fleet_twin_alt as fa
from wearcast.statistics.generators import scenarios
from wearcast.statistics.generators import twin_effects as te


def test_noise_whitened_wheel_means_have_unit_covariance():
    rng = np.random.default_rng(3)
    wheels = np.repeat(np.arange(60), 5).astype(str)
    inst = fs.codes_of(np.repeat(np.arange(60) % 2, 5))
    mix = np.array([[1.0, 0.0, 0.0], [0.9, 0.3, 0.0], [0.5, 0.2, 0.1]])
    coef = (rng.normal(size=(60, 3)) @ mix.T)[fs.codes_of(wheels)] \
        + 0.05 * rng.normal(size=(300, 3)) + np.where(inst[:, None] == 1, 0.2, 0.0)
    z = _noise_whitened(coef, inst, wheels)
    c = _instrument_centred(z, inst)
    means = np.array([c[wheels == w].mean(axis=0) for w in np.unique(wheels)])
    assert np.allclose(np.cov(means.T), np.eye(3), atol=1e-6)
    # a linear map: the instrument contrast survives, in units of the nuisance
    assert abs(z[inst == 1].mean(axis=0) - z[inst == 0].mean(axis=0)).max() > 0.5


def _diagnosis(scenario: scenarios.Scenario):
    args, kwargs = scenario.finder_arguments()
    return diagnose(*args, **kwargs, n_boot=200)


@pytest.mark.parametrize("generator,seed", [("twin", 100), ("alt", 100)])
def test_weak_instrument_error_is_named(generator, seed):
    if generator == "twin":
        s = scenarios.twin_scenario((), (te.flange_tread_offset("MP-2", 0.2),), seed=seed,
                                    table=ft.synthetic_wear_table())
    else:
        s = scenarios.alt_scenario(fa.AltEffects(instrument_scale=("LP-2", 0.005)), seed)
    d = _diagnosis(s)
    assert d.verdict == "profile_misalignment", [
        (f.cause, round(f.gain.relative, 3), f.evidence["p_value"]) for f in d.findings]
    f = d.finding("profile_misalignment")
    assert f.evidence["p_value"] <= 0.04 and f.gain.relative >= 0.01
