"""Benchmark: a full curve-radius wear table (30 curve classes, motor and trailer bogies, both
wheelsets and sides, tread and flange, tau_max and T-gamma) on one core, and the Aosta route
(seed 003 Table 3's classes, Minuetto motor and trailer bogies; issue 11's target 0.5 s).

Run: ``.venv/bin/python benchmarks/bench_wear_tables.py`` (target: under 2 s warm).

The last lines time the Aosta route's curving solves (both bogie types, as the table solves
them) without and with the contact pipeline at each equilibrium pose
(``curving.solve_curving_cases(..., contact_pipeline=True)``, ``CurvingResult.pipeline``), in
the same run: the extra cost of issue 11's one contact pipeline.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core

import time  # noqa: E402

import numpy as np  # noqa: E402

from wearcast.physics import curving  # noqa: E402
from wearcast.physics.vehicles import vehicle_preset  # noqa: E402
from wearcast.physics.wear_tables import wear_table_for_route  # noqa: E402
from wearcast.statistics.generators.twin_routes import aosta_route  # noqa: E402


def thirty_classes() -> tuple[list[float | None], list[float]]:
    """Tangent plus 29 radii 150-5000 m with a cant falling with the radius (150 mm at 150 m,
    20 mm at 5000 m); speeds from a_nc = 0.58 m/s^2 (seed 001), capped at 160 km/h."""
    radii = np.geomspace(150.0, 5000.0, 29)
    cant = np.interp(np.log(radii), np.log([150.0, 5000.0]), [150.0, 20.0])
    return [None, *radii.tolist()], [0.0, *cant.tolist()]


def main() -> None:
    radii, cant = thirty_classes()
    print("wear table: 30 curve classes x (motor, trailer) x (leading, trailing) x "
          "(left, right), one core")
    for preset in ("manchester", "metro_b"):
        curving.contact_table_for.cache_clear()
        t0 = time.perf_counter()
        table = wear_table_for_route(preset, radii, cant_mm=cant, max_speed_kmh=160.0)
        cold = time.perf_counter() - t0
        warm = []
        for _ in range(3):
            t0 = time.perf_counter()
            wear_table_for_route(preset, radii, cant_mm=cant, max_speed_kmh=160.0)
            warm.append(time.perf_counter() - t0)
        print(f"  {preset:<11s} rows {len(table):4d}  cold (incl. contact table) "
              f"{cold:5.2f} s  warm best {min(warm):5.2f} s  median {np.median(warm):5.2f} s")


def aosta() -> None:
    route = aosta_route()
    radii = [c.radius_m for c in route.classes]
    cant = [c.cant_mm for c in route.classes]
    speed = [c.speed_kmh for c in route.classes]
    wear_table_for_route("minuetto", radii, cant_mm=cant, speed_kmh=speed)  # warm the caches
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        table = wear_table_for_route("minuetto", radii, cant_mm=cant, speed_kmh=speed)
        times.append(time.perf_counter() - t0)
    print(f"  aosta (minuetto, {len(radii)} classes + tangent) rows {len(table):4d}  warm best "
          f"{min(times):5.2f} s  median {np.median(times):5.2f} s  (target 0.5 s)")


def aosta_pipeline_cost() -> None:
    """The Aosta classes' curving without and with the contact pipeline (warm, best of 2)."""
    route = aosta_route()
    best: dict[bool, float] = {}
    for pipeline in (False, True):
        times = []
        for _ in range(2):
            t0 = time.perf_counter()
            for kind in ("motor", "trailer"):
                vehicle = vehicle_preset("minuetto", kind)
                cases = [curving.curve_case(
                    c.radius_m, c.cant_mm if c.radius_m is not None else 0.0,
                    None if c.speed_kmh is None else c.speed_kmh / 3.6, "left",
                    torque_nm=vehicle.traction_torque_nm) for c in route.classes]
                curving.solve_curving_cases(vehicle, cases, contact_pipeline=pipeline)
            times.append(time.perf_counter() - t0)
        best[pipeline] = min(times)
    wheel_poses = len(route.classes) * 2 * 4  # bogie types x (2 wheelsets x 2 wheels)
    extra_ms = 1e3 * (best[True] - best[False]) / wheel_poses
    print(f"  aosta curving ({len(route.classes)} classes x motor, trailer): table contacts "
          f"{best[False]:5.2f} s, with the contact pipeline at each pose {best[True]:5.2f} s "
          f"(x{best[True] / best[False]:.1f}; {extra_ms:.1f} ms per wheel and pose over "
          f"{wheel_poses} wheel poses)")


if __name__ == "__main__":
    main()
    aosta()
    aosta_pipeline_cost()
