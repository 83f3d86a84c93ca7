"""CPU seconds of single loop runs of the Aosta diagnosis, this checkout against another one.

Run: .venv/bin/python benchmarks/catalogue_run_cpu.py [--params '{}' '{"forward_share": 1.0}']
     [--km 8000] [--step 0.8] [--baseline-python ../main/.venv/bin/python] [--repeat 1]

Each run is one catalogue value of ``benchmarks/diagnose_aosta_physics.py`` (``--params``: the
``VehicleWearOptions`` of the value, ``law`` for the wear law; ``{}``: the null) on seed 003's
Table 3 classes, made in a fresh process by each interpreter in turn (``--baseline-python``
first, then this one, interleaved run by run, so both see the same machine load). A run reports
the process CPU time of ``simulate_vehicle_wear`` alone (not the imports or numba's cache
loading), its steps, contact updates and class fallbacks, FT and qR at the end, and a digest
of the run's whole series (mileage, FT, FH and qR of every wheel at every step, bytes): equal
digests mean bit-identical runs. Needs ../shared/reference.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TRACK_CSV = ROOT.parent / "shared" / "reference" / "published" / \
    "aosta_statistical_track_nclass7.csv"
DEFAULT_PARAMS = ("{}", '{"forward_share": 1.0}', '{"flange_wear_factor": 0.5}')


def _child(params_json: str, km: float, step: float) -> None:
    import numpy as np
    import pandas as pd

    from wearcast.physics.vehicle_wear_simulation import (
        VehicleWearOptions,
        simulate_vehicle_wear,
    )
    from wearcast.statistics.generators.scenarios import seed003_classes

    params = json.loads(params_json)
    law = params.pop("law", "usfd")
    classes = seed003_classes(pd.read_csv(TRACK_CSV, comment="#"))
    c0 = time.process_time()
    sim = simulate_vehicle_wear("minuetto", classes, law=law, mileage_km=km,
                                depth_per_step_mm=step, options=VehicleWearOptions(**params))
    cpu = time.process_time() - c0
    digest = hashlib.sha256()
    for a in (sim.mileage_km, sim.sd_mm, sim.sh_mm, sim.qr_mm):
        digest.update(np.ascontiguousarray(a, dtype=float).tobytes())
    print(json.dumps({"cpu_s": cpu, "steps": len(sim.mileage_km) - 1,
                      "updates": sim.contact_updates, "fallbacks": sim.contact_fallbacks,
                      "ft_mm": float(sim.mean("sd_mm")[-1]),
                      "qr_mm": float(sim.mean("qr_mm")[-1]),
                      "digest": digest.hexdigest()[:16]}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--params", nargs="+", default=list(DEFAULT_PARAMS),
                        help="catalogue values as JSON ({} for the null)")
    parser.add_argument("--km", type=float, default=8000.0, help="mileage [km]")
    parser.add_argument("--step", type=float, default=0.8, help="D_step [mm]")
    parser.add_argument("--baseline-python", default=None, metavar="PY",
                        help="interpreter of the checkout to compare with (runs first)")
    parser.add_argument("--repeat", type=int, default=1, help="rounds over all runs")
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child is not None:
        _child(args.child, args.km, args.step)
        return
    if not TRACK_CSV.exists():
        print(f"skipped: {TRACK_CSV} not found")
        return
    pythons = ([("base", args.baseline_python)] if args.baseline_python else []) + [
        ("this", sys.executable)]
    totals = {name: 0.0 for name, _ in pythons}
    for rnd in range(args.repeat):
        for params in args.params:
            digests = {}
            for name, py in pythons:
                out = subprocess.run([py, str(Path(__file__).resolve()), "--child", params,
                                      "--km", str(args.km), "--step", str(args.step)],
                                     capture_output=True, text=True, check=True)
                r = json.loads(out.stdout.strip().splitlines()[-1])
                totals[name] += r["cpu_s"]
                digests[name] = r["digest"]
                print(f"round {rnd + 1} {name:4s} {params}: {r['cpu_s']:.1f} s CPU, "
                      f"{r['steps']} steps, {r['updates']} updates, {r['fallbacks']} "
                      f"fallbacks; FT {r['ft_mm']:.4f}, qR {r['qr_mm']:.4f} mm; series "
                      f"{r['digest']}", flush=True)
            if len(digests) == 2:
                same = len(set(digests.values())) == 1
                print(f"  {params}: series {'bit-identical' if same else 'DIFFER'}",
                      flush=True)
    print("total CPU: " + ", ".join(f"{k} {v:.1f} s" for k, v in totals.items())
          + (f"; this / base {totals['this'] / totals['base']:.3f}" if "base" in totals
             else ""))


if __name__ == "__main__":
    main()
