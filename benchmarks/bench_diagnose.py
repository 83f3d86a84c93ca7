"""Benchmark: diagnose 200 wheels x 10 measurements across the whole catalogue (target < 2 s).

Run: .venv/bin/python benchmarks/bench_diagnose.py
Data: fleet twin, 4 units x 7 cars (+1) ... trimmed to 200 wheels, 10 mileages each, with a
traction effect hidden; profile generation and processing are not timed, only ``diagnose``.
"""

from __future__ import annotations

import time

from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.generators.scenarios import twin_scenario


def main() -> None:
    mileages = tuple(float(s) for s in range(15_000, 165_000, 15_000))  # 10 measurements
    scenario = twin_scenario((te.traction(1.3),), seed=11, max_wheels=200, vehicles_per_unit=7,
                             mileages_km=mileages, points_per_profile=150)
    df = scenario.measurements
    args, kwargs = scenario.finder_arguments()
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        d = diagnose(*args, **kwargs)
        times.append(time.perf_counter() - t0)
    print(f"diagnose: {df['wheel_id'].nunique()} wheels x {len(df) // df['wheel_id'].nunique()} "
          f"measurements = {len(df)} rows, {len(d.findings)} causes scored, "
          f"{len(d.skipped)} skipped; verdict {d.verdict}")
    print(f"time: best {min(times):.2f} s, median {sorted(times)[1]:.2f} s (target < 2 s)")


if __name__ == "__main__":
    main()
