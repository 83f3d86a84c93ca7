"""Physics diagnosis of the whole-vehicle loop on the measured Minuetto wheels (seed 003 Table 2).

Run: .venv/bin/python benchmarks/diagnose_aosta_physics.py [--step 0.8] [--km 8000]

The model: ``physics.vehicle_wear_simulation`` (minuetto, two motor + two trailer bogies, both
running directions, all wheels averaged as measured) on seed 003's Table 3 classes with its
USFD law and one fitted wear-coefficient scale; the catalogue of
``statistics.physics_diagnosis`` (flange lubrication, friction level, running-direction share,
patch model, wear law, traction, rail state: the Minuetto's rail worn by its own passages on
the same classes to 5 and 10 Mt, ``physics.rail_tonnage``), each extension run at its
catalogue values to --km (far enough for the fitted scales), scored leaving one vehicle out
(3 vehicles: test groups are points). Prints the time of every loop run and of the whole
diagnosis, the null fit, every finding and the verdict. Needs ../shared/reference.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import pandas as pd

from wearcast.physics.rail_tonnage import rails_worn_to_tonnages
from wearcast.physics.vehicle_wear_simulation import VehicleWearOptions, simulate_vehicle_wear
from wearcast.statistics.physics_diagnosis import CATALOGUE, RAIL_TONNAGES_MT, diagnose_physics

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT.parent / "shared" / "reference" / "published"


def main() -> None:
    from validate_aosta_measured import aosta_classes  # benchmarks/ on sys.path when run

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--step", type=float, default=0.8, help="D_step [mm]")
    parser.add_argument("--km", type=float, default=8000.0, help="simulated mileage [km]")
    parser.add_argument("--causes", default=",".join(c.name for c in CATALOGUE),
                        help="comma-separated causes of the catalogue (default: all)")
    args = parser.parse_args()
    wanted = args.causes.split(",")
    unknown = set(wanted) - {c.name for c in CATALOGUE}
    if unknown:
        parser.error(f"unknown causes: {', '.join(sorted(unknown))}")
    catalogue = tuple(c for c in CATALOGUE if c.name in wanted)
    measured_csv = REFERENCE / "aosta_measured_FH_FT_QR.csv"
    track_csv = REFERENCE / "aosta_statistical_track_nclass7.csv"
    if not measured_csv.exists():
        print(f"skipped: {REFERENCE} not found")
        return
    measured = pd.read_csv(measured_csv, comment="#")
    classes = aosta_classes(pd.read_csv(track_csv, comment="#"))

    contacts: dict = {}  # first contact updates shared by the runs (same new profile)
    rails: dict = {}  # the rail state's worn rails, one chain of rail steps for all tonnages

    def simulate(params):
        params = dict(params)
        law = params.pop("law", "usfd")
        tonnage = params.pop("rail_tonnage_mt", 0.0)
        if tonnage:
            if tonnage not in rails:
                t0 = time.perf_counter()
                out = rails_worn_to_tonnages("minuetto", classes,
                                             sorted({*RAIL_TONNAGES_MT, tonnage}), law="usfd")
                rails.update(out.rails)
                print(f"  rails worn to {sorted(out.rails)} Mt: {out.rail_steps} rail steps "
                      f"of {', '.join(f'{t:.2f}' for t in out.tonnage_per_step_mt)} Mt in "
                      f"{time.perf_counter() - t0:.1f} s", flush=True)
            params["rail"] = rails[tonnage]
        t0 = time.perf_counter()
        sim = simulate_vehicle_wear("minuetto", classes, law=law, mileage_km=args.km,
                                    depth_per_step_mm=args.step,
                                    options=VehicleWearOptions(**params),
                                    contact_cache=contacts)
        label = {k: getattr(v, "name", v) for k, v in params.items()} or "null"
        print(f"  loop run {label} law={law}: {len(sim.mileage_km) - 1} steps in "
              f"{time.perf_counter() - t0:.1f} s; FT {sim.mean('sd_mm')[-1]:.2f}, "
              f"qR {sim.mean('qr_mm')[-1]:.2f} mm at {args.km:.0f} km", flush=True)
        return sim

    t0 = time.perf_counter()
    d = diagnose_physics(simulate, measured, catalogue=catalogue)
    print(f"physics diagnosis of the Aosta data: {time.perf_counter() - t0:.1f} s")
    print(json.dumps(d.to_dict(), indent=1, default=str))


if __name__ == "__main__":
    main()
