"""A hand-built hybrid model, curve-radius table and routes for the reprofiling tests
(test_reprofiling, test_perf_reprofiling, test_perf_reprofiling_surface)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from wearcast.statistics.hybrid import HybridModel, RegionCalibration
from wearcast.statistics.routes import Route, RouteClass
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM
from wearcast.statistics.wear_rates import WearRate
from wearcast.statistics.wear_states import build_wear_states, region_area_mm2
from wearcast.statistics.wear_tables import TABLE_COLUMNS

Y = np.asarray(DEFAULT_GRID_Y_MM)
SPLIT = -30.0
ROUTE = Route("r", (RouteClass(None, None, 0.0, 100.0, 0.6),
                    RouteClass(300.0, "left", 90.0, 60.0, 0.4)))
TANGENT = Route("t", (RouteClass(None, None, 0.0, 100.0, 1.0),))


def table(tread_tangent: float = 50.0) -> pd.DataFrame:
    """Curve-radius table of one motor bogie (tau_max; one curve radius, 250 m)."""
    rows = []
    for ws in ("leading", "trailing"):
        rows += [("motor", ws, "tangent", np.nan, "flange", "tau_max", 0.0),
                 ("motor", ws, "tangent", np.nan, "tread", "tau_max", tread_tangent),
                 ("motor", ws, "high", 250.0, "flange", "tau_max", 120.0),
                 ("motor", ws, "low", 250.0, "flange", "tau_max", 1.0),
                 ("motor", ws, "high", 250.0, "tread", "tau_max", 90.0),
                 ("motor", ws, "low", 250.0, "tread", "tau_max", 70.0)]
    return pd.DataFrame(rows, columns=TABLE_COLUMNS)


def model(c_flange: float = 2e-5, c_tread: float = 5e-6, rel: float = 0.1) -> HybridModel:
    """Hand-built model: Gaussian flange-face and tread wear shapes, six states a region."""
    flange = np.exp(-0.5 * ((Y + 39.0) / 3.0) ** 2)
    tread = np.exp(-0.5 * (Y / 14.0) ** 2)
    flange /= region_area_mm2(Y, flange, SPLIT, "flange")
    tread /= region_area_mm2(Y, tread, SPLIT, "tread")
    a_f, a_t = np.linspace(1, 60, 30), np.linspace(2, 200, 30)
    curves = a_f[:, None] * flange + a_t[:, None] * tread
    states = build_wear_states(Y, curves, a_f, a_t, split_y_mm=SPLIT, n_states=6)
    rate = WearRate(1e-3, 1e-5, 1e-4, 30)

    def cal(c: float) -> RegionCalibration:
        return RegionCalibration(c_s=c, c_s_rel_std_error=0.01, c_s_rel_spread=rel, p_m=1.0,
                                 rate=rate)

    return HybridModel(measure="tau_max", running_mode="lead", states=states,
                       flange=cal(c_flange), tread=cal(c_tread), bogie_types=("motor",))
