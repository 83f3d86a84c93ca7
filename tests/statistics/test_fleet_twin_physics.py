"""The fleet twin driven by a curve-radius table computed by the physics core (issue 4).

The twin accepts any table in the format of docs/conventions.md; here it is the Minuetto-like DMU's
table
from quasi-static curving (``wearcast.physics.wear_tables``) for the radii of the Aosta route
(seed 003 Table 3) and the metro line (seed 000 Table 1). The hybrid calibration must then
recover the c_s the twin was made with, from processed (noisy, misaligned) profiles.
"""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.vocabulary import REGIONS
from wearcast.physics.wear_tables import wear_table_for_route
from wearcast.statistics import hybrid
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.generators import twin_routes
from wearcast.statistics.route_measure import weighted_wear_measure


@pytest.fixture(scope="module")
def physics_table():
    radii = sorted({c.radius_m for r in (twin_routes.aosta_route(), twin_routes.metro_route())
                    for c in r.classes if c.radius_m is not None})
    return wear_table_for_route("minuetto", [None, *radii], cant_mm=0.0)


def test_twin_follows_a_physics_table_and_calibration_recovers_cs(physics_table):
    route = twin_routes.aosta_route()
    # Choose c_s so that unit A's motor wheels wear ~0.35 (tread) and ~0.5 (flange) mm^2 per
    # 1000 km on average, whatever the physics table's scale: realistic areas at 150,000 km.
    p = {region: np.mean([weighted_wear_measure(route, physics_table, bogie_type="motor",
                                                axle=axle, side=side, running_mode="mixed",
                                                region=region, measure="tau_max")
                          for axle in (1, 2) for side in ("left", "right")])
         for region in REGIONS}
    assert p["flange"] > 0 and p["tread"] > 0
    c_s = {"tread": 3.5e-4 / p["tread"], "flange": 5e-4 / p["flange"]}
    config = ft.FleetConfig(
        units=(ft.UnitConfig("A", route, vehicles=2, running_mode="mixed"),),
        mileages_km=(30_000, 90_000, 150_000), points_per_profile=200, seed=11,
        calibration_factor=c_s)
    twin = ft.generate_fleet(config, physics_table)
    frame, curves = te.twin_measurements(twin)
    routes, _ = te.scenario_routes(config)
    motor = (frame["bogie_type"] == "motor").to_numpy()
    model = hybrid.calibrate(frame[motor], routes, physics_table, wear_curves_mm=curves[motor],
                             measure="tau_max", running_mode="mixed")
    # 8 motor wheels with 10 % per-wheel rate scatter: the mean of 8 log-normal factors has a
    # standard error of ~3.5 %, so 10 % is a 3-sigma bound; processing errors are < 1 %.
    for region in REGIONS:
        assert model.region(region).c_s == pytest.approx(c_s[region], rel=0.10), region
