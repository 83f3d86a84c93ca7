"""The finder's null for wear that is nonlinear by physics (``discrepancy_progression``).

A simulation of the route says how a wheel's wear grows with mileage; the finder's baseline
then grows that way, and ``nonlinear_progression`` is a departure from it. The fleet-twin
checks below hide a power-law progression in every wheel and give the finder (a) nothing,
(b) that very progression as the expected one, (c) a different one.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.discrepancy_progression import (
    ExpectedProgression,
    SimulatedWheel,
    progression_from_simulations,
)
from wearcast.statistics.generators import scenarios, twin_wear_table
from wearcast.statistics.generators import twin_effects as te

S_REF_KM = 100_000.0
TABLE = twin_wear_table.synthetic_wear_table()


def power_progression(beta: float) -> ExpectedProgression:
    """The expected progression A ~ s^beta on every wheelset position and region."""
    s = np.linspace(5_000.0, 250_000.0, 50)
    area = s * (s / S_REF_KM) ** (beta - 1.0)
    keys = [(b, w, r) for b in ("motor", "trailer") for w in ("leading", "trailing")
            for r in ("flange", "tread")]
    return ExpectedProgression.from_areas(s, {k: area for k in keys}, source=f"s^{beta}")


def test_factor_is_area_over_least_squares_linear_growth():
    s = np.array([10.0, 20.0, 40.0])
    area = np.array([1.0, 1.5, 2.0])                      # decelerating wear
    ep = ExpectedProgression.from_areas(s, {("motor", "leading", "tread"): area})
    k = np.sum(area * s) / np.sum(s * s)
    np.testing.assert_allclose(ep.factors[("motor", "leading", "tread")], area / (k * s))
    # log-log interpolation between grid points, ends held, 1 at s = 0
    g = ep.factor("motor", "leading", "tread", [0.0, 5.0, np.sqrt(10.0 * 20.0), 80.0])
    f = ep.factors[("motor", "leading", "tread")]
    np.testing.assert_allclose(g, [1.0, f[0], np.sqrt(f[0] * f[1]), f[2]])
    with pytest.raises(ValueError, match="trailer"):
        ep.factor("trailer", "leading", "tread", [10.0])


def test_row_factor_mixes_wheelsets_by_their_share_of_the_measure():
    s = np.array([10.0, 20.0])
    ep = ExpectedProgression(s, {("motor", "leading", r): np.array([2.0, 2.0]) for r in
                                 ("flange", "tread")}
                             | {("motor", "trailing", r): np.array([0.5, 0.5]) for r in
                                ("flange", "tread")})
    parts = np.zeros((3, 2, 2, 2, 3))
    parts[:, 0, :, 0, 0] = 3.0      # leading measure 3, trailing 1 (tau_max, both regions)
    parts[:, 0, :, 1, 0] = 1.0
    out = ep.row_factors(["motor"] * 3, [15.0] * 3, parts, [1.0, 0.0, 0.5], 0)
    mixed = (0.5 * 3.0 * 2.0 + 0.5 * 1.0 * 0.5) / (0.5 * 3.0 + 0.5 * 1.0)
    np.testing.assert_allclose(out[:, 0], [2.0, 0.5, mixed])
    np.testing.assert_allclose(out[:, 1], out[:, 0])


def test_bad_progressions_are_refused():
    with pytest.raises(ValueError, match="mileage_km"):
        ExpectedProgression(np.array([10.0, 5.0]), {})
    with pytest.raises(ValueError, match="factors"):
        ExpectedProgression(np.array([10.0, 20.0]), {("motor", "leading", "tread"):
                                                     np.array([1.0, -1.0])})


@lru_cache(maxsize=4)
def _diagnosed(expected_beta: float | None):
    s = scenarios.twin_scenario((te.nonlinear_progression(0.8, S_REF_KM),), (), seed=3,
                                table=TABLE)
    args, kwargs = s.finder_arguments()
    ep = None if expected_beta is None else power_progression(expected_beta)
    return diagnose(*args, **kwargs, expected_progression=ep,
                    causes=["traction", "nonlinear_progression", "seasonal_friction",
                            "vehicle_load"])


def test_progression_the_simulation_expects_is_not_a_discrepancy():
    d = _diagnosed(0.8)
    assert d.verdict == "none", [(f.cause, f.gain.relative, f.evidence["p_value"])
                                 for f in d.findings]
    assert "expected progression" in d.null_test


def test_without_the_simulation_the_same_data_name_nonlinear_progression():
    d = _diagnosed(None)
    assert d.verdict == "nonlinear_progression"
    beta = d.finding("nonlinear_progression").evidence["intervals"]["beta_tread"]
    assert beta["value"] == pytest.approx(0.8, abs=0.03), beta


def test_a_departure_from_the_expected_progression_is_named_with_the_total_exponent():
    # the simulation expects s^0.95, the wheels wear as s^0.8: the departure is named and the
    # reported exponent is the total (expected 0.95 plus the fitted departure)
    d = _diagnosed(0.95)
    assert d.verdict == "nonlinear_progression"
    f = d.finding("nonlinear_progression")
    params = f.extension["parameters"]
    assert params["expected_beta_tread"] == pytest.approx(0.95, abs=0.01)
    beta = f.evidence["intervals"]["beta_tread"]
    assert beta["value"] == pytest.approx(0.8, abs=0.03), beta
    assert f.extension["parameters"]["beta_tread"] == pytest.approx(beta["value"])


def _run(bogie, axle, beta, depth_mm=1.0, flange_share=0.5):
    """A wear-loop-like run whose worn areas grow as s^beta: a flange bump (y < -30) and a
    tread bump (y >= -30) of known areas at the last step."""
    y = np.linspace(-70.0, 60.0, 521)
    s = np.linspace(0.0, 40_000.0, 9)
    shape_f = flange_share * np.exp(-((y + 40.0) / 3.0) ** 2)
    shape_t = (1.0 - flange_share) * np.exp(-((y - 5.0) / 8.0) ** 2)
    growth = (s / s[-1]) ** beta
    profiles = -depth_mm * growth[:, None] * (shape_f + shape_t)[None, :]
    return SimulatedWheel(bogie, axle, y, profiles, s)


def test_simulated_areas_are_the_integrated_wear_of_each_region():
    run = _run("motor", 1, 1.0)
    areas = run.region_areas_mm2(np.array([20_000.0, 40_000.0, 50_000.0]))
    flange = 0.5 * 3.0 * np.sqrt(np.pi)  # integral of the flange bump at the end [mm^2]
    tread = 0.5 * 8.0 * np.sqrt(np.pi)
    assert areas["flange"] == pytest.approx([flange / 2, flange, flange], rel=1e-3)
    assert areas["tread"] == pytest.approx([tread / 2, tread, tread], rel=1e-3)  # end held


def test_progression_from_simulations_recovers_the_power_law():
    runs = [_run(b, a, 0.7) for b in ("motor", "trailer") for a in (1, 2)]
    runs.append(_run("motor", 1, 0.7, depth_mm=3.0))  # the other side: averaged, same shape
    expected = progression_from_simulations(runs, "test")
    grid = np.asarray(expected.mileage_km)
    assert grid[-1] == pytest.approx(40_000.0) and grid.size == 20
    # the runs' wear is linear between their steps (every 5,000 km): s^0.7 interpolated
    steps = np.linspace(0.0, 40_000.0, 9)
    area = np.interp(grid, steps, steps ** 0.7)
    k = np.sum(area * grid) / np.sum(grid ** 2)  # least-squares slope through the origin
    for key, g in expected.factors.items():
        assert g == pytest.approx(area / (k * grid), rel=1e-6), key
    assert g[0] > 1.3 and g[-1] < 0.95  # sublinear: above the straight line early
    linear = progression_from_simulations([_run("motor", 2, 1.0)], "linear")
    assert linear.factors[("motor", "trailing", "flange")] == pytest.approx(1.0)
    assert set(linear.factors) == {("motor", "trailing", r) for r in ("flange", "tread")}


def test_progression_from_simulations_refuses_bad_runs():
    with pytest.raises(ValueError, match="simulations"):
        progression_from_simulations([], "none")
    bad = _run("motor", 3, 1.0)
    with pytest.raises(ValueError, match="axle"):
        progression_from_simulations([bad], "bad")
