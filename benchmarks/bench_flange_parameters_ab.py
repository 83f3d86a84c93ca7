"""Sd/Sh/qR of this tree against another checkout: the numbers of every path, and their speed.

Usage::

    git worktree add --detach ../base main
    .venv/bin/python benchmarks/bench_flange_parameters_ab.py ../base [n_pairs]

The baseline is imported as ``wearcast_base`` (see ``bench_processing_ab``). Numbers: on
worn S1002 profiles (2,000 per grid) on three common grids (the hybrid model's 0.5 mm grid,
a 0.1 mm grid and an odd 0.336 mm grid that does not hold y = 0), the largest difference
of ``flange_parameters`` (one profile) and ``flange_parameters_batch`` (common grid) between
the trees, and whether the batch equals the one-profile numbers to the bit in each tree; on
the 512 cleaned profiles of ``bench_processing.synthetic_profiles``, whether
``flange_parameters_rows`` (the import's block path) is the same in both trees. Speed: the
median of ``n_pairs`` (default 7) interleaved pairs of process CPU times per call.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_processing import synthetic_profiles  # noqa: E402
from bench_processing_ab import _baseline_package, interleaved  # noqa: E402

GRIDS = {"0.5 mm (model)": np.linspace(-58.0, 50.0, 217),
         "0.1 mm": np.linspace(-70.0, 60.0, 1301), "0.336 mm": np.linspace(-60.3, 40.1, 300)}


def _worn(y: np.ndarray, n: int, seed: int) -> np.ndarray:
    """S1002 [mm] with random flange and tread wear, an offset and, on some rows, noise."""
    rng = np.random.default_rng(seed)
    s1002 = importlib.import_module("wearcast.physics.profiles.s1002").s1002_height_mm
    flange = rng.uniform(0, 4, (n, 1)) * np.exp(
        -0.5 * ((y - rng.uniform(-45, -33, (n, 1))) / rng.uniform(1, 6, (n, 1))) ** 2)
    tread = rng.uniform(0, 3, (n, 1)) * np.exp(-0.5 * (y / 14.0) ** 2)
    noise = rng.normal(0, 0.02, (n, y.size)) * (rng.uniform(size=(n, 1)) < 0.3)
    return s1002(y) - flange - tread + noise + rng.normal(0, 0.3, (n, 1))


def _one_by_one(mod: Any, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    return np.array([[p.sd_mm, p.sh_mm, p.qr_mm]
                     for p in (mod.flange_parameters(y, row) for row in z)])


def _largest(a: np.ndarray, b: np.ndarray) -> float:
    same_nan = np.array_equal(np.isnan(a), np.isnan(b))
    return float(np.nanmax(np.abs(a - b))) if same_nan else float("inf")


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("baseline", help="checkout of the baseline (has physics/, statistics/)")
    parser.add_argument("pairs", nargs="?", type=int, default=7)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        _baseline_package(Path(args.baseline), Path(tmp))
        sys.path.insert(0, tmp)
        mods = {tree: importlib.import_module(f"{tree}.physics.profiles.parameters")
                for tree in ("wearcast_base", "wearcast")}
        base, this = mods["wearcast_base"], mods["wearcast"]
        for name, y in GRIDS.items():
            z = _worn(y, 2000, y.size)
            one = {t: _one_by_one(m, y, z) for t, m in mods.items()}
            batch = {t: m.flange_parameters_batch(y, z).stacked() for t, m in mods.items()}
            print(f"grid {name}: 2000 profiles, largest |this - baseline| one-profile "
                  f"{_largest(one['wearcast'], one['wearcast_base']):.3g} mm, batch "
                  f"{_largest(batch['wearcast'], batch['wearcast_base']):.3g} mm; batch = "
                  "one-profile to the bit: baseline "
                  f"{np.array_equal(batch['wearcast_base'], one['wearcast_base'], True)}, "
                  f"this {np.array_equal(batch['wearcast'], one['wearcast'], True)}")
        ragged = importlib.import_module("wearcast.statistics.ragged")
        cleaning = importlib.import_module("wearcast.statistics.cleaning")
        cleaned = [cleaning.clean_profile(*p) for p in synthetic_profiles(512)]
        y_rows, valid = ragged.pack([c.y_mm for c in cleaned], 0.0)
        z_rows, _ = ragged.pack([c.z_mm for c in cleaned], 0.0)
        same = np.array_equal(base.flange_parameters_rows(y_rows, z_rows, valid),
                              this.flange_parameters_rows(y_rows, z_rows, valid), True)
        print(f"rows (block path), 512 cleaned profiles: the same in both trees: {same}")
        y = GRIDS["0.5 mm (model)"]
        z = _worn(y, 1000, 1)
        cases = {
            "flange_parameters": (
                lambda m: [m.flange_parameters(c.y_mm, c.z_mm) for c in cleaned], 512,
                "profile"),
            "flange_parameters_rows": (
                lambda m: m.flange_parameters_rows(y_rows, z_rows, valid), 512, "profile"),
            "flange_parameters_batch (1000 x 217)": (
                lambda m: m.flange_parameters_batch(y, z), 1000, "row"),
        }
        print(f"{args.pairs} interleaved pairs, process CPU time")
        for name, (func, count, unit) in cases.items():
            for m in (base, this):
                func(m)  # compile / warm up
            print(f"  {name:<38s} " + interleaved(
                lambda _, f=func: f(base), lambda _, f=func: f(this), [None], args.pairs,
                count, unit))


if __name__ == "__main__":
    main(sys.argv[1:])
