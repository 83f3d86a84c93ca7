"""Detection rates of the discrepancy finder: seeds x effects x strengths.

Run: .venv/bin/python benchmarks/detection_rates.py [n_seeds] [--alt]   (default 5 seeds;
~4 s per dataset). ``--alt`` runs the same sweep on the independent generator
``fleet_twin_alt`` (3 units of 4/3/2 motor or trailer cars, ~12 % missing measurements,
uniform wheel/vehicle scatter, heteroscedastic area noise, its own shapes and injections;
calibration on unit U1's motor cars).
Prints, per cause and strength, the share of seeds whose verdict names the cause; the
false-positive rate on effect-free data; and the detection limit per cause = the weakest
strength found in every seed. Noise: the twin's defaults (10 % per-wheel rate scatter, 3 %
per-measurement area scatter, 0.015 mm profile noise, rigid misalignment), fleet of
``twin_effects.scenario_config`` (96 wheels x 6 measurements), calibration on unit A motors.
"""

from __future__ import annotations

import sys
import time

from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import fleet_twin_alt as fa
from wearcast.statistics import hybrid
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.discrepancy import diagnose

TABLE = ft.synthetic_wear_table()
# strengths from weak to strong (the moderate one used by the tests is marked *)
SWEEP = {
    "traction": [(m, (te.traction(m),), ()) for m in (1.05, 1.1, 1.2, 1.3)],
    "running_direction": [(p, (te.running_direction(TABLE, p),), ())
                          for p in (0.55, 0.6, 0.7, 0.8)],
    "curve_asymmetry": [(q, (te.curve_asymmetry(TABLE, q),), ()) for q in (0.55, 0.6, 0.7)],
    "flange_lubrication": [(m, (te.flange_lubrication(m),), ()) for m in (0.9, 0.8, 0.7, 0.5)],
    "wear_measure": [("t_gamma", (te.wear_measure(TABLE),), ())],
    "nonlinear_progression": [(b, (te.nonlinear_progression(b),), ())
                              for b in (0.95, 0.9, 0.85, 0.75)],
    "seasonal_friction": [(a, (te.seasonal_friction(a),), ()) for a in (0.1, 0.2, 0.3)],
    "vehicle_load": [(g, (te.vehicle_load(g),), ()) for g in (0.5, 1.0, 1.5)],
    "profile_misalignment": [(o, (), (te.flange_tread_offset("MP-2", o),))
                             for o in (0.1, 0.2, 0.3)],
}


def verdict(we, pe, seed: int) -> str:
    cfg = te.scenario_config(seed=seed, wear_effects=we, profile_effects=pe)
    df, curves = te.twin_measurements(ft.generate_fleet(cfg, TABLE))
    routes, attrs = te.scenario_routes(cfg)
    cal = (df["vehicle_id"].str.startswith("A") & (df["bogie_type"] == "motor")).to_numpy()
    model = hybrid.calibrate(df[cal], routes, TABLE, wear_curves_mm=curves[cal],
                             measure="tau_max", running_mode="mixed")
    return diagnose(model, df, curves, routes, TABLE, route_attributes=attrs,
                    calibration_wheel_ids=set(df["wheel_id"][cal]), n_boot=300).verdict


# the alternative generator: (strength, AltEffects, None); last entry = the tests' strength
ALT_SWEEP = {
    "traction": [(m, fa.AltEffects(traction=m), None) for m in (1.1, 1.2, 1.3, 1.4)],
    "running_direction": [(p, fa.AltEffects(leading_share=p), None)
                          for p in (0.55, 0.6, 0.7, 0.8)],
    "curve_asymmetry": [(q, fa.AltEffects(left_share=q), None) for q in (0.55, 0.6, 0.7)],
    "flange_lubrication": [(m, fa.AltEffects(lubricated_flange=m), None)
                           for m in (0.9, 0.8, 0.7, 0.5)],
    "wear_measure": [("t_gamma", fa.AltEffects(true_measure="t_gamma"), None)],
    "nonlinear_progression": [(c, fa.AltEffects(running_in=c), None)
                              for c in (0.25, 0.5, 1.0)],
    "seasonal_friction": [(a, fa.AltEffects(seasonal_amplitude=a), None)
                          for a in (0.1, 0.2, 0.3)],
    "vehicle_load": [(g, fa.AltEffects(load_exponent=g), None) for g in (0.5, 1.0, 1.5)],
    "profile_misalignment": [(e, fa.AltEffects(instrument_scale=("LP-2", e)), None)
                             for e in (0.0025, 0.005, 0.01)],
}


def verdict_alt(effects, _unused, seed: int) -> str:
    fleet = fa.generate_alt_fleet(fa.AltConfig(effects=effects or fa.AltEffects(), seed=seed))
    df, curves = fleet.measurements, fleet.wear_curves
    cal = (df["unit"].eq("U1") & df["bogie_type"].eq("motor")).to_numpy()
    model = hybrid.calibrate(df[cal], fleet.routes, fleet.table, wear_curves_mm=curves[cal],
                             measure="tau_max", running_mode="mixed")
    return diagnose(model, df, curves, fleet.routes, fleet.table,
                    route_attributes=fleet.route_attributes,
                    calibration_wheel_ids=set(df["wheel_id"][cal]), n_boot=300).verdict


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    alt = "--alt" in sys.argv[1:]
    n_seeds = int(args[0]) if args else 5
    sweep = ALT_SWEEP if alt else SWEEP
    run = verdict_alt if alt else verdict
    print(f"generator: {'fleet_twin_alt' if alt else 'fleet_twin'}")
    seeds = range(100, 100 + n_seeds)
    t0 = time.perf_counter()
    null = [run((), (), s) for s in seeds]
    fp = sum(v != "none" for v in null) / len(null)
    print(f"null data: false-positive rate {fp:.0%} over {len(null)} seeds ({null})")
    correct = total = 0
    for cause, runs in sweep.items():
        limit = None
        for strength, we, pe in runs:
            vs = [run(we, pe, s) for s in seeds]
            rate = sum(v == cause for v in vs) / len(vs)
            print(f"{cause:22s} strength {strength!s:8s} correct {rate:4.0%}  "
                  f"({', '.join(sorted(set(vs)))})")
            if rate == 1.0 and limit is None:
                limit = strength
        # the last (strongest) entry is the tests' moderate strength: count its verdicts
        correct += sum(v == cause for v in vs)
        total += len(vs)
        print(f"{cause:22s} detection limit (all seeds correct): {limit}")
    print(f"moderate strengths: {correct}/{total} correct verdicts ({correct / total:.0%}); "
          f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
