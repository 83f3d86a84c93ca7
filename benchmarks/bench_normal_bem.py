"""Benchmark: one coarse normal boundary-element solve, numpy FFT against the compiled direct
product (``contact.normal_bem_kernel``), on the grids of the production method ("bem-coarse",
~24 x 24 elements) and a finer one; same iteration, same solution to rounding.

Run: ``.venv/bin/python benchmarks/bench_normal_bem.py`` (one core; prints ms per solve,
iterations, the ratio and the largest pressure difference relative to the peak).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core

import time  # noqa: E402
from functools import partial  # noqa: E402

import numpy as np  # noqa: E402

from wearcast.physics.contact.normal_bem import solve_normal_bem  # noqa: E402


def _gap(ny: int, nx: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A conformal tread-like gap [mm]: rolling radius 460 mm, a lateral quadratic with a
    cubic and a wavy term (non-Hertzian), over a patch of ~11 x 7 mm."""
    x = (np.arange(nx) - 0.5 * nx + 0.5) * (11.0 / nx)
    y = (np.arange(ny) - 0.5 * ny + 0.3) * (7.0 / ny)
    gap = (x[None, :] ** 2 / 460.0 + 0.004 * y[:, None] ** 2 + 0.0004 * y[:, None] ** 3
           + 0.0006 * np.sin(1.7 * y[:, None]))
    return gap, x, y


def _best_ms(fn, repeat: int) -> float:
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * min(times)


def main() -> None:
    print("normal BEM, one solve (force prescribed, tol 1e-6): numpy FFT vs compiled direct")
    for ny, nx in ((22, 22), (24, 24), (26, 26), (34, 34)):
        gap, x, y = _gap(ny, nx)
        results = {}
        ms = {}
        for compiled in (False, True):
            solve = partial(solve_normal_bem, gap, x, y, normal_force_n=20_000.0, tol=1e-6,
                            compiled=compiled)
            ms[compiled] = _best_ms(solve, 7)
            results[compiled] = solve()
        diff = float(np.abs(results[True].pressure_mpa - results[False].pressure_mpa).max()
                     / results[False].peak_pressure_mpa)
        print(f"  {ny:2d} x {nx:2d}: FFT {ms[False]:6.2f} ms, compiled {ms[True]:6.2f} ms "
              f"(x{ms[False] / ms[True]:.1f}), {results[True].iterations} iterations, "
              f"max |dp| / p0 {diff:.1e}")


if __name__ == "__main__":
    main()
