"""Residual structure outside the catalogue (statistics/finder_structure.py)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from wearcast.statistics.finder_structure import level_effects, structure_factors, structure_share


def test_structure_share_is_one_for_level_means_and_small_for_noise():
    rng = np.random.default_rng(3)
    factor = np.repeat(np.array(["a", "b", "c"]), 40)
    level = {"a": 0.2, "b": -0.1, "c": -0.1}
    residual = np.stack([[level[f], -level[f]] for f in factor])        # (n, 2): only the levels
    weight = np.ones_like(residual)
    assert abs(float(structure_share(residual, weight, factor)[0]) - 1.0) < 1e-12
    noise = rng.normal(0.0, 1.0, residual.shape)
    share = float(structure_share(noise, weight, factor)[0])
    # three level means of 40 standard normal rows explain about 3 / 120 of the sum of squares
    assert 0.0 <= share < 0.1
    # a (n, m, B) stack of resamples gives one share per resample, the same as column by column
    stack = np.stack([noise, residual], axis=2)
    both = structure_share(stack, weight, factor)
    assert both.shape == (2,)
    assert abs(both[0] - share) < 1e-12 and abs(both[1] - 1.0) < 1e-12


def test_level_effects_give_each_levels_rate_change_in_percent():
    factor = np.array(["x"] * 5 + ["y"] * 5)
    residual = np.stack([np.r_[np.full(5, np.log(1.1)), np.full(5, np.log(0.9))],
                         np.zeros(10)], axis=1)
    rows = level_effects(residual, np.ones_like(residual), factor, ["tread", "flange"])
    assert [r["level"] for r in rows] == ["x", "y"] and [r["n"] for r in rows] == [5, 5]
    assert abs(rows[0]["tread_rate_change_pct"] - 10.0) < 1e-9
    assert abs(rows[1]["tread_rate_change_pct"] + 10.0) < 1e-9
    assert rows[0]["flange_rate_change_pct"] == 0.0


def test_structure_factors_keep_groupings_with_two_populated_levels():
    frame = pd.DataFrame({"bogie_type": ["motor"] * 10 + ["trailer"] * 10,
                          "axle": [1] * 20, "side": ["left", "right"] * 10,
                          "instrument_id": ["only"] * 20,
                          "measured_on": pd.date_range("2024-01-01", periods=20, freq="20D")})
    factors = structure_factors(frame, np.arange(20.0) * 1000.0, min_rows=4)
    assert set(factors) == {"wheel_position", "date_quarter", "mileage"}   # one instrument: no
    assert len(set(factors["wheel_position"])) == 4
