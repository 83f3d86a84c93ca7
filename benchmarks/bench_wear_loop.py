"""Benchmark: the wear loop, 20 adaptive wheel steps (D_step = 0.2 mm) over 30 curve classes.

Run: .venv/bin/python benchmarks/bench_wear_loop.py [--steps 20] [--classes 30]
Target (issue 5): < 60 s on this machine; seed 003 needed 20 h to over 2 days of multibody
simulation for comparable work. Prints the time, the contact updates and fallbacks, the
mileage and Sd/Sh/qR at every fifth step.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from wearcast.physics.vocabulary import CurveClass
from wearcast.physics.wear_loop import WearSteps, simulate_wear


def classes(n: int) -> list[CurveClass]:
    """n - 1 curves 200-3000 m (cant falling 150 -> 40 mm, alternating direction) + tangent."""
    radii = np.geomspace(200.0, 3000.0, n - 1)
    cants = np.linspace(150.0, 40.0, n - 1)
    out = [CurveClass(float(r), float(c), None, "left" if i % 2 == 0 else "right", 1.0)
           for i, (r, c) in enumerate(zip(radii, cants, strict=True))]
    return out + [CurveClass(None, share=float(n - 1))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--classes", type=int, default=30)
    parser.add_argument("--vehicle", default="metro_b")
    args = parser.parse_args()
    t0 = time.perf_counter()
    sim = simulate_wear(args.vehicle, classes(args.classes),
                        steps=WearSteps(n_steps=args.steps, depth_per_step_mm=0.2))
    elapsed = time.perf_counter() - t0
    print(f"wear loop: {args.steps} steps x {args.classes} classes ({args.vehicle}): "
          f"{elapsed:.1f} s (target < 60 s); contact updates {sim.contact_updates}, "
          f"fallbacks {sim.contact_fallbacks}")
    print("step  mileage_km  Sh_mm  Sd_mm  qR_mm  max_wear_mm")
    for i in range(0, args.steps + 1, 5):
        print(f"{i:4d}  {sim.mileage_km[i]:10.1f}  {sim.sh_mm[i]:5.2f}  {sim.sd_mm[i]:5.2f}  "
              f"{sim.qr_mm[i]:5.2f}  {sim.wear_mm[i].max():6.3f}")


if __name__ == "__main__":
    main()
