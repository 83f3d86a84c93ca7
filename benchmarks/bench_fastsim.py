"""Benchmark: batched FASTSIM, microseconds per 40 x 40 patch.

Run: .venv/bin/python benchmarks/bench_fastsim.py [--batch 1000] [--grid 40] [--repeat 5]
Prints the best-of-N wall time per patch for a batch of random wheel-rail patches
(a, b, Fn, creepages spread over adhesion to full sliding).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from wearcast.physics.contact.fastsim import fastsim


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
    fastsim(xi[:10], eta[:10], phi[:10], a[:10], b[:10], fn[:10], 0.3)  # warm-up
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        fastsim(xi, eta, phi, a, b, fn, 0.3, n_x=args.grid, n_y=args.grid)
        times.append(time.perf_counter() - t0)
    best = min(times)
    print(f"fastsim {args.grid}x{args.grid}, batch {n}: {best / n * 1e6:.1f} us/patch "
          f"(best of {args.repeat}, total {best * 1e3:.1f} ms)")


if __name__ == "__main__":
    main()
