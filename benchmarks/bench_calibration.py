"""Benchmark: hybrid-model calibration on 10,000 synthetic measurements (target < 2 s),
predict for 10 mileages (target ~1-2 ms) and a reprofiling search.

Run: ``.venv/bin/python benchmarks/bench_calibration.py``
"""

from __future__ import annotations

import time

import numpy as np
import pandas as pd

from wearcast.statistics.hybrid import calibrate
from wearcast.statistics.hybrid_prediction import predict
from wearcast.statistics.reprofiling import reprofiling_mileage
from wearcast.statistics.route_measure import weighted_wear_measure
from wearcast.statistics.routes import Route, RouteClass
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM
from wearcast.statistics.wear_states import region_area_mm2
from wearcast.statistics.wear_tables import TABLE_COLUMNS, compile_wear_table

N_MEASUREMENTS = 10_000
Y = np.asarray(DEFAULT_GRID_Y_MM)
ROUTE = Route("bench", (
    RouteClass(None, None, 0.0, 120.0, 0.55),
    RouteClass(300.0, "left", 100.0, 60.0, 0.15),
    RouteClass(300.0, "right", 100.0, 60.0, 0.15),
    RouteClass(800.0, "left", 50.0, 90.0, 0.15),
))


def synthetic_table() -> pd.DataFrame:
    rows = []
    for bogie, bf in (("motor", 1.2), ("trailer", 1.0)):
        for wheelset, wf in (("leading", 1.5), ("trailing", 0.6)):
            for measure in ("tau_max", "t_gamma"):
                rows.append((bogie, wheelset, "tangent", np.nan, "flange", measure, 0.0))
                rows.append((bogie, wheelset, "tangent", np.nan, "tread", measure, 40.0))
                for r in (250.0, 400.0, 700.0, 1500.0, 5000.0):
                    rows += [(bogie, wheelset, "high", r, "flange", measure, bf * wf * 3e4 / r),
                             (bogie, wheelset, "low", r, "flange", measure, 0.02),
                             (bogie, wheelset, "high", r, "tread", measure, 40 + bf * wf * 1e4 / r),
                             (bogie, wheelset, "low", r, "tread", measure, 40 + bf * 3e3 / r)]
    return pd.DataFrame(rows, columns=TABLE_COLUMNS)


def synthetic_fleet(table, n: int, seed: int = 0) -> tuple[pd.DataFrame, np.ndarray]:
    """Measurements whose shapes change with area, with 8 % rate scatter and curve noise."""
    rng = np.random.default_rng(seed)
    wt = compile_wear_table(table)
    positions = [(b, a, s) for b in ("motor", "trailer") for a in (1, 2) for s in ("left", "right")]
    idx = rng.integers(0, len(positions), n)
    mileage = rng.uniform(2_000, 250_000, n)
    c_true = {"flange": 2e-5, "tread": 4e-6}
    areas = {}
    for region in ("flange", "tread"):
        p = np.array([weighted_wear_measure(ROUTE, wt, bogie_type=b, axle=a, side=s,
                                            running_mode="lead", region=region,
                                            measure="tau_max") for b, a, s in positions])
        areas[region] = c_true[region] * p[idx] * mileage * (1 + 0.08 * rng.standard_normal(n))
    flange = np.exp(-0.5 * ((Y + 40.0) / 3.5) ** 2)
    flange /= region_area_mm2(Y, flange, -30.0, "flange")
    width = 8.0 + areas["tread"] / 20.0  # the tread wear widens as it grows
    tread = np.exp(-0.5 * (Y[None, :] / width[:, None]) ** 2)
    tread /= region_area_mm2(Y, tread, -30.0, "tread")[:, None]
    curves = areas["flange"][:, None] * flange + areas["tread"][:, None] * tread
    curves += 0.003 * rng.standard_normal(curves.shape)
    frame = pd.DataFrame({
        "wheel_id": [f"w{i % 500}" for i in range(n)],
        "bogie_type": [positions[i][0] for i in idx], "axle": [positions[i][1] for i in idx],
        "side": [positions[i][2] for i in idx], "mileage_km": mileage, "route": "bench",
        "flange_area_mm2": areas["flange"], "tread_area_mm2": areas["tread"],
    })
    return frame, curves


def main() -> None:
    table = synthetic_table()
    frame, curves = synthetic_fleet(table, N_MEASUREMENTS)
    start = time.perf_counter()
    model = calibrate(frame, {"bench": ROUTE}, table, wear_curves_mm=curves,
                      measure="tau_max", running_mode="lead")
    t_cal = time.perf_counter() - start
    wt = compile_wear_table(table)
    mileage = np.linspace(0.0, 300_000.0, 10)
    kw = {"bogie_type": "motor", "axle": 1, "side": "right"}
    predict(model, ROUTE, wt, mileage_km=mileage, **kw)
    reps = 200
    start = time.perf_counter()
    for _ in range(reps):
        predict(model, ROUTE, wt, mileage_km=mileage, **kw)
    t_pred = (time.perf_counter() - start) / reps
    start = time.perf_counter()
    res = reprofiling_mileage(model, ROUTE, wt, **kw)
    t_rep = time.perf_counter() - start
    print(f"calibration, {N_MEASUREMENTS} measurements x {Y.size} grid points: "
          f"{t_cal:.3f} s (target < 2 s)")
    print(f"  c_s flange {model.flange.c_s:.4e} (true 2e-5), "
          f"tread {model.tread.c_s:.4e} (true 4e-6)")
    print(f"predict, 10 mileages (compiled table): {t_pred * 1e3:.2f} ms per call")
    print(f"reprofiling mileage search: {t_rep * 1e3:.1f} ms "
          f"(P50 {res.mileage_p50_km:.0f} km, governed by {res.governing_limit})")


if __name__ == "__main__":
    main()
