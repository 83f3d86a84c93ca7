"""Benchmark of per-profile processing (clean, align, wear curve, areas, Sd/Sh/qR).

Usage: ``.venv/bin/python benchmarks/bench_processing.py [n_profiles]`` (default 3000).
Prints profiles per second for synthetic worn, moved, noisy S1002 profiles of 400 points,
given field side first as a MiniProf would, and the time of each stage (process CPU time,
so that other load on a shared machine inflates the figures less), then the same profiles
processed together in chunks as the import does it
(:func:`wearcast.statistics.processing_batch.process_profiles_free`, results equal to
round-off) and the ratio of the two.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.alignment import align_to_reference
from wearcast.statistics.cleaning import clean_profile
from wearcast.statistics.processing import process_profile
from wearcast.statistics.processing_batch import BLOCK, process_profiles_free
from wearcast.statistics.profile_parameters import flange_parameters
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM, wear_areas_mm2, wear_curve_mm


def synthetic_profiles(n: int, n_points: int = 400, seed: int = 0):
    """n worn S1002 profiles: random tread (0-2 mm) and flange (0-1 mm) wear, placement
    errors (1 mm, 0.5 mm, 3 mrad) and 10 um noise; raw order field side first."""
    rng = np.random.default_rng(seed)
    y = np.linspace(-70.0, 60.0, n_points)
    z_ref = s1002_height_mm(y)
    out = []
    for _ in range(n):
        wear = rng.uniform(0, 2) * np.exp(-0.5 * ((y - rng.uniform(-5, 10)) / 11.0) ** 2)
        wear += rng.uniform(0, 1) * np.exp(-0.5 * ((y + 38.0) / 3.0) ** 2)
        z = z_ref - wear
        theta, dy, dz = rng.normal(0, 0.003), rng.normal(0, 1.0), rng.normal(0, 0.5)
        c, s = np.cos(theta), np.sin(theta)
        ym = c * y - s * z + dy
        zm = s * y + c * z + dz + rng.normal(0, 0.01, n_points)
        out.append((ym[::-1].copy(), zm[::-1].copy()))
    return out


def _time_per_item(func, items, repeats: int = 3) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.process_time()
        for item in items:
            func(item)
        best = min(best, (time.process_time() - start) / len(items))
    return best


def main(n: int = 3000) -> None:
    profiles = synthetic_profiles(n)
    cleaned = [clean_profile(y, z) for y, z in profiles]
    aligned = [align_to_reference(c.y_mm, c.z_mm) for c in cleaned]
    wear = [wear_curve_mm(a.y_mm, a.z_mm) for a in aligned]
    stages = {
        "clean_profile": _time_per_item(lambda p: clean_profile(*p), profiles),
        "align_to_reference": _time_per_item(lambda c: align_to_reference(c.y_mm, c.z_mm),
                                             cleaned),
        "wear_curve_mm": _time_per_item(lambda a: wear_curve_mm(a.y_mm, a.z_mm), aligned),
        "wear_areas_mm2": _time_per_item(lambda w: wear_areas_mm2(DEFAULT_GRID_Y_MM, w), wear),
        "flange_parameters": _time_per_item(lambda a: flange_parameters(a.y_mm, a.z_mm),
                                            aligned),
    }
    total = _time_per_item(lambda p: process_profile(*p), profiles)
    print(f"process_profile: {n} profiles of 400 points, best of 3 runs, CPU time of one core")
    for name, seconds in stages.items():
        print(f"  {name:<20s} {seconds * 1e6:8.1f} us")
    print(f"  {'process_profile':<20s} {total * 1e6:8.1f} us/profile")
    print(f"throughput: {1.0 / total:,.0f} profiles/s")
    chunks = [profiles[i:i + BLOCK] for i in range(0, n, BLOCK)]
    batch = _time_per_item(process_profiles_free, chunks) * len(chunks) / n
    print(f"process_profiles_free (chunks of {BLOCK}): {batch * 1e6:8.1f} us/profile, "
          f"{1.0 / batch:,.0f} profiles/s, {total / batch:.1f}x the per-profile calls")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3000)
