"""Benchmark: batched FASTSIM, microseconds per 40 x 40 patch.

Run: .venv/bin/python benchmarks/bench_fastsim.py [--batch 1000] [--grid 40] [--repeat 5]
Prints the best-of-N time per patch for a batch of random wheel-rail patches (a, b, Fn,
creepages spread over adhesion to full sliding), for ``fastsim_forces`` (totals only, the
compiled kernel's fast path) and ``fastsim`` (with the traction fields, numpy march), as
wall time and as CPU time of this process (the CPU time is the figure on a machine shared
with other jobs), and the totals by the numpy march for comparison.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from wearcast.physics.contact import fastsim_kernel
from wearcast.physics.contact.fastsim import fastsim, fastsim_forces


def _best(func, repeat: int) -> tuple[float, float]:
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        func()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return min(wall), min(cpu)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--batch", type=int, default=1000)
    parser.add_argument("--grid", type=int, default=40)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    n = args.batch
    a = rng.uniform(3.0, 9.0, n)
    b = rng.uniform(3.0, 9.0, n)
    fn = rng.uniform(20e3, 120e3, n)
    xi = rng.uniform(-3e-3, 3e-3, n)
    eta = rng.uniform(-3e-3, 3e-3, n)
    phi = rng.uniform(-1e-3, 1e-3, n)
    fastsim(xi[:10], eta[:10], phi[:10], a[:10], b[:10], fn[:10], 0.3)  # warm-up / compile
    fastsim_forces(xi[:10], eta[:10], phi[:10], a[:10], b[:10], fn[:10], 0.3)
    grid = {"n_x": args.grid, "n_y": args.grid}
    print(f"compiled kernel: {'numba' if fastsim_kernel.HAVE_NUMBA else 'absent (numpy march)'}")
    for label, func in (
            ("fastsim_forces (totals)", lambda: fastsim_forces(xi, eta, phi, a, b, fn, 0.3,
                                                               **grid)),
            ("fastsim (with fields)", lambda: fastsim(xi, eta, phi, a, b, fn, 0.3, **grid))):
        wall, cpu = _best(func, args.repeat)
        print(f"{label:26s} {args.grid}x{args.grid}, batch {n}: {wall / n * 1e6:6.1f} us/patch "
              f"wall, {cpu / n * 1e6:6.1f} us/patch CPU (best of {args.repeat})")
    if fastsim_kernel.march_totals is not None:
        totals = fastsim_kernel.march_totals
        fastsim_kernel.march_totals = None
        try:
            wall, cpu = _best(lambda: fastsim_forces(xi, eta, phi, a, b, fn, 0.3, **grid),
                              args.repeat)
        finally:
            fastsim_kernel.march_totals = totals
        print(f"{'numpy march (reference)':26s} {args.grid}x{args.grid}, batch {n}: "
              f"{wall / n * 1e6:6.1f} us/patch wall, {cpu / n * 1e6:6.1f} us/patch CPU")


if __name__ == "__main__":
    main()
