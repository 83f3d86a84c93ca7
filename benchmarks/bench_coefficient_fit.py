"""Benchmark: seed 000's calibration of the zone coefficients, exact vs four metaheuristics.

Run: .venv/bin/python benchmarks/bench_coefficient_fit.py [--noise 0.005] [--full-loop]
Twin data: the wear loop with known coefficients (metro_b, seed 000 Table 1 track bands plus a
250 m curve; fit at 50 km, predict at 80 km, 5 km steps -- seed 000's 50,000 / 80,000 / 5,000 km
divided by 1000 because the quasi-static contact puts the flange in the KTH seizure zone and
wears ~1000x faster than the seed's measured wheels). All methods share the outer loop
(profile feedback) and the same model runs; they differ in the inner solver only.
Outer iteration stops when no coefficient moves by more than 1 % (rtol=1e-2), for every method;
every method also shares the outer loop's two savings (a no-feedback predictor run to start the
iteration, exact reuse of the initial profile's contact), so the reported RMSE is that of a fresh
full loop run at the final coefficients. Timing is per method, from scratch (no cache shared
between methods). A method whose last inner solve returns its previous point unchanged (tabu
search here) gets its final run's contacts from the cache: bit-identical profiles, no new solve.
Prints a table like seed 000 Table 2 and the exact method's speed-up over the seed's fastest
optimiser (PSO, 212 s; target >= 100x at equal or lower RMSE). ``--full-loop`` adds the
metaheuristics run as the seed ran them (one whole loop run per objective evaluation, ~200 runs
each), timed on this machine against the exact method of the same run.
"""

from __future__ import annotations

import argparse

import pandas as pd

from wearcast.physics.vocabulary import CurveClass
from wearcast.statistics.coefficient_fit import CalibrationProblem, calibrate_full_loop
from wearcast.statistics.coefficient_fit_comparison import comparison_table
from wearcast.statistics.coefficient_fit_twin import make_twin

SEED_000_PSO_S = 212.0  # seed 000 Table 2, line 1, 50,000 km
CLASSES = [CurveClass(r, 0.0, v, d, s / 2) for r, s, v in ((1500.0, 75, 70), (700.0, 22, 60),
                                                           (250.0, 3, 30))
           for d in ("left", "right")]
TRUE_K = (3e-4, 33e-4, 7e-4, 330e-4)
BOUNDS = ((1e-4, 10e-4), (30e-4, 40e-4), (1e-4, 10e-4), (300e-4, 400e-4))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--noise", type=float, default=0.005, help="measurement noise [mm]")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--full-loop", action="store_true",
                        help="also run the metaheuristics with one whole loop run per "
                        "evaluation, as seed 000 did (~5-10 min)")
    args = parser.parse_args()
    twin = make_twin("metro_b", CLASSES, TRUE_K, 50.0, 80.0, 5.0, noise_mm=args.noise,
                     seed=args.seed, contact_update_depth_mm=0.1)
    problem = CalibrationProblem("metro_b", CLASSES, twin.y_mm, twin.wear_fit_mm, 50.0,
                                 step_km=5.0, free=(0, 1, 2, 3), bounds=BOUNDS,
                                 contact_update_depth_mm=0.1)
    table = comparison_table(problem, ["exact", "GA", "PSO", "TS", "SA", "DE"],
                             predict_mileage_km=80.0, predict_wear_mm=twin.wear_predict_mm,
                             seed=args.seed, rtol=1e-2)
    pd.set_option("display.width", 200)
    pd.set_option("display.max_columns", 20)
    cols = ["method", "rmse_mm", "max_depth_mm", "re_max_depth_pct", "time_s", "model_runs",
            "evaluations", "k1", "k4", "rmse_predict_mm", "re_max_depth_predict_pct"]
    print(f"twin: true k1 = {TRUE_K[0]:.2e}, k4 = {TRUE_K[3]:.2e} (k2, k3: zones never met); "
          f"noise {args.noise} mm; measured max depth {twin.wear_fit_mm.max():.3f} mm")
    print(table[cols].to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    t = table.set_index("method")
    exact = t.loc["exact"]
    best_heur = t.loc[["GA", "PSO", "TS", "SA", "DE"], "rmse_mm"].min()
    verdict = "equal or lower" if exact.rmse_mm <= best_heur * (1 + 1e-6) else "HIGHER"
    print(f"exact: {exact.time_s:.2f} s -> {SEED_000_PSO_S / exact.time_s:.0f}x faster than "
          f"seed 000's PSO (212 s); RMSE {exact.rmse_mm:.5f} mm vs best metaheuristic "
          f"{best_heur:.5f} mm ({verdict})")
    print(f"inner solve only (model runs excluded): the metaheuristics make "
          f"{int(t.loc[['GA', 'PSO', 'TS', 'SA', 'DE'], 'evaluations'].min())}-"
          f"{int(t.loc[['GA', 'PSO', 'TS', 'SA', 'DE'], 'evaluations'].max())} objective calls, "
          f"the exact method {int(exact.evaluations)} bounded least-squares solves; "
          f"seed 000's optimisers ran the whole simulation per call")
    if args.full_loop:
        _full_loop(problem, exact.time_s, exact.rmse_mm, args.seed)


def _full_loop(problem: CalibrationProblem, exact_s: float, exact_rmse: float, seed: int) -> None:
    """The four metaheuristics (and DE) the seed's way: one whole loop run per evaluation."""
    print("full-loop metaheuristics (seed 000's set-up; budgets FULL_LOOP_BUDGETS, ~200 loop "
          "runs each):")
    print("method              rmse_mm    time_s  loop_runs  s/run   k1        k4        "
          "time / exact")
    for method in ("GA", "PSO", "TS", "SA", "DE"):
        fit = calibrate_full_loop(problem, method, seed=seed)
        print(f"{fit.method:18s}  {fit.rmse_mm:.6f}  {fit.time_s:7.1f}  {fit.model_runs:9d}  "
              f"{fit.time_s / fit.model_runs:.3f}  {fit.coefficients[0]:.3e}  "
              f"{fit.coefficients[3]:.3e}  {fit.time_s / exact_s:6.0f}x   "
              f"(exact: {exact_rmse:.6f} mm)")


if __name__ == "__main__":
    main()
