"""Detection table of the discrepancy finder: cause x strength x generator, false alarms.

Run: .venv/bin/python benchmarks/detection_rates.py [--seeds N] [--generators twin,alt,depot]
         [--causes traction,seasonal_friction,...] [--strengths all|moderate]
(~20-40 s per dataset on a loaded 2-core machine; keep N small while developing).

Generators (``wearcast.statistics.generators``):
- ``twin``: the fleet twin the finder was first built on (4 units x 3 cars, 6 measurements
  per wheel, processed profiles); calibration on unit A's motor bogies.
- ``alt``: ``fleet_twin_alt`` (3 units of 4/3/2 motor or trailer cars, missing measurements,
  uniform scatter, additive traction, running-in, linear load law, processed profiles);
  calibration on unit U1's motor cars.
- ``depot``: ``depot`` (calendar days, heavy-tailed heteroscedastic noise, random effects,
  missed and repeated visits, reprofiling mid-series, route changes, mixed instruments;
  areas with noise, profiles only for the instrument scale); calibration on unit N1's
  motor bogies.
Prints one line per (generator, cause, strength): the share of seeds whose verdict names the
cause, and per generator the false-alarm rate (verdict other than ``none``) on effect-free
data.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import pandas as pd

from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.generators import depot as dp
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import fleet_twin_alt as fa
from wearcast.statistics.generators import scenarios as sc
from wearcast.statistics.generators import twin_effects as te

TABLE = ft.synthetic_wear_table()


def _verdict(scenario: sc.Scenario) -> str:
    args, kwargs = scenario.finder_arguments()
    return diagnose(*args, **kwargs, n_boot=300).verdict


def run_twin(effect: Any, seed: int) -> str:
    we, pe = effect
    return _verdict(sc.twin_scenario(we, pe, seed=seed, table=TABLE))


def run_alt(effect: Any, seed: int) -> str:
    return _verdict(sc.alt_scenario(effect, seed))


def run_depot(effect: Any, seed: int) -> str:
    return _verdict(sc.depot_scenario(effect, seed))


# (strength, effect) from weak to strong; the last entry is the tests' moderate strength
SWEEPS: dict[str, tuple[Callable[[Any, int], str], Any, dict[str, list[tuple[Any, Any]]]]] = {
    "twin": (run_twin, ((), ()), {
        "traction": [(m, ((te.traction(m),), ())) for m in (1.1, 1.2)],
        "running_direction": [(p, ((te.running_direction(TABLE, p),), ())) for p in (0.6, 0.7)],
        "curve_asymmetry": [(q, ((te.curve_asymmetry(TABLE, q),), ())) for q in (0.6, 0.7)],
        "flange_lubrication": [(m, ((te.flange_lubrication(m),), ())) for m in (0.8, 0.7)],
        "wear_measure": [("t_gamma", ((te.wear_measure(TABLE),), ()))],
        "nonlinear_progression": [(b, ((te.nonlinear_progression(b),), ())) for b in (0.9, 0.85)],
        "seasonal_friction": [(a, ((te.seasonal_friction(a),), ())) for a in (0.1, 0.2)],
        "vehicle_load": [(g, ((te.vehicle_load(g),), ())) for g in (0.5, 1.0)],
        "profile_misalignment": [(o, ((), (te.flange_tread_offset("MP-2", o),)))
                                 for o in (0.1, 0.2)],
    }),
    "alt": (run_alt, fa.AltEffects(), {
        "traction": [(m, fa.AltEffects(traction=m)) for m in (1.2, 1.3)],
        "running_direction": [(p, fa.AltEffects(leading_share=p)) for p in (0.6, 0.7)],
        "curve_asymmetry": [(q, fa.AltEffects(left_share=q)) for q in (0.6, 0.7)],
        "flange_lubrication": [(m, fa.AltEffects(lubricated_flange=m)) for m in (0.8, 0.7)],
        "wear_measure": [("t_gamma", fa.AltEffects(true_measure="t_gamma"))],
        "nonlinear_progression": [(c, fa.AltEffects(running_in=c)) for c in (0.5, 1.0)],
        "seasonal_friction": [(a, fa.AltEffects(seasonal_amplitude=a)) for a in (0.2, 0.3)],
        "vehicle_load": [(g, fa.AltEffects(load_exponent=g)) for g in (1.0, 1.5)],
        "profile_misalignment": [(e, fa.AltEffects(instrument_scale=("LP-2", e)))
                                 for e in (0.005, 0.01)],
    }),
    "depot": (run_depot, dp.DepotEffects(), {
        "traction": [(m, dp.DepotEffects(traction=m)) for m in (1.1, 1.2)],
        "running_direction": [(p, dp.DepotEffects(leading_share=p)) for p in (0.6, 0.7)],
        "curve_asymmetry": [(q, dp.DepotEffects(left_share=q)) for q in (0.6, 0.7)],
        "flange_lubrication": [(m, dp.DepotEffects(greased_flange=m)) for m in (0.8, 0.6)],
        "wear_measure": [(w, dp.DepotEffects(measure_blend=w)) for w in (0.3, 0.6)],
        "nonlinear_progression": [(b, dp.DepotEffects(hardening=b)) for b in (0.9, 0.8)],
        "seasonal_friction": [(a, dp.DepotEffects(seasonal=a)) for a in (0.15, 0.3)],
        "vehicle_load": [(g, dp.DepotEffects(load_exponent=g)) for g in (1.0, 2.0)],
        "profile_misalignment": [(e, dp.DepotEffects(instrument_scale=("DP-B", e)))
                                 for e in (0.003, 0.006)],
    }),
}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--generators", default="twin,alt,depot")
    ap.add_argument("--causes", default="")
    ap.add_argument("--strengths", default="all", choices=("all", "moderate"))
    args = ap.parse_args()
    seeds = range(100, 100 + args.seeds)
    rows = []
    t0 = time.perf_counter()
    for gen in args.generators.split(","):
        run, null_effect, sweep = SWEEPS[gen]
        null = [run(null_effect, s) for s in seeds]
        fa_rate = sum(v != "none" for v in null) / len(null)
        print(f"{gen:6s} null data: false-alarm rate {fa_rate:.0%} over {len(null)} seeds "
              f"({', '.join(null)})", flush=True)
        rows.append({"generator": gen, "cause": "none (false alarms)", "strength": "-",
                     "rate": fa_rate, "n": len(null)})
        for cause, runs in sweep.items():
            if args.causes and cause not in args.causes.split(","):
                continue
            if args.strengths == "moderate":
                runs = runs[-1:]
            for strength, effect in runs:
                vs = [run(effect, s) for s in seeds]
                rate = sum(v == cause for v in vs) / len(vs)
                print(f"{gen:6s} {cause:22s} strength {strength!s:8s} named {rate:4.0%}  "
                      f"({', '.join(sorted(set(vs)))})", flush=True)
                rows.append({"generator": gen, "cause": cause, "strength": strength,
                             "rate": rate, "n": len(vs)})
    print()
    print(pd.DataFrame(rows).to_string(index=False))
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
