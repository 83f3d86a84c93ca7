"""Random-effects (GLS) fit of the calendar season (``statistics/finder_random_effects.py``).

The season's contrast lies within the wheels; its between-wheel part is weighted by what
the wheels' own scatter leaves of it. The estimator must be the same on the data, in every
cross-validation fold and on every resampled dataset (the level of the test rests on it),
and on data of ``fleet_twin_alt`` (not the twin the finder was built on) a seasonal
amplitude of 0.2 that ordinary least squares missed (seed 113: adjusted p 0.105, seed 105:
``ambiguous`` against flange lubrication) must be named, while effect-free data of the same
seeds still give ``none``.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from tests.statistics.conftest import findings_summary
from wearcast.statistics import causes as cz
from wearcast.statistics import finder_random_effects as fre
from wearcast.statistics import finder_scoring as fs
from wearcast.statistics.discrepancy import _folds, diagnose
from wearcast.statistics.discrepancy_data import build_data
from wearcast.statistics.generators import fleet_twin_alt as fa
from wearcast.statistics.generators import scenarios
from wearcast.statistics.wear_tables import compile_wear_table


def test_variance_components_recover_the_simulated_ones():
    rng = np.random.default_rng(3)
    groups, per = 400, 6
    codes = np.repeat(np.arange(groups), per)            # region = code parity
    w = rng.uniform(0.5, 1.0, codes.size)
    s_u, s_e = np.array([0.2, 0.1]), np.array([0.05, 0.08])
    region = codes % 2
    y = w * rng.normal(0.0, 1.0, groups)[codes] * s_u[region] \
        + rng.normal(0.0, 1.0, codes.size) * s_e[region]
    s_u2, s_e2 = fre.variance_components(y.reshape(-1, 2), w.reshape(-1, 2), codes)
    np.testing.assert_allclose(np.sqrt(s_u2), s_u, rtol=0.12)
    np.testing.assert_allclose(np.sqrt(s_e2), s_e, rtol=0.05)


@lru_cache(maxsize=2)
def alt_data(amplitude: float, seed: int):
    s = scenarios.alt_scenario(fa.AltEffects(seasonal_amplitude=amplitude), seed)
    args, kwargs = s.finder_arguments()
    model, df, curves, routes, table = args
    data = build_data(model, df, curves, routes, compile_wear_table(table),
                      calibration_wheel_ids=kwargs["calibration_wheel_ids"],
                      route_attributes=kwargs["route_attributes"])
    everything = np.ones(data.n, dtype=bool)
    null = cz.NullArea().fit(data, everything)
    data.set_robust_weights(data.e - data.phi * null.log_scale_[None, :])
    return data


def _baseline_residual(data):
    sw = np.sqrt(data.weights)
    w = sw * data.phi
    b = np.sum(w * (sw * data.e), axis=0) / np.sum(w * w, axis=0)
    return sw * data.e - w * b, w


def test_wheel_transform_is_the_inverse_square_root_of_the_random_intercept_covariance(
        monkeypatch):
    data = alt_data(0.2, 113)
    monkeypatch.setattr(fre, "LEVELS", "wheel")
    for key in fre._CACHE_KEYS:
        data.cache.pop(key, None)
    try:
        codes = fre._group_codes(data)
        r, loading = _baseline_residual(data)
        w = loading.reshape(-1)
        y = (np.sqrt(data.weights) * data.e).reshape(-1)
        s_u2, s_e2 = fre.variance_components(r, loading, codes)
        assert np.all(s_u2 > 0) and np.all(s_e2 > 0)
        qy = fre.quasi_demean(data, y)
        for g in np.unique(codes)[:12]:   # (Q y)'(Q y) = s_e^2 y' V^-1 y per (wheel, region)
            sel = codes == g
            k = g % 2
            v = s_e2[k] * np.eye(sel.sum()) + s_u2[k] * np.outer(w[sel], w[sel])
            assert qy[sel] @ qy[sel] == pytest.approx(
                s_e2[k] * y[sel] @ np.linalg.solve(v, y[sel]), rel=1e-9)
        c = fre.shrinkage(data)
        assert np.all((c >= 0.0) & (c < 1.0)) and np.ptp(c) > 0.0
    finally:
        for key in fre._CACHE_KEYS:
            data.cache.pop(key, None)


def test_nested_components_recover_the_simulated_ones():
    rng = np.random.default_rng(5)
    vehicles, wheels, per = 150, 8, 6
    s_v, s_u, s_e = np.array([0.15, 0.1]), np.array([0.1, 0.2]), np.array([0.05, 0.04])
    n = vehicles * wheels * per
    veh = np.repeat(np.arange(vehicles), wheels * per)
    whl = np.repeat(np.arange(vehicles * wheels), per)
    w = rng.uniform(0.5, 1.0, (n, 2))
    y = w * (rng.normal(size=(vehicles, 2))[veh] * s_v + rng.normal(size=(vehicles * wheels,
                                                                           2))[whl] * s_u) \
        + rng.normal(size=(n, 2)) * s_e
    region = np.tile(np.arange(2), n)
    s_v2, s_u2, s_e2 = fre.nested_components(y, w, np.repeat(whl, 2) * 2 + region,
                                             np.repeat(veh, 2) * 2 + region)
    np.testing.assert_allclose(np.sqrt(s_v2), s_v, rtol=0.15)
    np.testing.assert_allclose(np.sqrt(s_u2), s_u, rtol=0.12)
    np.testing.assert_allclose(np.sqrt(s_e2), s_e, rtol=0.05)


def test_nested_transform_is_the_inverse_square_root_of_the_vehicle_and_wheel_covariance():
    # T = Q_v Q_w: (T y)'(T y) = s_e^2 y' V^-1 y per (vehicle, region) block with
    # V = s_e^2 I + s_u^2 sum_j w_j w_j' + s_v^2 w w' (wheels j of the vehicle), and T' is
    # the transpose of T
    data = alt_data(0.2, 113)
    assert fre.LEVELS == "vehicle_wheel"
    wheel = fre._group_codes(data)
    vehicle = fre._group_codes(data, "vehicle_id")
    r, loading = _baseline_residual(data)
    s_v2, s_u2, s_e2 = fre.nested_components(r, loading, wheel, vehicle)
    assert np.all(s_v2 > 0) and np.all(s_u2 > 0)
    w = loading.reshape(-1)
    y = (np.sqrt(data.weights) * data.e).reshape(-1)
    ty = fre.quasi_demean(data, y)
    for g in np.unique(vehicle)[:6]:
        sel = vehicle == g
        k = g % 2
        v = s_e2[k] * np.eye(sel.sum()) + s_v2[k] * np.outer(w[sel], w[sel])
        for j in np.unique(wheel[sel]):
            wj = np.where(wheel[sel] == j, w[sel], 0.0)
            v += s_u2[k] * np.outer(wj, wj)
        assert ty[sel] @ ty[sel] == pytest.approx(
            s_e2[k] * y[sel] @ np.linalg.solve(v, y[sel]), rel=1e-8)
    x = np.random.default_rng(0).normal(size=(y.size, 2))
    assert fre.quasi_demean_transpose(data, x).T @ x[:, ::-1] == pytest.approx(
        x.T @ fre.quasi_demean(data, x[:, ::-1]), rel=1e-9)


def test_vehicle_transform_is_the_inverse_square_root_of_the_vehicle_covariance():
    # Q_v (the tests' metric, ``finder_scoring.SCORE_METRIC = "gls_vehicle"``): one random
    # log-scale per (vehicle, region), the wheels' scatter counted as the measurements'
    data = alt_data(0.2, 113)
    vehicle = fre._group_codes(data, "vehicle_id")
    r, loading = _baseline_residual(data)
    s_v2, s_e2 = fre.variance_components(r, loading, vehicle)
    assert np.all(s_v2 > 0)
    w = loading.reshape(-1)
    y = (np.sqrt(data.weights) * data.e).reshape(-1)
    qy = fre.vehicle_demean(data, y)
    for g in np.unique(vehicle):
        sel = vehicle == g
        k = g % 2
        v = s_e2[k] * np.eye(sel.sum()) + s_v2[k] * np.outer(w[sel], w[sel])
        assert qy[sel] @ qy[sel] == pytest.approx(
            s_e2[k] * y[sel] @ np.linalg.solve(v, y[sel]), rel=1e-8)
    # a vehicle's level is (mostly) gone, a contrast within the vehicle is kept whole
    x = np.where(vehicle == vehicle[0], w, 0.0)
    contrast = x * np.where(np.arange(x.size) % 4 < 2, 1.0, -1.0)
    contrast -= x * (x @ contrast) / (x @ x)
    assert np.linalg.norm(fre.vehicle_demean(data, x)) < 0.5 * np.linalg.norm(x)
    np.testing.assert_allclose(fre.vehicle_demean(data, contrast), contrast, atol=1e-12)


def test_resampled_gains_score_in_the_tests_metric_as_the_data():
    # traction (GLS fit, nested effects) scored held out after the vehicle transform: the
    # linearised gain of the resampling test equals the gain computed on the data
    data = alt_data(0.2, 113)
    folds = _folds(data.frame["vehicle_id"].astype(str).to_numpy(), 5, 0)
    traction = cz.cause_by_code("traction")
    sw = np.sqrt(data.weights)

    def loss(residual):
        z = fre.vehicle_demean(data, (sw * residual).reshape(-1))
        return np.sum(z ** 2)

    gain = 1.0 - loss(fs.held_out(data, traction, folds)) \
        / loss(fs.held_out(data, cz.NullArea(), folds))
    y = (sw * data.e).reshape(-1, 1)
    null_design = fs.area_design(data, np.zeros((data.n, 2, 0)))
    design = fs.area_design(data, traction.features(data, traction.start()))
    re = fs.RandomEffectsFit(lambda v: fre.quasi_demean(data, v), None,
                             [np.array([False, False, True])],
                             score=lambda v: fre.vehicle_demean(data, v), scored=[True])
    linearised = fs.bootstrap_gains(null_design, [design], y, np.repeat(folds, 2), re)
    assert linearised[0, 0] == pytest.approx(gain, abs=1e-10)


def test_resampled_gains_use_the_estimator_of_the_data():
    # the linearised held-out gain of the resampling test equals the cause's own held-out
    # gain (the season is linear): both fit theta by GLS and the scales by least squares
    data = alt_data(0.2, 113)
    folds = _folds(data.frame["vehicle_id"].astype(str).to_numpy(), 5, 0)
    season = cz.cause_by_code("seasonal_friction")

    def loss(residual):
        return np.sum(data.weights * residual ** 2)

    gain = 1.0 - loss(fs.held_out(data, season, folds)) \
        / loss(fs.held_out(data, cz.NullArea(), folds))
    y = (np.sqrt(data.weights) * data.e).reshape(-1, 1)
    null_design = fs.area_design(data, np.zeros((data.n, 2, 0)))
    design = fs.area_design(data, season.features(data, season.start()))
    re = fs.RandomEffectsFit(lambda v: fre.quasi_demean(data, v), None,
                             [np.array([False, False, True, True])])
    linearised = fs.bootstrap_gains(null_design, [design], y, np.repeat(folds, 2), re)
    assert linearised[0, 0] == pytest.approx(gain, abs=1e-10)
    ols = fs.bootstrap_gains(null_design, [design], y, np.repeat(folds, 2))
    assert abs(ols[0, 0] - gain) > 1e-4     # the GLS fit is not the OLS one


def test_two_stage_map_gives_the_coefficients_and_the_interval_covers_the_season():
    data = alt_data(0.2, 113)
    season = cz.cause_by_code("seasonal_friction")
    design = fs.area_design(data, season.features(data, season.start()))
    y = (np.sqrt(data.weights) * data.e).reshape(-1)
    mask = np.array([False, False, True, True])
    coef = fre.two_stage(design, y, fre.quasi_demean(data, design), fre.quasi_demean(data, y),
                         mask)
    lmap = fre.two_stage_map(design, fre.quasi_demean(data, design), mask,
                             lambda v: fre.quasi_demean_transpose(data, v))
    np.testing.assert_allclose(lmap @ y, coef, atol=1e-10)
    everything = np.ones(data.n, dtype=bool)
    vehicle = data.frame["vehicle_id"].astype(str).to_numpy()
    est = season.fit(data, everything, cluster=vehicle)
    np.testing.assert_allclose(est.theta_, coef[2:], atol=1e-10)
    amp = est.intervals()["amplitude"]
    # fleet_twin_alt: rate x (1 + 0.2 sin(2 pi (doy - 110) / 365.25))
    assert amp["ci95_low"] <= 0.2 <= amp["ci95_high"]


@pytest.mark.parametrize("seed", [105, 113])
def test_weak_alt_season_is_named_and_its_null_gives_none(seed):
    for amplitude, expected in ((0.2, "seasonal_friction"), (0.0, "none")):
        s = scenarios.alt_scenario(fa.AltEffects(seasonal_amplitude=amplitude), seed)
        args, kwargs = s.finder_arguments()
        d = diagnose(*args, **kwargs, n_boot=300)
        assert d.verdict == expected, (amplitude, d.runner_up, d.margin, d.candidates,
                                       findings_summary(d))


@pytest.mark.slow
def test_season_amplitude_interval_coverage_over_runs():
    # issue 13 item 4: the 95 % interval of the GLS amplitude (sandwich of the two-stage
    # estimator, vehicle clusters, t with groups - 1 dof) covers the injected 0.2 in >= 90 %
    # of 20 fleet_twin_alt datasets (measured: 19 of 20)
    covered = 0
    for seed in range(100, 120):
        data = alt_data(0.2, seed)
        everything = np.ones(data.n, dtype=bool)
        est = cz.cause_by_code("seasonal_friction").fit(
            data, everything, cluster=data.frame["vehicle_id"].astype(str).to_numpy())
        amp = est.intervals()["amplitude"]
        covered += amp["ci95_low"] <= 0.2 <= amp["ci95_high"]
    assert covered >= 18
