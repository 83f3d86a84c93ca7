"""Where one loop run of the Aosta diagnosis spends its steps and its time (issue 12 §6).

Run: .venv/bin/python benchmarks/catalogue_run_cost.py [--params '{"forward_share": 1.0}']
     [--km 8000] [--step 0.8] [--every 1000]

One run of ``benchmarks/diagnose_aosta_physics.py``'s catalogue (``--params``: the
``VehicleWearOptions`` of one catalogue value, ``law`` for the wear law; ``{}``: the null) on
seed 003's Table 3 classes, timed by wrapping (not changing) the loop's parts:

* Steps: the loop's step is D_step / the largest VERTICAL depth rate of any wheel (normal
  rate times sqrt(1 + z'^2), ``vehicle_wear_simulation``). Per ``--every`` km it prints the
  steps, their mean length, and the wheel, lateral position, slope factor sqrt(1 + z'^2) and
  normal rate of the step-setting point.
* Time: the contact tables (``curving_table.build_contact_table``), the curving solves from
  the last equilibrium (warm), the retries of the points that fail from it (continuation from
  centred wheelsets, ``class_contacts._solve_points``), the wear rates, and the rest.
* Retries: operating points retried, how many the retry solves, and the class fallbacks
  (classes and wheels that keep the previous update's contact).

Needs ../shared/reference.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

import wearcast.physics.class_contacts as class_contacts
import wearcast.physics.curving as curving
import wearcast.physics.vehicle_wear_simulation as vehicle_wear
from wearcast.statistics.generators.scenarios import seed003_classes

ROOT = Path(__file__).resolve().parents[1]
TRACK_CSV = ROOT.parent / "shared" / "reference" / "published" / \
    "aosta_statistical_track_nclass7.csv"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--params", default='{"forward_share": 1.0}',
                        help="one catalogue value as JSON ({} for the null)")
    parser.add_argument("--km", type=float, default=8000.0, help="mileage [km]")
    parser.add_argument("--step", type=float, default=0.8, help="D_step [mm]")
    parser.add_argument("--every", type=float, default=1000.0, help="report interval [km]")
    args = parser.parse_args()
    if not TRACK_CSV.exists():
        print(f"skipped: {TRACK_CSV} not found")
        return
    params = json.loads(args.params)
    law = params.pop("law", "usfd")
    classes = seed003_classes(pd.read_csv(TRACK_CSV, comment="#"))
    clock: dict[str, float] = {"table": 0.0, "cold": 0.0, "warm": 0.0, "retry": 0.0,
                               "rates": 0.0}
    counts = {"retried": 0, "retry_solved": 0}

    def timed(name: str, fn: Any) -> Any:
        def wrapper(*a: Any, **k: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                clock[name] += time.perf_counter() - t0
        return wrapper

    # _solve_points' solves: cold (a first update, no last equilibrium: initial_states None),
    # warm (from the last equilibria), retry (the warm failures from centred wheelsets: a list
    # of None)
    solve = curving.solve_curving_cases_or_none

    def solve_counted(vehicle: Any, cases: Any, labels: Any, table: Any, **k: Any) -> Any:
        init = k.get("initial_states")
        kind = ("cold" if init is None else
                "retry" if all(s is None for s in init) else "warm")
        t0 = time.perf_counter()
        out = solve(vehicle, cases, labels, table, **k)
        clock[kind] += time.perf_counter() - t0
        if kind == "retry":
            counts["retried"] += len(cases)
            counts["retry_solved"] += sum(r is not None for r in out)
        return out

    class_contacts.solve_curving_cases_or_none = solve_counted  # type: ignore[assignment]
    class_contacts.build_contact_table = timed(  # type: ignore[assignment]
        "table", class_contacts.build_contact_table)
    vehicle_wear._wheel_rates = timed("rates", vehicle_wear._wheel_rates)  # type: ignore

    # the step-setting point: rates (before the update) and profiles (after the previous one)
    y = np.linspace(*vehicle_wear.WHEEL_GRID_MM[:2],
                    int(round((vehicle_wear.WHEEL_GRID_MM[1] - vehicle_wear.WHEEL_GRID_MM[0])
                              / vehicle_wear.WHEEL_GRID_MM[2])) + 1)
    state: dict[str, Any] = {"profiles": None, "rows": []}
    check_rates, check_profiles = vehicle_wear._check_finite_rates, vehicle_wear._check_profiles

    def on_rates(rates: Any, labels: Any, mileage_km: float) -> None:
        prof = state["profiles"]
        if prof is None:
            prof = np.broadcast_to(vehicle_wear.s1002_height_mm(y), rates.shape)
        slope = np.gradient(prof, y, axis=-1)
        factor = np.sqrt(1.0 + slope * slope)
        i = np.unravel_index(int(np.argmax(rates * factor)), rates.shape)
        state["rows"].append((mileage_km, labels[i[0] * 4 + i[1]], float(y[i[2]]),
                              float(factor[i]), float(rates[i]) * 1000.0,
                              float(rates.max()) * 1000.0))
        check_rates(rates, labels, mileage_km)

    def on_profiles(y_mm: Any, z0: Any, profiles: Any, labels: Any, mileage_km: float) -> None:
        state["profiles"] = profiles.copy()
        check_profiles(y_mm, z0, profiles, labels, mileage_km)

    vehicle_wear._check_finite_rates = on_rates  # type: ignore[assignment]
    vehicle_wear._check_profiles = on_profiles  # type: ignore[assignment]

    t0, c0 = time.perf_counter(), time.process_time()
    sim = vehicle_wear.simulate_vehicle_wear(
        "minuetto", classes, law=law, mileage_km=args.km, depth_per_step_mm=args.step,
        options=vehicle_wear.VehicleWearOptions(**params))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    km = sim.mileage_km
    print(f"run {params or 'null'} (law {law}), D_step {args.step:g} mm to {args.km:.0f} km: "
          f"{len(km) - 1} steps, {sim.contact_updates} bogie contact updates, "
          f"{sim.contact_fallbacks} class fallbacks; {wall:.1f} s wall, {cpu:.1f} s CPU; "
          f"FT {sim.mean('sd_mm')[-1]:.4f}, FH {sim.mean('sh_mm')[-1]:.4f}, "
          f"qR {sim.mean('qr_mm')[-1]:.4f} mm")
    print("time: " + ", ".join(f"{k} {v:.1f} s ({100 * v / wall:.0f} %)"
                               for k, v in clock.items())
          + f", rest {wall - sum(clock.values()):.1f} s")
    print(f"retries from centred wheelsets: {counts['retried']} operating points, "
          f"{counts['retry_solved']} solved")
    print("km range       steps  mean step km  step set by (wheel, y mm, sqrt(1+z'^2), "
          "normal rate mm/1000 km)  largest normal rate")
    lo = 0.0
    while lo < args.km - 1e-9:
        hi = min(lo + args.every, args.km)
        rows = [r for r in state["rows"] if lo <= r[0] < hi]
        if rows:
            worst = max(rows, key=lambda r: r[3] * r[4])
            print(f"{lo:6.0f}-{hi:6.0f}  {len(rows):6d}  {(hi - lo) / len(rows):12.1f}  "
                  f"{worst[1]}, {worst[2]:.1f}, {worst[3]:.1f}, {worst[4]:.2f}"
                  f"{'':>22}{max(r[5] for r in rows):.2f}")
        lo = hi


if __name__ == "__main__":
    main()
