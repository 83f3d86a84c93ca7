"""Physics diagnosis of the whole-vehicle loop on the measured Minuetto wheels (seed 003 Table 2).

Run: .venv/bin/python benchmarks/diagnose_aosta_physics.py [--step 0.8] [--scale-max 1.5]
[--km 8000] [--workers 2] [--gap-smoothing masked --rail-edge-ramp-mm 3]

The model: ``physics.vehicle_wear_simulation`` (minuetto, two motor + two trailer bogies, both
running directions, all wheels averaged as measured) on seed 003's Table 3 classes with its
USFD law and one fitted wear-coefficient scale; the catalogue of
``statistics.physics_diagnosis`` (flange lubrication, friction level, running-direction share,
patch model, wear law, traction, rail state: the Minuetto's rail worn by its own passages on
the same classes to 5 and 10 Mt, ``physics.rail_tonnage``), each extension run at its
catalogue values to the mileage the scale search needs for scales up to --scale-max
(``physics_diagnosis.diagnosis_mileage_km``: --scale-max x the furthest measured mileage,
1.5 x 3,537 = 5,306 km; --km overrides it), scored leaving one vehicle out (3 vehicles: test
groups are points). The loop runs are independent of each other and of the measurements:
``--workers N`` (default 2, both cores of the reference machine) makes them in N processes
(the rail state's two runs in one, so its chain of rail steps is computed once), the same
runs as one after the other. Prints the time of every loop run and of the whole diagnosis,
the null fit, every finding, the verdict and the fits at their runs' reach (``at_reach``:
raise --scale-max). Needs ../shared/reference.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

import pandas as pd

from wearcast.physics import gap_smoothing as gs
from wearcast.physics.rail_tonnage import rails_worn_to_tonnages
from wearcast.physics.vehicle_wear_simulation import VehicleWearOptions, simulate_vehicle_wear
from wearcast.statistics.physics_causes import CATALOGUE, RAIL_TONNAGES_MT
from wearcast.statistics.physics_diagnosis import (
    DIAGNOSIS_SCALE_MAX,
    diagnose_physics,
    diagnosis_mileage_km,
    run_sequentially,
)

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT.parent / "shared" / "reference" / "published"
MEASURED_CSV = REFERENCE / "aosta_measured_FH_FT_QR.csv"
TRACK_CSV = REFERENCE / "aosta_statistical_track_nclass7.csv"

#: What every run of one process shares: the classes, mileage and step, the first contact
#: updates (same new profile) and the rail state's worn rails (one chain of rail steps).
_RUN: dict[str, Any] = {}


def _setup(km: float, cut: bool, step: float, gap_smoothing: str = gs.GAP_SMOOTHING,
           rail_edge_ramp_mm: float = gs.RAIL_EDGE_RAMP_MM) -> None:
    from validate_aosta_measured import aosta_classes  # benchmarks/ on sys.path when run

    # the contact tables' gap smoothing (physics/gap_smoothing.py), set in every process
    gs.GAP_SMOOTHING = gs.check_gap_smoothing(gap_smoothing)
    gs.RAIL_EDGE_RAMP_MM = rail_edge_ramp_mm
    _RUN.update(km=km, cut=cut, step=step, contacts={}, rails={},
                classes=aosta_classes(pd.read_csv(TRACK_CSV, comment="#")))


def simulate(params: Mapping[str, Any]) -> Any:
    """One whole-vehicle run of the catalogue (``{}``: the null), timed."""
    label = dict(params) or "null"
    params = dict(params)
    law = params.pop("law", "usfd")
    tonnage = params.pop("rail_tonnage_mt", 0.0)
    classes, rails, km = _RUN["classes"], _RUN["rails"], _RUN["km"]
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
    sim = simulate_vehicle_wear("minuetto", classes, law=law, mileage_km=km,
                                depth_per_step_mm=_RUN["step"],
                                options=VehicleWearOptions(**params),
                                contact_cache=_RUN["contacts"], cut_last_step=_RUN["cut"])
    print(f"  loop run {label}: {len(sim.mileage_km) - 1} steps in "
          f"{time.perf_counter() - t0:.1f} s; FT {sim.mean('sd_mm')[-1]:.2f}, "
          f"qR {sim.mean('qr_mm')[-1]:.2f} mm at {sim.mileage_km[-1]:.0f} km", flush=True)
    return sim


def _run_group(sets: Sequence[Mapping[str, Any]]) -> list[Any]:
    return [_attempt(p) for p in sets]


def _attempt(params: Mapping[str, Any]) -> Any:
    try:
        return simulate(params)
    except Exception as exc:  # the cause is skipped, saying why (the null's is raised)
        return exc


def parallel_runs(workers: int, km: float, cut: bool, step: float,
                  smoothing: tuple[str, float]):
    """A ``run_all`` for :func:`diagnose_physics` making the runs in ``workers`` processes."""

    def run_all(_simulate: Any, sets: Sequence[Mapping[str, Any]]) -> list[Any]:
        rail = [p for p in sets if p.get("rail_tonnage_mt")]
        # the rail state's group first: it holds the chain of rail steps and two runs, the
        # longest task; started last it would run alone at the end (longest task first)
        groups = ([rail] if rail else []) + [[p] for p in sets if not p.get("rail_tonnage_mt")]
        with ProcessPoolExecutor(workers, initializer=_setup,
                                 initargs=(km, cut, step, *smoothing)) as pool:
            done = [r for g in pool.map(_run_group, groups) for r in g]
        order = [p for g in groups for p in g]
        return [done[order.index(p)] for p in sets]

    return run_all


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--step", type=float, default=0.8, help="D_step [mm]")
    parser.add_argument("--scale-max", type=float, default=DIAGNOSIS_SCALE_MAX,
                        help="largest wear scale fitted on simulated mileage (sets the runs' "
                             "mileage: diagnosis_mileage_km)")
    parser.add_argument("--km", type=float, default=None,
                        help="simulated mileage [km] (default: from --scale-max and the data)")
    parser.add_argument("--workers", type=int, default=2,
                        help="processes making the loop runs (1: one after the other)")
    parser.add_argument("--causes", default=",".join(c.name for c in CATALOGUE),
                        help="comma-separated causes of the catalogue (default: all)")
    parser.add_argument("--gap-smoothing", default=gs.GAP_SMOOTHING,
                        choices=gs.GAP_SMOOTHING_METHODS,
                        help="the contact tables' gap smoothing (physics/gap_smoothing.py)")
    parser.add_argument("--rail-edge-ramp-mm", type=float, default=gs.RAIL_EDGE_RAMP_MM,
                        help="coverage ramp of the masked smoothing [mm] (gap_smoothing)")
    args = parser.parse_args()
    if not args.rail_edge_ramp_mm > 0:
        parser.error("--rail-edge-ramp-mm must be positive")
    smoothing = (args.gap_smoothing, args.rail_edge_ramp_mm)
    wanted = args.causes.split(",")
    unknown = set(wanted) - {c.name for c in CATALOGUE}
    if unknown:
        parser.error(f"unknown causes: {', '.join(sorted(unknown))}")
    catalogue = tuple(c for c in CATALOGUE if c.name in wanted)
    if not MEASURED_CSV.exists():
        print(f"skipped: {REFERENCE} not found")
        return
    measured = pd.read_csv(MEASURED_CSV, comment="#")
    km = args.km if args.km is not None else diagnosis_mileage_km(measured, args.scale_max)
    print(f"loop runs to {km:,.0f} km{'' if args.km is not None else ' (last step whole)'}",
          flush=True)
    # runs to the derived mileage keep their last step whole: each is then the first part of
    # the same run to any longer mileage, so every fit reading it up to there is unchanged;
    # --km cuts the last step to land on it, as before
    cut = args.km is not None
    _setup(km, cut, args.step, *smoothing)
    make = (parallel_runs(args.workers, km, cut, args.step, smoothing) if args.workers > 1
            else run_sequentially)
    runs_s = [0.0]

    def run_all(sim: Any, sets: Sequence[Mapping[str, Any]]) -> list[Any]:
        t_runs = time.perf_counter()
        out = make(sim, sets)
        runs_s[0] = time.perf_counter() - t_runs
        return out

    t0 = time.perf_counter()
    d = diagnose_physics(simulate, measured, catalogue=catalogue, run_all=run_all)
    total = time.perf_counter() - t0
    print(f"physics diagnosis of the Aosta data: {total:.1f} s ({args.workers} "
          f"worker{'s' if args.workers > 1 else ''}; loop runs {runs_s[0]:.1f} s, fits and "
          f"tests {total - runs_s[0]:.1f} s)")
    if d.at_reach:
        print(f"at their runs' reach (raise --scale-max): {', '.join(d.at_reach)}")
    print(json.dumps(d.to_dict(), indent=1, default=str))


if __name__ == "__main__":
    main()
