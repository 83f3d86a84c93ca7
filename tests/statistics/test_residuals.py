"""Residuals of the calibrated hybrid model (seed 001 eqs. 2-4)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from wearcast.statistics import hybrid
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.generators import twin_routes, twin_wear_table
from wearcast.statistics.residuals import geometric_basis, log_residual, model_residuals
from wearcast.statistics.route_measure import leading_shares, route_parts, weighted_wear_measure
from wearcast.statistics.wear_tables import compile_wear_table

TABLE = twin_wear_table.synthetic_wear_table()
ROUTE = te.to_route(twin_routes.aosta_route())


def _exact_frame(model, mileage=(20_000.0, 80_000.0, 150_000.0)):
    rows = []
    for bogie in ("motor", "trailer"):
        for axle in (1, 2):
            for side in ("left", "right"):
                p = {r: weighted_wear_measure(
                    ROUTE, TABLE, bogie_type=bogie, axle=axle, side=side,
                    running_mode="mixed", region=r, measure="tau_max")
                    for r in ("flange", "tread")}
                for s in mileage:
                    rows.append({"wheel_id": f"{bogie}{axle}{side}", "bogie_type": bogie,
                                 "axle": axle, "side": side, "mileage_km": s,
                                 "route": ROUTE.name,
                                 "flange_area_mm2": model.flange.c_s * p["flange"] * s,
                                 "tread_area_mm2": model.tread.c_s * p["tread"] * s})
    return pd.DataFrame(rows)


@pytest.fixture(scope="module")
def model():
    cfg = te.scenario_config(seed=1, vehicles_per_unit=1)
    twin = ft.generate_fleet(cfg, TABLE)
    df, curves = te.twin_measurements(twin)
    routes, _ = te.scenario_routes(cfg)
    return hybrid.calibrate(df, routes, TABLE, wear_curves_mm=curves, measure="tau_max",
                            running_mode="mixed")


def test_residuals_vanish_when_data_follow_the_model(model):
    frame = _exact_frame(model)
    res = model_residuals(model, frame, {ROUTE.name: ROUTE}, TABLE)
    assert np.allclose(res.log_residual, 0.0, atol=1e-12)
    assert np.allclose(res.frame["rate_res_tread"], 0.0, atol=1e-15)


def test_residuals_measure_a_known_multiplicative_error(model):
    frame = _exact_frame(model)
    frame["tread_area_mm2"] *= 1.25
    res = model_residuals(model, frame, {ROUTE.name: ROUTE}, TABLE)
    # floored log residual: log((1.25 A + a0) / (A + a0)) lies between 0 and log 1.25
    e = res.frame["logres_tread"].to_numpy()
    assert np.all(e > 0) and np.all(e <= np.log(1.25) + 1e-12)
    big = res.predicted_mm2[:, 1] > 20 * res.floor_mm2[1]
    assert np.allclose(e[big], np.log(1.25), atol=0.02)


def test_route_parts_sum_to_the_weighted_measure():
    wt = compile_wear_table(TABLE)
    for side in ("left", "right"):
        parts = route_parts(ROUTE, wt, bogie_type="motor", side=side, region="flange",
                            measure="tau_max")
        for axle, row in ((1, 0), (2, 1)):
            p = weighted_wear_measure(ROUTE, wt, bogie_type="motor", axle=axle,
                                             side=side, running_mode="lead", region="flange",
                                             measure="tau_max")
            assert parts[row].sum() == pytest.approx(p, rel=1e-12)


def test_mirror_symmetry_of_a_symmetric_route():
    # Aosta classes are split into equal left/right halves: left and right wheels see the same P
    wt = compile_wear_table(TABLE)
    left = route_parts(ROUTE, wt, bogie_type="trailer", side="left", region="flange",
                       measure="t_gamma")
    right = route_parts(ROUTE, wt, bogie_type="trailer", side="right", region="flange",
                        measure="t_gamma")
    assert left.sum() == pytest.approx(right.sum(), rel=1e-12)
    assert left[:, 1] == pytest.approx(right[:, 2])


def test_leading_shares_and_log_residual_limits():
    assert leading_shares([1, 2, 1, 2], ["lead", "lead", "mixed", "mixed"]).tolist() == \
        [1.0, 0.0, 0.5, 0.5]
    e = log_residual([[10.0, 0.0]], [[5.0, 0.0]], [1.0, 1.0])
    assert e[0, 0] == pytest.approx(np.log(11 / 6))
    assert e[0, 1] == 0.0
    # antisymmetric in measured/predicted
    assert log_residual([[5.0]], [[10.0]], [1.0])[0, 0] == pytest.approx(-e[0, 0])


def test_geometric_basis_shapes():
    y = np.linspace(-58, 50, 217)
    b = geometric_basis(y, -30.0)
    assert b.shape == (3, y.size)
    assert np.all(b[1, y >= -30] == 0.0)            # flange offset only on the flange
    assert b[0, np.argmin(np.abs(y))] == pytest.approx(0.0, abs=1e-9)  # scale about y = 0
