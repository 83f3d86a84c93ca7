"""The vectorised reprofiling search and prediction against the scalar algorithms they replace.

The reference here is the previous implementation, kept as test code: a geometric grid of 80
mileages per rate quantile, each profile evaluated on its own, then Brent's method on the
smallest limit margin (tightened to 1e-9 relative). The vectorised search promises the
crossing to within max(0.1 % of the mileage, 50 km) (``MILEAGE_RTOL``/``MILEAGE_ATOL_KM``).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.ndimage import uniform_filter1d
from scipy.optimize import brentq

from tests.statistics import _reprofiling_helpers as fixtures
from wearcast.statistics import hybrid_prediction, hybrid_profiles, reprofiling
from wearcast.statistics.hybrid_prediction import predict, region_rates
from wearcast.statistics.hybrid_profiles import parameters_at_areas, profile_at_areas
from wearcast.statistics.profile_parameters import WheelLimits, flange_parameters
from wearcast.statistics.reprofiling import (
    MILEAGE_ATOL_KM,
    MILEAGE_RTOL,
    _margins,
    reprofiling_mileage,
)
from wearcast.statistics.route_measure import weighted_wear_measure, wheelset_weights
from wearcast.statistics.routes import Route, RouteClass, rail_for
from wearcast.statistics.wear_states import (
    join_regions,
    wear_curve_at_area,
    wear_curves_at_areas,
)
from wearcast.statistics.wear_tables import (
    RadiusOutOfTableError,
    compile_wear_table,
    table_value,
)

KW = {"bogie_type": "motor", "axle": 1}
Y, SPLIT, ROUTE, TANGENT = fixtures.Y, fixtures.SPLIT, fixtures.ROUTE, fixtures.TANGENT
_table, _model = fixtures.table, fixtures.model


def _brentq_reference(model, route, table, limits, start, *, side):
    """P10/P50/P90 reprofiling mileages by the previous scalar algorithm [km]."""
    start = {"flange": 0.0, "tread": 0.0, **(start or {})}
    _, rates = region_rates(model, route, table, side=side, quantiles=(0.9, 0.5, 0.1), **KW)
    out = []
    for q in range(3):

        def worst(s, q=q):
            s = np.atleast_1d(np.asarray(s, dtype=float))
            _, _, params, _ = profile_at_areas(model, start["flange"] + rates["flange"][q] * s,
                                               start["tread"] + rates["tread"][q] * s)
            return _margins(params, limits).min(axis=1)

        grid = np.concatenate([[0.0], np.geomspace(30.0, 3e6, 80)])
        crossed = np.flatnonzero(worst(grid) < 0)
        if crossed.size == 0 or crossed[0] == 0:
            out.append(np.inf if crossed.size == 0 else 0.0)
            continue
        lo, hi = grid[crossed[0] - 1], grid[crossed[0]]
        out.append(brentq(lambda s: float(worst(s)[0]), lo, hi, xtol=1e-9 * hi, rtol=1e-12))
    return out


CASES = list(itertools.product(
    [(1e-5, 2e-6), (2e-5, 5e-6), (5e-5, 2e-5)],  # c_s flange, tread
    [0.05, 0.2],  # relative spread of c_s
    ["left", "right"],
    [ROUTE, TANGENT],
    [WheelLimits(), WheelLimits(qr_min_mm=9.5), WheelLimits(sd_min_mm=28.0, sh_max_mm=30.0)],
    [None, {"flange": 5.0, "tread": 20.0}],
))


@pytest.fixture(scope="module")
def table():
    return compile_wear_table(_table())


@pytest.mark.parametrize("case", range(0, len(CASES), 3))
def test_vectorised_search_finds_the_brent_crossing(case, table):
    (c_f, c_t), rel, side, route, limits, start = CASES[case]
    model = _model(c_f, c_t, rel)
    expected = _brentq_reference(model, route, table, limits, start, side=side)
    res = reprofiling_mileage(model, route, table, side=side, limits=limits, start_areas=start,
                              **KW)
    got = [res.mileage_p10_km, res.mileage_p50_km, res.mileage_p90_km]
    for e, g in zip(expected, got, strict=True):
        if not np.isfinite(e) or e == 0.0:
            assert g == e
            continue
        # the promised tolerance; measured on these cases: below 3e-6 relative (< 2 km)
        assert abs(g - e) <= max(MILEAGE_RTOL * e, MILEAGE_ATOL_KM)
        assert g == pytest.approx(e, rel=1e-4)
    if res.reached:
        value = {"sd": res.sd_mm - limits.sd_min_mm, "sh": limits.sh_max_mm - res.sh_mm,
                 "qr": res.qr_mm - limits.qr_min_mm}
        assert value[res.governing_limit] == pytest.approx(0.0, abs=1e-3)
        assert min(value.values()) >= -1e-3


def test_parameters_without_whole_profiles_are_exact(table, monkeypatch):
    model = _model()
    fa = np.linspace(0.0, 90.0, 61)
    ta = np.linspace(0.0, 300.0, 61)[::-1].copy()
    full = profile_at_areas(model, fa, ta)
    params, extra = parameters_at_areas(model, fa, ta)
    np.testing.assert_array_equal(extra, full[3])
    np.testing.assert_allclose(params, full[2], atol=1e-9, equal_nan=True)
    # with a prefix that stops before the flank every profile takes the whole-grid path
    monkeypatch.setattr(hybrid_profiles, "PARAMETER_MAX_Y_MM", -45.0)
    fresh = _model()
    assert fresh.parameter_columns.size < model.parameter_columns.size
    np.testing.assert_allclose(parameters_at_areas(fresh, fa, ta)[0], full[2], atol=1e-9,
                               equal_nan=True)


def test_joined_states_reproduce_joining_each_curve(table):
    # joining is linear: W_f J_f + W_t J_t must equal join(wear_f(A_f), wear_t(A_t)) and the
    # profile's parameters must be those of flange_parameters on the joined profile
    model = _model()
    fa, ta = np.array([0.0, 3.0, 40.0, 75.0]), np.array([150.0, 0.0, 80.0, 400.0])
    wf, ef = wear_curves_at_areas(model.states, "flange", fa)
    wt, et = wear_curves_at_areas(model.states, "tread", ta)
    joined = join_regions(model.grid_y_mm, wf, wt, model.split_y_mm, model.join_window_mm)
    wear, z, params, extra = profile_at_areas(model, fa, ta)
    np.testing.assert_allclose(wear, joined, atol=1e-12)
    np.testing.assert_array_equal(extra, ef | et)
    for i in range(fa.size):
        p = flange_parameters(model.grid_y_mm, z[i])
        np.testing.assert_allclose(params[i], (p.sd_mm, p.sh_mm, p.qr_mm), atol=1e-12)
    for area in (0.0, 7.5, 61.0, 200.0):  # beyond the last state: scaled and flagged
        curve, flag = wear_curve_at_area(model.states, "flange", area)
        many, flags = wear_curves_at_areas(model.states, "flange", np.array([area]))
        np.testing.assert_allclose(many[0], curve, atol=1e-12)
        assert flags[0] == flag == (area > model.states.flange.areas_mm2[-1])


@pytest.mark.parametrize("split", [-30.0, -56.5, 48.0])
def test_join_smooths_only_near_the_split_as_a_whole_grid_filter(split):
    # the moving average is computed on the columns it needs only; at the grid's ends the
    # 'nearest' padding must act as on the whole grid
    y = np.linspace(-58.0, 50.0, 217)
    rng = np.random.default_rng(3)
    f, t = rng.normal(size=(4, y.size)), rng.normal(size=(4, y.size))
    joined = join_regions(y, f, t, split, 4.0)
    whole = np.where(y < split, f, t)
    smooth = uniform_filter1d(whole, size=9, axis=-1, mode="nearest")
    expected = np.where(np.abs(y - split) <= 2.0, smooth, whole)
    np.testing.assert_allclose(joined, expected, atol=1e-12)


def _loop_measure(route, wt, *, axle, side, running_mode, region, measure):
    """Seed 001 eq. 2 class by class, as before vectorising."""
    total = 0.0
    for c in route.classes:
        if c.share == 0.0:
            continue
        p_i = sum(w * table_value(wt, "motor", ws, rail_for(c, side), c.radius_m, region,
                                  measure)
                  for ws, w in wheelset_weights(axle, running_mode).items())
        total += c.share * p_i
    return total


def test_vectorised_weighted_measure_is_the_class_by_class_sum(table):
    rng = np.random.default_rng(11)
    for _ in range(20):
        n = int(rng.integers(1, 12))
        shares = rng.dirichlet(np.ones(n))
        shares[rng.uniform(size=n) < 0.2] = 0.0
        shares = shares / shares.sum() if shares.sum() > 0 else np.full(n, 1.0 / n)
        classes = tuple(
            RouteClass(None, None, 0.0, 80.0, float(s)) if rng.uniform() < 0.3 else
            RouteClass(float(rng.uniform(250.0, 5000.0)), str(rng.choice(["left", "right"])),
                       50.0, 80.0, float(s))
            for s in shares)
        route = Route("random", classes)
        for axle, side, mode, region in itertools.product(
                (1, 2), ("left", "right"), ("lead", "mixed"), ("flange", "tread")):
            fast = weighted_wear_measure(route, table, bogie_type="motor", axle=axle,
                                         side=side, running_mode=mode, region=region,
                                         measure="tau_max")
            assert fast == _loop_measure(route, table, axle=axle, side=side, running_mode=mode,
                                         region=region, measure="tau_max")
    tight = Route("tight", (RouteClass(100.0, "left", 0.0, 40.0, 1.0),))
    with pytest.raises(RadiusOutOfTableError, match="radius_m"):  # as the class-by-class sum
        weighted_wear_measure(tight, table, bogie_type="motor", axle=1, side="left",
                              running_mode="lead", region="flange", measure="tau_max")


def test_given_weighted_measures_give_the_same_prediction(table):
    model = _model()
    kw = {**KW, "side": "right", "mileage_km": [0.0, 1e5, 3e5]}
    base = predict(model, ROUTE, table, **kw)
    p_s = hybrid_prediction.model_weighted_measures(model, ROUTE, table, bogie_type="motor", axle=1,
                                                    side="right")
    given = predict(model, ROUTE, table, weighted_measures=p_s, **kw)
    assert given.weighted_measure == base.weighted_measure
    np.testing.assert_array_equal(given.z_mm, base.z_mm)
    res = reprofiling.reprofiling_mileage(model, ROUTE, table, side="right",
                                          weighted_measures=p_s, **KW)
    assert res == reprofiling.reprofiling_mileage(model, ROUTE, table, side="right", **KW)
