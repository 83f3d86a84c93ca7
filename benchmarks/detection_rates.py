"""Detection table of the discrepancy finder: cause x strength x generator, false alarms.

Run: .venv/bin/python benchmarks/detection_rates.py [--seeds N] [--first-seed S]
         [--generators twin,alt,depot,loop] [--causes traction,seasonal_friction,...]
         [--strengths all|moderate|S1,S2] [--no-null] [--verbose] [--loop-cache FILE]
         [--resampling wild|permute] [--loop-null simulated|linear]
         [--progression-stretch F] [--margin-test combined|bootstrap|sign_flip]
         [--margin-nuisance encompassing|runner_up] [--noise-weighting region|area|none]
         [--shape-weighting position_area|area|none] [--shape-growth life|none]
         [--shape-position position|none] [--echo-area scale_offset|scale]
         [--score-metric ols|gls|gls_vehicle]
         [--margin-metric ols|test]
         [--random-effects-levels vehicle_wheel|wheel] [--traction-fit gls|ols]
(3-6 s per dataset with 1-2 free cores, 20-40 s on a loaded machine; the loop generator's
eight wear-loop runs take about 5 minutes once per process, or once at all with
--loop-cache; ``--causes _`` runs only the effect-free datasets).

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
- ``loop``: ``fleet_twin_loop`` -- the twin's layout on one track geometry (tangent and
  500 m curves) with the physics wear loop as truth (metro_b, KTH/Archard law), processed
  profiles; the model's table holds the loop's own mean rates (``loop_table``); the running
  direction is hidden by weighting the loop's axle-1 and axle-2 runs; the finder's baseline
  grows as the same loop runs say (``--loop-null simulated``, the default:
  ``scenarios.loop_expected_progression``), or linearly (``--loop-null linear``, the hybrid
  model's law, which the loop's evolving profiles break). Causes the loop cannot
  carry on one geometry with one law (curve asymmetry, wear measure) are not in its sweep.
Prints one line per (generator, cause, strength): the share of seeds whose verdict names the
cause, and per generator the false-alarm rate (verdict other than ``none``) on effect-free
data; with --verbose one line per dataset (verdict, runner-up, margin and its p-value, the
three smallest adjusted p-values with their held-out gains).
"""

from __future__ import annotations

import argparse
import os
import pickle
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
import pandas as pd

from wearcast.statistics import cause_base as cb
from wearcast.statistics import causes as cz
from wearcast.statistics import finder_instrument as fi
from wearcast.statistics import finder_random_effects as fre
from wearcast.statistics import finder_scoring as fs
from wearcast.statistics import finder_shape_growth as fsg
from wearcast.statistics import finder_shape_position as fsp
from wearcast.statistics import finder_shape_weights as fsw
from wearcast.statistics import hybrid
from wearcast.statistics.discrepancy import diagnose
from wearcast.statistics.generators import depot as dp
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import fleet_twin_alt as fa
from wearcast.statistics.generators import fleet_twin_loop as fl
from wearcast.statistics.generators import scenarios as sc
from wearcast.statistics.generators import twin_effects as te
from wearcast.statistics.generators import twin_wear_table
from wearcast.statistics.generators.scenarios import (
    LOOP_MEASURE,
    LOOP_MILEAGES_KM,
    LOOP_TRUTH,
    loop_config,
)

TABLE = twin_wear_table.synthetic_wear_table()


def _diagnosis(scenario: sc.Scenario) -> Any:
    args, kwargs = scenario.finder_arguments()
    return diagnose(*args, **kwargs, n_boot=300)


def run_twin(effect: Any, seed: int) -> Any:
    we, pe = effect
    return _diagnosis(sc.twin_scenario(we, pe, seed=seed, table=TABLE))


def run_alt(effect: Any, seed: int) -> Any:
    return _diagnosis(sc.alt_scenario(effect, seed))


def run_depot(effect: Any, seed: int) -> Any:
    return _diagnosis(sc.depot_scenario(effect, seed))


# --- the loop-driven generator ---------------------------------------------------------------
# Truth from the physics wear loop (``fleet_twin_loop``): per (route, bogie type, axle, side)
# one quasi-static wear-loop run of the metro_b vehicle (archard_kth law, 6 fixed steps), each
# wheel's wear curve the loop's at its own mileage times its rate factor. The hybrid model is
# calibrated with a table of the loop's own mean rates (``loop_table``), so the null carries
# what the loop does beyond the hybrid model's linear law (its profile evolution). Loop runs
# are deterministic and cached across seeds.

_LOOP_CACHE: dict[Any, Any] = {}
_LOOP_TABLE: list[pd.DataFrame] = []
_LOOP_PROGRESSION: list[Any] = []
# the loop's null: "simulated" (the baseline grows as the loop runs of the track say,
# ``scenarios.loop_expected_progression``) or "linear" (the hybrid model's linear law)
LOOP_NULL = ["simulated"]
# the simulation's km per fleet km relative to the loop that made the data (1: the same
# wear speed; 1.3: the user's simulation wears 30 % slower, so its progression is stretched)
LOOP_PROGRESSION_STRETCH = [1.0]


def _loop_runs() -> dict[tuple[str, int], list[Any]]:
    runs = {(b, a): [v for k, v in _LOOP_CACHE.items() if k[4] == b and k[5] == a]
            for b in ("motor", "trailer") for a in (1, 2)}
    if not all(runs.values()):
        raise RuntimeError("generate a loop fleet before building its table")
    return runs


def loop_table() -> pd.DataFrame:
    """The curve-radius table of the loop's own wear rates (built once, after the loop runs).

    With the physics core's table of the new profile (``physics.wear_tables``) the finder
    names ``wear_measure`` or ``running_direction`` on every effect-free loop dataset (held-out
    gains of 25-47 % with tau_max or T-gamma): the loop's worn profiles share the wear between
    the leading and trailing wheelsets differently from the new profile's contact, which is
    what the hybrid model gets wrong, not a false alarm. The null needs a table that is right
    for this track: per bogie type, wheelset and region, the least-squares rate (through the
    origin) of the loop's wear area over the loop mileage the fleet spans [mm^2 per 1,000 km],
    the same on every rail and for both measures (one track geometry with equal left and right
    curves: the route's measure is then exactly that rate). What remains for the finder is the
    loop's own profile evolution (a rate that changes with the worn amount) and the nuisance.
    """
    if not _LOOP_TABLE:
        _LOOP_TABLE.append(sc.loop_rate_table(
            _loop_runs(), max(LOOP_MILEAGES_KM) * LOOP_TRUTH.mileage_scale))
    return _LOOP_TABLE[0]


def loop_progression() -> Any:
    """The progression the same loop runs expect (``scenarios.loop_expected_progression``):
    the loop's wear is not linear in mileage (its profiles evolve), so the finder's null on
    loop data grows as the loop says, as a user's would after simulating the route; None
    with ``--loop-null linear``."""
    if LOOP_NULL[0] == "linear":
        return None
    if not _LOOP_PROGRESSION:
        ep = sc.loop_expected_progression(
            _loop_runs(), max(LOOP_MILEAGES_KM) * LOOP_TRUTH.mileage_scale,
            LOOP_TRUTH.mileage_scale)
        _LOOP_PROGRESSION.append(replace(ep, mileage_km=ep.mileage_km
                                         * LOOP_PROGRESSION_STRETCH[0]))
    return _LOOP_PROGRESSION[0]


def loop_leading_share(p: float) -> Callable[[ft.WheelSpec, ft.WearHistory], ft.WearHistory]:
    """Mixed-mode axle 1 leads a share p of the distance (axle 2 the rest): each region's
    areas rescaled from the loop's 50/50 mix of its axle-1 and axle-2 runs to p/(1 - p)."""
    def effect(wheel: ft.WheelSpec, history: ft.WearHistory) -> ft.WearHistory:
        if wheel.running_mode != "mixed":
            return history
        by_axle = {k[5]: v for k, v in _LOOP_CACHE.items()
                   if k[3] == wheel.route.classes and k[4] == wheel.bogie_type
                   and k[6] == wheel.side}
        if set(by_axle) != {1, 2}:
            raise RuntimeError("loop runs of both axles must be cached before the effect")
        km = history.mileage_km * LOOP_TRUTH.mileage_scale
        share = p if wheel.axle == 1 else 1.0 - p
        out = {}
        per_axle = {ax: sc.loop_wear_areas(by_axle[ax], km) for ax in (1, 2)}
        for region, area in (("tread", history.tread_area_mm2),
                             ("flange", history.flange_area_mm2)):
            a = {ax: per_axle[ax][region] for ax in (1, 2)}
            mix = 0.5 * (a[1] + a[2])
            new = share * a[1] + (1.0 - share) * a[2]
            out[region] = area * np.where(mix > 0, new / np.where(mix > 0, mix, 1.0), 1.0)
        return replace(history, tread_area_mm2=out["tread"], flange_area_mm2=out["flange"])
    return effect


def loop_case(effect: Any, seed: int) -> tuple[pd.DataFrame, Any, dict[str, Any],
                                                dict[str, Any], pd.DataFrame, Any]:
    we, pe = effect
    cfg = loop_config(seed, we, pe)
    fleet = fl.generate_loop_fleet(cfg, LOOP_TRUTH, cache=_LOOP_CACHE).fleet
    df, curves = te.twin_measurements(fleet)
    routes, attrs = te.scenario_routes(cfg)
    table = loop_table()
    cal = (df["vehicle_id"].str.startswith("A") & (df["bogie_type"] == "motor")).to_numpy()
    model = hybrid.calibrate(df[cal], routes, table, wear_curves_mm=curves[cal],
                             measure=LOOP_MEASURE, running_mode="mixed")
    return df, curves, routes, attrs, table, (model, cal)


def run_loop(effect: Any, seed: int) -> Any:
    df, curves, routes, attrs, table, (model, cal) = loop_case(effect, seed)
    return diagnose(model, df, curves, routes, table, route_attributes=attrs,
                    calibration_wheel_ids=set(df["wheel_id"][cal]), n_boot=300,
                    expected_progression=loop_progression())


# (strength, effect) from weak to strong; the last entry is the tests' moderate strength
SWEEPS: dict[str, tuple[Callable[[Any, int], Any], Any, dict[str, list[tuple[Any, Any]]]]] = {
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
                                 for o in (0.1, 0.2, 0.3)],
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
        "traction": [(m, dp.DepotEffects(traction=m)) for m in (1.1, 1.2, 1.3)],
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
    "loop": (run_loop, ((), ()), {
        "traction": [(m, ((te.traction(m),), ())) for m in (1.1, 1.15, 1.2, 1.3)],
        "running_direction": [(p, ((loop_leading_share(p),), ())) for p in (0.6, 0.7)],
        "flange_lubrication": [(m, ((te.flange_lubrication(m),), ())) for m in (0.8, 0.7)],
        "nonlinear_progression": [(b, ((te.nonlinear_progression(b),), ())) for b in (0.9, 0.85)],
        "seasonal_friction": [(a, ((te.seasonal_friction(a),), ()))
                              for a in (0.1, 0.15, 0.2, 0.3)],
        "vehicle_load": [(g, ((te.vehicle_load(g),), ())) for g in (0.5, 1.0)],
        "profile_misalignment": [(o, ((), (te.flange_tread_offset("MP-2", o),)))
                                 for o in (0.1, 0.2)],
    }),
}


def detail(d: Any) -> str:
    """Verdict, runner-up, margin and its p, and the smallest adjusted p-values."""
    ps = sorted((f.evidence.get("p_value", 1.0), f.cause, f.gain.relative) for f in d.findings)
    top = ", ".join(f"{c} p={p:.3f} gain={g:.3f}" for p, c, g in ps[:3])
    margin = "" if d.margin is None else f" margin={d.margin:.4f} p_m={d.margin_p_value:.3f}"
    extra = f" candidates={list(d.candidates)}" if d.candidates else ""
    extra += f" unexplained={[u['by'] for u in d.unexplained]}" if d.unexplained else ""
    return f"{d.verdict} (runner-up {d.runner_up}{margin}; {top}){extra}"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--generators", default="twin,alt,depot")
    ap.add_argument("--causes", default="")
    ap.add_argument("--strengths", default="all",
                    help="all, moderate (the last of each sweep) or a comma-separated list of "
                         "strengths to run (e.g. 1.1,0.1)")
    ap.add_argument("--first-seed", type=int, default=100)
    ap.add_argument("--no-null", action="store_true", help="skip the effect-free datasets")
    ap.add_argument("--verbose", action="store_true",
                    help="one line per dataset: verdict, runner-up, margin, p-values")
    ap.add_argument("--resampling", default=fs.RESAMPLING, choices=("wild", "permute"),
                    help="nuisance-only resampling of the finder (finder_scoring.RESAMPLING)")
    ap.add_argument("--margin-test", default=fs.MARGIN_TEST,
                    choices=("combined", "bootstrap", "sign_flip"),
                    help="test of the verdict's margin over the runner-up "
                         "(finder_scoring.MARGIN_TEST)")
    ap.add_argument("--margin-nuisance", default=fs.NUISANCE_OF_MARGIN,
                    choices=("encompassing", "runner_up"),
                    help="nuisance of the margin's bootstrap: residuals of the fit carrying "
                         "both causes or of the runner-up's own fit "
                         "(finder_scoring.NUISANCE_OF_MARGIN)")
    ap.add_argument("--noise-weighting", default=cb.NOISE_WEIGHTING,
                    choices=("region", "area", "none"),
                    help="precision weights of the finder's rows: one noise scale per region, "
                         "a variance function of the predicted area, or Huber weights alone "
                         "(cause_base.NOISE_WEIGHTING)")
    ap.add_argument("--shape-weighting", default=fsw.SHAPE_WEIGHTING,
                    choices=("position_area", "area", "none"),
                    help="precision weights of the wear-curve (instrument) cause's rows: a "
                         "variance function of the predicted worn area with a factor per "
                         "wheel position (between-wheel test), of the area alone, or none "
                         "(finder_shape_weights.SHAPE_WEIGHTING)")
    ap.add_argument("--shape-growth", default=fsg.SHAPE_GROWTH, choices=("life", "none"),
                    help="wear-curve (instrument) cause: each wheel life's shape coefficients "
                         "less their growth with the worn area, or as measured "
                         "(finder_shape_growth.SHAPE_GROWTH)")
    ap.add_argument("--shape-position", default=fsp.SHAPE_POSITION,
                    choices=("position", "none"),
                    help="wear-curve (instrument) cause: the coefficients less the shape of "
                         "each wheel's position (bogie type, leading share), or not "
                         "(finder_shape_position.SHAPE_POSITION)")
    ap.add_argument("--echo-area", default=fi.AREA_DISTORTION, choices=("scale_offset", "scale"),
                    help="a named instrument's area distortion in the echo test of the area "
                         "causes named beside it: a log-scale and an additive area per "
                         "instrument and region, or the log-scale alone "
                         "(finder_instrument.AREA_DISTORTION)")
    ap.add_argument("--score-metric", default=fs.SCORE_METRIC,
                    choices=("ols", "gls", "gls_vehicle"),
                    help="held-out error of the finder's tests: weighted squared residuals, "
                         "or after the nested vehicle/wheel random-effects transform, or "
                         "after a random log-scale per vehicle (finder_scoring.SCORE_METRIC)")
    ap.add_argument("--within-vehicle-margin", default=fs.WITHIN_VEHICLE_MARGIN,
                    choices=("bootstrap", "combined"),
                    help="margin test of a within-vehicle best cause (traction) scored in the "
                         "vehicle metric: the bootstrap alone or the combined test "
                         "(finder_scoring.WITHIN_VEHICLE_MARGIN)")
    ap.add_argument("--margin-rivals", default=fs.MARGIN_RIVALS, choices=("named", "all"),
                    help="causes the verdict's margin is tested against: those significant "
                         "and material themselves, or every other cause "
                         "(finder_scoring.MARGIN_RIVALS)")
    ap.add_argument("--margin-metric", default=fs.MARGIN_METRIC, choices=("ols", "test"),
                    help="metric of the margin test: the reported gains' or the tests' "
                         "(finder_scoring.MARGIN_METRIC)")
    ap.add_argument("--random-effects-levels", default=fre.LEVELS,
                    choices=("vehicle_wheel", "wheel"),
                    help="random effects of the GLS fits: nested vehicle and wheel, or wheel "
                         "only (finder_random_effects.LEVELS)")
    ap.add_argument("--traction-fit", default="gls", choices=("gls", "ols"),
                    help="traction multiplier from the random-effects GLS fit or by least "
                         "squares (causes.Traction.random_effects)")
    ap.add_argument("--loop-null", default="simulated", choices=("simulated", "linear"),
                    help="loop generator: baseline grows as the loop runs say or linearly")
    ap.add_argument("--progression-stretch", type=float, default=1.0,
                    help="loop generator: the expected progression's mileage axis times this "
                         "(a simulation that wears slower > 1, faster < 1 than the data)")
    ap.add_argument("--loop-cache", default="",
                    help="pickle file keeping the wear-loop runs between invocations")
    args = ap.parse_args()
    fs.RESAMPLING = args.resampling
    fs.MARGIN_TEST = args.margin_test
    fs.NUISANCE_OF_MARGIN = args.margin_nuisance
    cb.NOISE_WEIGHTING = args.noise_weighting
    fsw.SHAPE_WEIGHTING = args.shape_weighting
    fsg.SHAPE_GROWTH = args.shape_growth
    fsp.SHAPE_POSITION = args.shape_position
    fi.AREA_DISTORTION = args.echo_area
    fs.SCORE_METRIC = args.score_metric
    fs.MARGIN_METRIC = args.margin_metric
    fs.WITHIN_VEHICLE_MARGIN = args.within_vehicle_margin
    fs.MARGIN_RIVALS = args.margin_rivals
    fre.LEVELS = args.random_effects_levels
    cz.Traction.random_effects = args.traction_fit == "gls"
    LOOP_NULL[0] = args.loop_null
    LOOP_PROGRESSION_STRETCH[0] = args.progression_stretch
    if args.loop_cache and os.path.exists(args.loop_cache):
        with open(args.loop_cache, "rb") as fh:
            _LOOP_CACHE.update(pickle.load(fh))
    seeds = range(args.first_seed, args.first_seed + args.seeds)

    def verdicts(run: Callable[[Any, int], Any], effect: Any, label: str) -> list[str]:
        out = []
        for s in seeds:
            t = time.perf_counter()
            n_loop = len(_LOOP_CACHE)
            d = run(effect, s)
            if args.loop_cache and len(_LOOP_CACHE) > n_loop:
                with open(args.loop_cache, "wb") as fh:
                    pickle.dump(_LOOP_CACHE, fh)
            out.append(d.verdict)
            if args.verbose:
                print(f"    {label} seed {s}: {detail(d)} [{time.perf_counter() - t:.0f} s]",
                      flush=True)
        return out

    rows = []
    t0 = time.perf_counter()
    for gen in args.generators.split(","):
        run, null_effect, sweep = SWEEPS[gen]
        if not args.no_null:
            null = verdicts(run, null_effect, f"{gen} null")
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
            elif args.strengths != "all":
                runs = [r for r in runs if str(r[0]) in args.strengths.split(",")]
            for strength, effect in runs:
                vs = verdicts(run, effect, f"{gen} {cause} {strength}")
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
