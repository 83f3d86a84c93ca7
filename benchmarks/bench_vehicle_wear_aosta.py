"""Benchmark: the whole-vehicle wear loop of the Minuetto on Aosta to 3,600 km (issue 12).

Run: .venv/bin/python benchmarks/bench_vehicle_wear_aosta.py [--km 3600] [--step 0.8]
     [--route fleet|table3] [--json OUT] [--against EARLIER.json]

The run the physics model builds (``benchmarks/physics_model_aosta.py``, ``POST /v1/models``
``kind: physics``): ``physics.vehicle_wear_simulation.simulate_vehicle_wear`` of the
``minuetto`` preset (two motor and two trailer bogies, both running directions, all wheels
averaged), USFD, D_step = --step, on the example fleet's ``aosta`` route (39 curve classes;
``--route table3``: seed 003's Table 3 classes, what ``diagnose_aosta_physics.py`` runs,
needs ../shared/reference). Prints the wall and CPU time, steps, contact updates and fallbacks, and
the vehicle-mean FT/FH/qR at the end. ``--json`` writes them with the per-step series;
``--against`` compares with such a file written by another version of the code on the same
machine (e.g. the previous commit, run with ``PYTHONPATH`` pointing at its source): the time
ratio and, per quantity, the largest difference over the steps relative to the quantity's
loss at the end. Target (issue 12): < 10 s.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from wearcast.physics.vehicle_wear_simulation import simulate_vehicle_wear

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT.parent / "shared" / "reference" / "published"
QUANTITIES = {"FT": "sd_mm", "FH": "sh_mm", "qR": "qr_mm"}


def route_classes(name: str) -> list:
    if name == "fleet":
        routes = json.loads((ROOT / "service" / "example_fleet" / "routes.json").read_text())
        return next(r for r in routes if r["name"] == "aosta")["classes"]
    import pandas as pd

    from wearcast.statistics.generators.scenarios import seed003_classes

    return seed003_classes(pd.read_csv(REFERENCE / "aosta_statistical_track_nclass7.csv",
                                       comment="#"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--km", type=float, default=3600.0, help="mileage [km]")
    parser.add_argument("--step", type=float, default=0.8, help="D_step [mm]")
    parser.add_argument("--route", choices=("fleet", "table3"), default="fleet")
    parser.add_argument("--json", type=Path, help="write the result here")
    parser.add_argument("--against", type=Path, help="compare with an earlier --json")
    args = parser.parse_args()
    classes = route_classes(args.route)
    start, cpu_start = time.perf_counter(), time.process_time()
    sim = simulate_vehicle_wear("minuetto", classes, law="usfd", mileage_km=args.km,
                                depth_per_step_mm=args.step)
    elapsed = time.perf_counter() - start
    cpu = time.process_time() - cpu_start
    series = {k: sim.mean(q).tolist() for k, q in QUANTITIES.items()}
    print(f"whole-vehicle Aosta loop ({args.route}, {len(classes)} classes) to {args.km:,.0f} "
          f"km, D_step {args.step} mm: {elapsed:.1f} s (target < 10 s; CPU {cpu:.1f} s); "
          f"{len(sim.mileage_km) - 1} steps, {sim.contact_updates} contact updates, "
          f"{sim.contact_fallbacks} class fallbacks")
    print("end: " + ", ".join(f"{k} {v[-1]:.4f} mm" for k, v in series.items()))
    result = {"elapsed_s": elapsed, "cpu_s": cpu, "route": args.route, "km": args.km,
              "step": args.step, "mileage_km": sim.mileage_km.tolist(),
              "fallbacks": sim.contact_fallbacks, **series}
    if args.json is not None:
        args.json.write_text(json.dumps(result))
        print(f"wrote {args.json}")
    if args.against is not None:
        old = json.loads(args.against.read_text())
        if (old["route"], old["km"], old["step"]) != (args.route, args.km, args.step):
            parser.error("--against: a run of another route, mileage or step")
        print(f"earlier run: {old['elapsed_s']:.1f} s -> now {elapsed:.1f} s "
              f"(x{old['elapsed_s'] / elapsed:.2f} faster), fallbacks {old['fallbacks']} -> "
              f"{sim.contact_fallbacks}")
        if "cpu_s" in old:
            print(f"  CPU {old['cpu_s']:.1f} s -> {cpu:.1f} s (x{old['cpu_s'] / cpu:.2f})")
        for k in QUANTITIES:
            km_old, v_old = np.asarray(old["mileage_km"]), np.asarray(old[k])
            v_new = np.interp(km_old, sim.mileage_km, series[k])
            loss = max(abs(v_old[0] - v_old[-1]), 1e-9)
            diff = float(np.max(np.abs(v_new - v_old)))
            print(f"  {k}: largest difference {diff:.2e} mm = {100 * diff / loss:.3f} % of "
                  f"the loss ({loss:.3f} mm)")


if __name__ == "__main__":
    main()
