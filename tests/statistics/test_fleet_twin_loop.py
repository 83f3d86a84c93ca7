"""Fleet twin with the wear loop as its truth (issue 5)."""

import numpy as np
import pytest

from wearcast.statistics.generators.fleet_twin import (
    FleetConfig,
    TwinRoute,
    UnitConfig,
)
from wearcast.statistics.generators.fleet_twin_loop import LoopTruth, generate_loop_fleet
from wearcast.statistics.processing import process_profile
from wearcast.statistics.routes import RouteClass

ROUTE = TwinRoute("loop-line", (RouteClass(None, None, 0.0, 70.0, 0.6),
                                RouteClass(500.0, "left", 60.0, 60.0, 0.2),
                                RouteClass(500.0, "right", 60.0, 60.0, 0.2)))


@pytest.fixture(scope="module")
def twin():
    config = FleetConfig(units=(UnitConfig("L", ROUTE, running_mode="lead"),),
                         bogies=("trailer",), axles=(1,), mileages_km=(500.0, 1000.0, 2000.0),
                         mileage_jitter_km=0.0, rate_scatter=0.0, area_scatter=0.0, seed=3)
    return generate_loop_fleet(config, LoopTruth(n_steps=4))


def test_profiles_are_long_csv_and_truth_comes_from_the_loop(twin):
    fleet = twin.fleet
    assert set(fleet.profiles.groupby(["wheel_id", "mileage_km"]).groups) == {
        (w, m) for w in ("L1-T1L", "L1-T1R") for m in (500, 1000, 2000)}
    # one loop run per (route, bogie, axle, side)
    assert sorted(twin.simulations) == [("loop-line", "trailer", 1, s) for s in ("left", "right")]
    truth = fleet.truth.sort_values(["wheel_id", "mileage_km"])
    for _, rows in truth.groupby("wheel_id"):
        # the loop's wear grows with mileage, in both regions
        assert np.all(np.diff(rows.tread_area_mm2) > 0) and np.all(np.diff(rows.flange_area_mm2)
                                                                   >= 0)
    # no scatter: the true curve IS the loop's wear at that mileage
    right = twin.simulations[("loop-line", "trailer", 1, "right")]
    row = truth[(truth.wheel_id == "L1-T1R") & (truth.mileage_km == 2000)].iloc[0]
    assert row.max_depth_mm == pytest.approx(right.wear_at(2000.0).max(), rel=1e-9)


def test_symmetric_route_wears_left_and_right_wheels_alike(twin):
    # equal shares of left and right 500 m curves: mirror symmetry of the quasi-static bogie
    t = twin.fleet.truth.set_index(["side", "mileage_km"])
    for km in (500.0, 1000.0, 2000.0):
        assert t.loc[("left", km), "tread_area_mm2"] == pytest.approx(
            t.loc[("right", km), "tread_area_mm2"], rel=1e-6)


def test_processing_recovers_the_true_areas(twin):
    # measurement noise 0.015 mm and rigid misalignment: the statistical core's cleaning and
    # alignment must find the loop's wear areas again (tolerance: noise x width ~ 1 mm^2)
    fleet = twin.fleet
    row = fleet.truth.sort_values("mileage_km").iloc[-1]
    pts = fleet.profiles[(fleet.profiles.wheel_id == row.wheel_id)
                         & (fleet.profiles.mileage_km == row.mileage_km)]
    processed = process_profile(pts.y_mm.to_numpy(), pts.z_mm.to_numpy())
    assert processed.areas.tread_mm2 == pytest.approx(row.tread_area_mm2, abs=1.5)
