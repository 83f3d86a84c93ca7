"""Benchmark: diagnose 200 wheels x 10 measurements across the whole catalogue (target < 2 s).

Run: .venv/bin/python benchmarks/bench_diagnose.py
Data: fleet twin, 4 units x 7 cars (+1) ... trimmed to 200 wheels, 10 mileages each, with a
traction effect hidden; profile generation and processing are not timed, only ``diagnose``.
"""

from __future__ import annotations

import time

from wearcast.statistics import hybrid
from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_effects as te


def main() -> None:
    table = ft.synthetic_wear_table()
    mileages = tuple(float(s) for s in range(15_000, 165_000, 15_000))  # 10 measurements
    cfg = te.scenario_config(seed=11, vehicles_per_unit=7, mileages_km=mileages,
                             points_per_profile=150, wear_effects=(te.traction(1.3),))
    df, curves = te.twin_measurements(ft.generate_fleet(cfg, table))
    keep_wheels = sorted(df["wheel_id"].unique())[:200]
    sel = df["wheel_id"].isin(keep_wheels).to_numpy()
    df, curves = df[sel].reset_index(drop=True), curves[sel]
    routes, attrs = te.scenario_routes(cfg)
    cal = (df["vehicle_id"].str.startswith("A") & (df["bogie_type"] == "motor")).to_numpy()
    model = hybrid.calibrate(df[cal], routes, table, wear_curves_mm=curves[cal],
                             measure="tau_max", running_mode="mixed")
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        d = diagnose(model, df, curves, routes, table, route_attributes=attrs,
                     calibration_wheel_ids=set(df["wheel_id"][cal]))
        times.append(time.perf_counter() - t0)
    print(f"diagnose: {df['wheel_id'].nunique()} wheels x {len(df) // df['wheel_id'].nunique()} "
          f"measurements = {len(df)} rows, {len(d.findings)} causes scored, "
          f"{len(d.skipped)} skipped; verdict {d.verdict}")
    print(f"time: best {min(times):.2f} s, median {sorted(times)[1]:.2f} s (target < 2 s)")


if __name__ == "__main__":
    main()
