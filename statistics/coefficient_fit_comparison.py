"""Seed 000 Table 2 for our methods: every fitting method of
:mod:`wearcast.statistics.coefficient_fit` on one problem, with RMSE, maximum depth and its
relative error, time, loop runs and evaluations, and the same at a prediction mileage.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from wearcast.statistics.coefficient_fit import (
    METHODS,
    CalibrationProblem,
    FitResult,
    calibrate,
    rmse_mm,
    run_model,
)


def compare_methods(problem: CalibrationProblem, methods: Sequence[str] = METHODS, *,
                    predict_mileage_km: float | None = None,
                    predict_wear_mm: ArrayLike | None = None, seed: int = 0,
                    max_runs: int = 5, rtol: float = 1e-4,
                    progress: Callable[[int, int, str], None] | None = None
                    ) -> tuple[pd.DataFrame, dict[str, FitResult]]:
    """Seed 000 Table 2 for our methods and the fits behind it.

    Returns (table, fits): the table has RMSE [mm], maximum depth [mm] and its relative error
    [%], time [s], loop runs, objective evaluations, the coefficients (k1..k4, or
    c_tau_mm_per_m_mpa for tau_max), and (optionally) the same at a
    prediction mileage; a ``traditional_mean_k`` row evaluates the start coefficients (seed 000
    §VI). ``progress(done, total, method)`` is called after each method.
    """
    for m in methods:
        if m not in METHODS:
            raise ValueError(f"methods: unknown method {m!r}; known: {', '.join(METHODS)}")
    rows = []
    fits: dict[str, FitResult] = {}
    y = np.asarray(problem.y_mm, dtype=float)
    w = np.asarray(problem.wear_mm, dtype=float)

    def row(name, k, rmse, max_d, re, t, runs, evals):
        r = {"method": name, "rmse_mm": rmse, "max_depth_mm": max_d, "re_max_depth_pct": re,
             "time_s": t, "model_runs": runs, "evaluations": evals}
        r.update({name: float(v) for name, v in zip(problem.coefficient_names, k, strict=True)})
        if predict_mileage_km is not None:
            sim = run_model(problem, k, predict_mileage_km)
            model = np.interp(y, sim.y_mm, sim.wear_mm[-1])
            r["max_depth_predict_mm"] = float(model.max())
            if predict_wear_mm is not None:
                pw = np.asarray(predict_wear_mm, dtype=float)
                r.update({"rmse_predict_mm": rmse_mm(model, pw),
                          "re_max_depth_predict_pct": 100.0 * (model.max() - pw.max())
                          / pw.max()})
        rows.append(r)

    base = run_model(problem, problem.start)
    model = np.interp(y, base.y_mm, base.wear_mm[-1])
    row("traditional_mean_k", problem.start, rmse_mm(model, w), float(model.max()),
        100.0 * (model.max() - w.max()) / w.max(), float("nan"), 1, 0)
    for i, m in enumerate(methods):
        fit = calibrate(problem, m, seed=seed, max_runs=max_runs, rtol=rtol)
        fits[m] = fit
        row(m, fit.coefficients, fit.rmse_mm, fit.max_depth_mm, fit.re_max_depth_pct,
            fit.time_s, fit.model_runs, fit.evaluations)
        if progress is not None:
            progress(i + 1, len(methods), m)
    return pd.DataFrame(rows), fits


def comparison_table(problem: CalibrationProblem, methods: Sequence[str] = METHODS, *,
                     predict_mileage_km: float | None = None,
                     predict_wear_mm: ArrayLike | None = None, seed: int = 0,
                     max_runs: int = 5, rtol: float = 1e-4) -> pd.DataFrame:
    """Seed 000 Table 2 for our methods (the table of :func:`compare_methods`)."""
    return compare_methods(problem, methods, predict_mileage_km=predict_mileage_km,
                           predict_wear_mm=predict_wear_mm, seed=seed, max_runs=max_runs,
                           rtol=rtol)[0]
