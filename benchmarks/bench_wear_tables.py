"""Benchmark: a full curve-radius wear table (30 curve classes, motor and trailer bogies, both
wheelsets and sides, tread and flange, tau_max and T-gamma) on one core, and the Aosta route
(seed 003 Table 3's classes, Minuetto motor and trailer bogies; issue 11's target 0.5 s).

Run: ``.venv/bin/python benchmarks/bench_wear_tables.py`` (target: under 2 s warm).

The last lines time the Aosta route's curving solves (both bogie types, as the table solves
them) without and with the contact pipeline at each equilibrium pose
(``curving.solve_curving_cases(..., contact_pipeline=True)``, ``CurvingResult.pipeline``), in
the same run: the extra cost of issue 11's one contact pipeline, and the share of the
pipeline's patches and wheel poses that took the Hertz fast path (``hertz_patches``).
``--pipeline-only`` runs just those lines; run with another checkout's interpreter
(``cd ../base && .venv/bin/python /path/to/this/benchmarks/bench_wear_tables.py``) they
measure that checkout the same way.
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


def hertz_patches(pipeline: dict[str, np.ndarray]) -> tuple[int, int, int, int]:
    """(Hertz patches, loaded patches, wheels all of whose patches are Hertz, loaded wheels)
    of one curving result's pipeline contacts (2 wheelsets x 2 wheels x slots). A patch took
    the Hertz fast path when its peak pressure is Hertz's p0 = 3 F_n / (2 pi a b) of its
    equivalent ellipse (Johnson 1985 eq. 4.39 ff.) to 1e-6; a boundary-element patch misses
    that identity by percents (``tests/physics/test_wear_tables_contact_model.py``). The
    identity needs no flag from the pipeline, so this script counts the same way on any
    checkout (``--baseline-python``-style runs of an older tree)."""
    fn = pipeline["normal_force_n"]
    loaded = fn > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        p0 = 1.5 * fn / (np.pi * pipeline["a_mm"] * pipeline["b_mm"])
    hertz = loaded & np.isclose(pipeline["peak_pressure_mpa"], p0, rtol=1e-6, atol=0.0)
    wheel_loaded = loaded.any(axis=-1)
    wheel_hertz = wheel_loaded & (hertz == loaded).all(axis=-1)
    return (int(hertz.sum()), int(loaded.sum()), int(wheel_hertz.sum()),
            int(wheel_loaded.sum()))


def aosta_pipeline_cost() -> None:
    """The Aosta classes' curving without and with the contact pipeline (warm, best of 2),
    and the share of the pipeline's patches and wheel poses on the Hertz fast path."""
    route = aosta_route()
    best: dict[bool, float] = {}
    counts = np.zeros(4, dtype=int)
    for pipeline in (False, True):
        times = []
        for _ in range(2):
            t0 = time.perf_counter()
            results = []
            for kind in ("motor", "trailer"):
                vehicle = vehicle_preset("minuetto", kind)
                cases = [curving.curve_case(
                    c.radius_m, c.cant_mm if c.radius_m is not None else 0.0,
                    None if c.speed_kmh is None else c.speed_kmh / 3.6, "left",
                    torque_nm=vehicle.traction_torque_nm) for c in route.classes]
                results += curving.solve_curving_cases(vehicle, cases,
                                                       contact_pipeline=pipeline)
            times.append(time.perf_counter() - t0)
        best[pipeline] = min(times)
        if pipeline:
            counts = np.sum([hertz_patches(r.pipeline) for r in results
                             if r.pipeline is not None], axis=0)
    wheel_poses = len(route.classes) * 2 * 4  # bogie types x (2 wheelsets x 2 wheels)
    extra_ms = 1e3 * (best[True] - best[False]) / wheel_poses
    print(f"  aosta curving ({len(route.classes)} classes x motor, trailer): table contacts "
          f"{best[False]:5.2f} s, with the contact pipeline at each pose {best[True]:5.2f} s "
          f"(x{best[True] / best[False]:.1f}; {extra_ms:.1f} ms per wheel and pose over "
          f"{wheel_poses} wheel poses)")
    print(f"  the pipeline's Hertz fast path: {counts[0]} of {counts[1]} patches "
          f"({counts[0] / max(counts[1], 1):.0%}), all patches of {counts[2]} of {counts[3]} "
          f"wheel poses ({counts[2] / max(counts[3], 1):.0%})")


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--pipeline-only", action="store_true",
                        help="only the Aosta curving with and without the contact pipeline")
    if not parser.parse_args().pipeline_only:
        main()
        aosta()
    aosta_pipeline_cost()
