"""Seed 000's metro case: fit on line 1 at 50,000 km, predict line 1 at 80,000 km and line 2 at
140,000 km, beside the seed's own optimisers (its Table 2).

Run: .venv/bin/python benchmarks/reproduce_seed000.py [--step 0.1]

Route: seed 000 Table 1 (reference/published/metro_lines_track_conditions.csv; lines 1 and 2
share it): R >= 1,200 m 75 % at 70 km/h (as tangent), 800-1,200 m 11 % at 70, 600-800 m 11 %
at 60, 350-600 m 3 % at 40 km/h; representative radii 1,000 / 700 / 450 m, both directions,
cant 0 (not printed: ASSUMED). Vehicle: the ``metro_b`` preset (S1002, not the seed's LM
wheel). Law: Archard with the Jendel map means (seed 000's "traditional" mean k), per body (the
map is the wheel's wear). The wear loop runs the leading right wheel with adaptive steps of
--step mm, 2.0 / --step steps. Fit: one wear-coefficient scale c (all
patches of this route fall in KTH zone 1, so c is k1's fit) such that the simulated maximum
depth at c x 50,000 km equals the measured 0.348 mm (a scale on the rates is a change of the
mileage variable of the loop); prediction: the depth at c x 80,000 and c x 140,000 km. Step
convergence: the same with --step halved. Prints every number beside seed 000 Table 2
(reference/published/metro_wear_optimizer_comparison.csv).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pandas as pd

from wearcast.physics.vocabulary import CurveClass
from wearcast.physics.wear_laws import JENDEL_MAP_MEANS, ArchardKTH, WearLaw
from wearcast.physics.wear_loop import WearSteps, simulate_wear

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT.parent / "shared" / "reference" / "published"
CLASSES = [CurveClass(None, 0.0, 70.0, share=0.75)] + [
    CurveClass(r, 0.0, v, d, s / 2) for r, s, v in ((1000.0, 0.11, 70.0), (700.0, 0.11, 60.0),
                                                    (450.0, 0.03, 40.0)) for d in ("left", "right")]
MEASURED = {"line1_50000km": (50_000.0, 0.348), "line1_80000km": (80_000.0, 0.683),
            "line2_140000km": (140_000.0, 0.929)}


def depth_at(sim, km: float) -> float:
    """Maximum vertical wear depth at a mileage [mm] (linear between steps; NaN beyond)."""
    if km > sim.mileage_km[-1]:
        return float("nan")
    return float(np.interp(km, sim.mileage_km, sim.wear_mm.max(axis=1)))


def run(step_mm: float):
    law = WearLaw("archard_kth", ArchardKTH(coefficients=JENDEL_MAP_MEANS,
                                            coefficient_scope="per_body"))
    t0 = time.perf_counter()
    # 3 mm of step depth: the wheel's deepest point then passes line 2's 0.93 mm at c x 140,000
    # km (with 2 mm it stopped at 1.3 mm, short of that mileage, once the flange wear spread)
    sim = simulate_wear("metro_b", CLASSES, law=law, steps=WearSteps(
        n_steps=int(round(3.0 / step_mm)), depth_per_step_mm=step_mm))
    print(f"loop, D_step {step_mm:g} mm: {sim.mileage_km[-1]:.0f} km to "
          f"{sim.wear_mm[-1].max():.2f} mm in {time.perf_counter() - t0:.1f} s "
          f"({sim.contact_fallbacks} class fallbacks)", flush=True)
    return sim


def predictions(sim) -> dict[str, float]:
    c = sim.mileage_to_depth(MEASURED["line1_50000km"][1]) / MEASURED["line1_50000km"][0]
    out = {"scale": c}
    for case, (km, _) in MEASURED.items():
        out[case] = depth_at(sim, c * km)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--step", type=float, default=0.1, help="D_step [mm]")
    args = parser.parse_args()
    table = REFERENCE / "metro_wear_optimizer_comparison.csv"
    seed = pd.read_csv(table, comment="#") if table.exists() else None
    coarse, fine = run(2 * args.step), run(args.step)
    p2, p1 = predictions(coarse), predictions(fine)
    print(f"traditional mean k (no fit): 0.348 mm reached at {fine.mileage_to_depth(0.348):.0f}"
          f" km instead of 50,000 km ({50_000 / fine.mileage_to_depth(0.348):.1f}x too fast)")
    print(f"fitted scale c = {p1['scale']:.4f} (D_step {2 * args.step:g}: {p2['scale']:.4f})")
    print("case            measured  ours   err%   ours(2xstep)  seed PSO  err%   seed GA  "
          "seed TS  seed SA")
    for case, (_km, meas) in MEASURED.items():
        row = f"{case:15s} {meas:7.3f}  {p1[case]:5.3f} {100 * (p1[case] / meas - 1):+6.1f}  " \
              f"{p2[case]:10.3f}"
        if seed is not None:
            s = seed[seed.case == case].set_index("method")
            row += (f"    {s.loc['PSO', 'max_depth_mm']:6.3f} "
                    f"{s.loc['PSO', 're_max_depth_pct']:+6.1f}   "
                    f"{s.loc['GA', 'max_depth_mm']:6.3f}   {s.loc['TS', 'max_depth_mm']:6.3f}  "
                    f"{s.loc['SA', 'max_depth_mm']:6.3f}")
        print(row)
    change = max(abs(p1[c] - p2[c]) / p1[c] for c in ("line1_80000km", "line2_140000km"))
    print(f"step convergence: predictions change by {100 * change:.1f} % when D_step halves "
          f"({'converged' if change < 0.02 else 'NOT converged'} at 2 %)")


if __name__ == "__main__":
    main()
