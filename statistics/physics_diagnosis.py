"""Diagnosis of the PHYSICS wear model: what the whole-vehicle loop gets wrong, and why.

The model: :func:`wearcast.physics.vehicle_wear_simulation.simulate_vehicle_wear` with one
fitted wear-coefficient scale c. Scaling every wear rate by c is a change of the mileage
variable of the loop's autonomous evolution (profile -> contact -> rate): the series of a
scale-c run at mileage m equals the scale-1 run at c m, exactly up to the step discretisation.
So c is fitted without new runs: predicted(m; c) = series_1(c m).

Each physical cause (:data:`CATALOGUE`) is an extension of the loop with ONE physical
parameter theta (the wear scale c is refitted with it), run at a few values of theta; the
prediction between them is linear in theta (categorical causes: each level). Scoring, as the
hybrid finder's (``statistics.discrepancy``): folds grouped by vehicle (leave one vehicle out
when there are fewer than 5 vehicles), the null (c only) and each extension fitted on the
training vehicles, squared errors of the scored series (:data:`SERIES`: FT, FH and qR, each
where measured) [mm^2] on the held-out vehicle; the per-group
difference null - extension is tested one-sided (t-test over vehicles, over points when
there are fewer than 5 vehicles; Holm across the catalogue); the relative gain 1 - after /
before with a 95 % percentile bootstrap over the same groups. Verdict: among causes with
Holm p < alpha, relative gain >= ``min_relative_gain`` and a bootstrap interval above 0, the
one with the largest gain; else ``none``. Same response contract as the hybrid diagnosis:
``verdict``, ``findings`` (cause, summary, evidence, extension, gain with interval,
significant, material), ``skipped``.

Pure: the caller supplies ``simulate(params) -> simulation`` (any object with ``mileage_km``
and ``mean(quantity)``), so tests and the service choose vehicle, route and law.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray
from scipy import optimize, stats

from wearcast.statistics.finder_scoring import group_sums, sign_flip_p
from wearcast.statistics.findings import FinderResult, Finding, Gain, bootstrap_gain_interval
from wearcast.statistics.physics_causes import (
    CATALOGUE,
    CURVE_CLASSES_PARAMETER,
    NO_SEGMENTS,
    PhysicsCause,
)
from wearcast.statistics.physics_comparison import QUANTITIES

DEFAULT_ALPHA = 0.05
DEFAULT_MIN_RELATIVE_GAIN = 0.05
#: Scored series, measured column -> simulation quantity: FT (Sd), FH (Sh) and qR, the one list
#: of ``statistics.physics_comparison`` (a point missing a quantity is scored on the others).
SERIES = QUANTITIES
#: The diagnosis's tests in words (the answer's ``null_test``).
NULL_TEST = ("held-out FT/FH/qR error, one-sided test over the held-out groups with Holm's "
             "correction; the margin over every other cause with a gain by a one-sided "
             "sign-flip test over the same groups")
#: Name of the diagnosis's error metric (``findings.Gain.metric``).
METRIC = "ft_fh_qr_squared_error_mm2"
#: How far beyond its end a series is extrapolated (linearly from its last step) [-].
EXTRAPOLATION = 1.25
#: Bounds of the fitted wear-coefficient scale c [-].
SCALE_BOUNDS = (0.05, 20.0)
#: Points of the log grid the scale search starts from (``_fit``).
SCALE_GRID_POINTS = 121
#: The largest wear-coefficient scale a diagnosis's loop runs are made for [-]
#: (:func:`diagnosis_mileage_km`): every scale up to it is fitted on simulated, not
#: extrapolated, mileage. The search reads a run only up to c x the furthest mileage, so a
#: longer run (with the same steps up to there: ``simulate_vehicle_wear``'s
#: ``cut_last_step=False``) changes no fit whose scale is below this; a cause whose values
#: need a larger scale (a run that wears far more slowly than the measured wheels) is fitted
#: at the largest scale its run reaches, as with any run length, and the diagnosis says so
#: when that fit is the chosen one (``PhysicsDiagnosis.at_reach``). 1.5: the fitted scales of
#: the Aosta diagnosis (seed 003 Table 2), null and every extension on all data, lie between
#: 0.75 and 1.38, and its runs to 1.5 x 3,537 km give the answer of runs to 8,000 km bit for
#: bit (``benchmarks/diagnose_aosta_physics.py``).
DIAGNOSIS_SCALE_MAX = 1.5
#: A fit is at its run's reach when its scale is at least this share of it (``ScaleFit``).
AT_REACH_SHARE = 0.97


@dataclass(frozen=True)
class PhysicsDiagnosis(FinderResult):
    """verdict (a cause, ``none`` or ``ambiguous``), findings ranked by gain, skipped causes
    with reasons, the null model's fit on all data; the runner-up, the margin over it and its
    p-value, and the ``candidates`` of an ambiguous verdict (see ``_verdict``); ``at_reach``:
    the fits a longer run could move (:data:`DIAGNOSIS_SCALE_MAX`; a chosen fit on all data or
    a fold at the largest scale its runs reach).

    The attribute docstrings are the descriptions of the diagnosis answer's fields, which the
    hybrid diagnosis (``discrepancy.Diagnosis``) answers too
    (``service.diagnosis_schemas.DiagnosisOut``)."""

    null_fit: dict[str, Any]
    """physics models: the null model's own fit — wear_scale (the fitted wear-coefficient
    scale), rms_mm, the measured series it was fitted on and rms_mm_by_series (each series'
    RMS error, mm; a finding's extension carries its own on all data); null for hybrid
    models"""
    runner_up: str | None = None
    margin: float | None = None
    margin_p_value: float | None = None
    candidates: tuple[str, ...] = ()
    at_reach: tuple[str, ...] = ()
    """physics models: the null ('null') and the causes with a fit at the largest wear
    scale their loop runs reach (a longer run could move it); empty for hybrid models"""

    def to_dict(self) -> dict[str, Any]:
        return {**super().to_dict(), "null_fit": self.null_fit, "runner_up": self.runner_up,
                "margin": self.margin, "margin_p_value": self.margin_p_value,
                "candidates": list(self.candidates), "at_reach": list(self.at_reach)}


class _Series:
    """The loop's vehicle-mean series of one parameter set, as functions of mileage (the
    measured columns ``cols`` of :data:`SERIES`)."""

    def __init__(self, sim: Any, cols: Sequence[str], run_scale: float = 1.0):
        # a run made at wear scale s reaches at m the state a scale-1 run reaches at s m
        self.km = np.asarray(sim.mileage_km, dtype=float) * run_scale
        self.values = {col: np.asarray(sim.mean(SERIES[col]), dtype=float) for col in cols}

    def at(self, col: str, km: NDArray, strict: bool = True) -> NDArray:
        """Values at mileages; beyond the simulated end, linear from the last step, up to
        ``EXTRAPOLATION`` x the simulated mileage when ``strict`` (fits), without limit
        otherwise (a held-out vehicle's prediction with the training fit's scale)."""
        end = self.km[-1]
        if strict and np.any(km > EXTRAPOLATION * end):
            raise _OutOfRange(float(km.max()), float(end))
        v = self.values[col]
        slope = (v[-1] - v[-2]) / (self.km[-1] - self.km[-2]) if self.km.size > 1 else 0.0
        return np.where(km <= end, np.interp(km, self.km, v), v[-1] + slope * (km - end))


class _OutOfRange(ValueError):
    def __init__(self, wanted: float, have: float):
        super().__init__(f"needs the series to {wanted:.0f} km, simulated {have:.0f} km")


def _predict(series: list[_Series], weights: NDArray, scale: float, km: NDArray,
             cols: Sequence[str], strict: bool = True) -> NDArray:
    """(n_points, n_cols) prediction of a blend of series at scale c."""
    out = np.zeros((km.size, len(cols)))
    for s, w in zip(series, weights, strict=True):
        if w == 0:
            continue
        out += w * np.stack([s.at(c, scale * km, strict) for c in cols], axis=1)
    return out


def _blends(cause: PhysicsCause | None, runs: Mapping[Any, _Series]
            ) -> list[tuple[Any, list[_Series], NDArray]]:
    """Candidate (theta, series, weights): each level, and for numeric causes a fine grid of
    linear blends between adjacent values."""
    if cause is None:
        return [(None, [runs[None]], np.ones(1))]
    vals = list(cause.values)
    if cause.categorical:
        return [(v, [runs[v]], np.ones(1)) for v in vals]
    vals = sorted(vals)
    out = []
    for lo, hi in zip(vals[:-1], vals[1:], strict=True):
        for t in np.linspace(0.0, 1.0, 6)[:-1]:
            out.append((lo + t * (hi - lo), [runs[lo], runs[hi]], np.array([1 - t, t])))
    out.append((vals[-1], [runs[vals[-1]]], np.ones(1)))
    return out


def diagnosis_mileage_km(measured: pd.DataFrame,
                         scale_max: float = DIAGNOSIS_SCALE_MAX) -> float:
    """The mileage a diagnosis's loop runs need [km]: the largest the scale search reads for
    scales up to ``scale_max`` (a fit at scale c reads the series at c x each training point's
    mileage, a held-out prediction at c x the test vehicle's), i.e. ``scale_max`` x the
    furthest measured mileage. A run to it is read only within its simulated mileage at
    every scale up to ``scale_max``; the strict search extrapolates up to
    ``EXTRAPOLATION`` x ``scale_max`` beyond (:func:`fit_wear_scale`'s ``reach``)."""
    if not scale_max > 0:
        raise ValueError(f"scale_max: must be positive, got {scale_max}")
    if "distance_km" not in measured:
        raise ValueError("measured needs distance_km")
    far = float(pd.to_numeric(measured["distance_km"]).max())
    if not far > 0:
        raise ValueError("measured needs a mileage beyond 0 km")
    return scale_max * far


def _reach(series: Sequence[_Series], km: NDArray) -> float:
    """The largest scale the strict search can evaluate ``series`` at for mileages ``km``."""
    far = float(np.max(km)) if km.size else 0.0
    end = min(float(s.km[-1]) for s in series)
    return EXTRAPOLATION * end / far if far > 0 else SCALE_BOUNDS[1]


def _at_reach(scale: float, sse: float, series: Sequence[_Series], km: NDArray) -> bool:
    """Whether a fit (``scale``, ``sse``) of ``series`` on mileages ``km`` ended at the
    largest scale the runs reach (or found no scale at all): a longer run could move it."""
    return bool(sse >= 1e12 or scale >= AT_REACH_SHARE * _reach(series, km))


def _fit(candidates: list[tuple[Any, list[_Series], NDArray]], km: NDArray, y: NDArray,
         cols: Sequence[str]) -> tuple[Any, float, float]:
    """Best (theta, scale, sse) on the training points.

    The scale is searched on a log grid over SCALE_BOUNDS first, then refined by a bounded 1-D
    search between the grid points around the best one: the error is not unimodal in the scale
    (a scale beyond the simulated mileage is out of range, a flat cliff, and a series with a
    running-in has local minima), and a bounded search over the whole range alone can end at a
    bound."""
    best = (None, 1.0, np.inf)
    grid = np.linspace(np.log(SCALE_BOUNDS[0]), np.log(SCALE_BOUNDS[1]), SCALE_GRID_POINTS)
    for theta, series, w in candidates:
        def sse(log_c: float, series=series, w=w) -> float:
            try:
                pred = _predict(series, w, float(np.exp(log_c)), km, cols)
            except _OutOfRange:
                return 1e12
            return float(np.nansum((pred - y) ** 2))
        coarse = np.array([sse(g) for g in grid])
        k = int(np.argmin(coarse))
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
        res = optimize.minimize_scalar(sse, bounds=(lo, hi), method="bounded",
                                       options={"xatol": 1e-4})
        x, f = (float(res.x), float(res.fun)) if res.fun <= coarse[k] else (grid[k], coarse[k])
        if f < best[2]:
            best = (theta, float(np.exp(x)), f)
    return best


@dataclass(frozen=True)
class ScaleFit:
    """The wear-coefficient scale c of one run fitted to measured series (the null model's
    fit of :func:`diagnose_physics`): c, the sum of squared errors [mm^2] and RMS error [mm]
    over the fitted points, their number, and ``reach``: the largest c the run can be
    evaluated at for the furthest measured mileage (``EXTRAPOLATION`` x its end / that
    mileage); ``at_reach`` when the fit ended there (the optimum may lie beyond: simulate
    further)."""

    wear_scale: float
    sse_mm2: float
    rms_mm: float
    n_points: int
    reach: float
    at_reach: bool


def _measured_points(measured: pd.DataFrame) -> tuple[list[str], pd.DataFrame]:
    """The scored columns (of :data:`SERIES`, those measured at all) and the points with at
    least one of them (a missing value is left out of the squared error, not filled)."""
    cols = [c for c in SERIES if c in measured and measured[c].notna().any()]
    if not cols or "vehicle" not in measured or "distance_km" not in measured:
        raise ValueError(f"measured needs vehicle, distance_km and any of {', '.join(SERIES)}")
    return cols, measured.dropna(subset=cols, how="all").reset_index(drop=True)


def fit_wear_scale(simulation: Any, measured: pd.DataFrame) -> ScaleFit:
    """Least-squares wear-coefficient scale of one run against measured FT/FH/qR series
    (``measured`` as :func:`diagnose_physics` reads it): the search of the diagnosis's null
    model (log grid over SCALE_BOUNDS, then a bounded refinement)."""
    cols, data = _measured_points(measured)
    if data.empty:
        raise ValueError(f"measured has no point with any of {', '.join(cols)}")
    km = data["distance_km"].to_numpy(float)
    y = data[cols].to_numpy(float)
    n = int(np.isfinite(y).sum())
    series = _Series(simulation, cols)
    _, scale, sse = _fit(_blends(None, {None: series}), km, y, cols)
    reach = _reach([series], km)
    at_reach = bool(sse >= 1e12 or (float(km.max()) > 0 and _at_reach(scale, sse, [series], km)))
    return ScaleFit(float(scale), float(sse), float(np.sqrt(sse / n)), n,
                    float(min(reach, SCALE_BOUNDS[1])), at_reach)


def _holm(pvalues: Sequence[float]) -> NDArray:
    p = np.asarray(pvalues, dtype=float)
    order = np.argsort(p)
    adj = np.empty_like(p)
    running = 0.0
    for rank, i in enumerate(order):
        running = max(running, (len(p) - rank) * float(p[i]))
        adj[i] = min(1.0, running)
    return adj


#: How a diagnosis makes its loop runs: (simulate, [parameter sets]) -> [simulation or the
#: exception its run raised], in the order given.
RunAll = Callable[[Callable[[Mapping[str, Any]], Any], Sequence[Mapping[str, Any]]],
                  list[Any]]


def catalogue_runs(catalogue: Sequence[PhysicsCause]) -> list[dict[str, Any]]:
    """The loop runs a diagnosis of ``catalogue`` needs, each once: the null ({}) first, then
    every cause's values other than its null ({parameter: value})."""
    out: list[dict[str, Any]] = [{}]
    seen = {_run_key({})}
    for cause in catalogue:
        for v in cause.values:
            params = cause.run_params(v)
            key = _run_key(params)
            if v != cause.null and key not in seen:
                seen.add(key)
                out.append(params)
    return out


def _run_key(params: Mapping[str, Any]) -> tuple[tuple[str, str], ...]:
    return tuple(sorted((k, repr(v)) for k, v in params.items()))


def run_sequentially(simulate: Callable[[Mapping[str, Any]], Any],
                     sets: Sequence[Mapping[str, Any]]) -> list[Any]:
    """Each parameter set's run in turn; a run that raises gives its exception (a cause's
    leaves the cause skipped), except the first (the null's), which is raised at once."""
    out: list[Any] = []
    for params in sets:
        try:
            out.append(simulate(params))
        except Exception as exc:
            if not out:
                raise
            out.append(exc)
    return out


def diagnose_physics(simulate: Callable[[Mapping[str, Any]], Any], measured: pd.DataFrame, *,
                     catalogue: Sequence[PhysicsCause] = CATALOGUE,
                     alpha: float = DEFAULT_ALPHA,
                     min_relative_gain: float = DEFAULT_MIN_RELATIVE_GAIN,
                     n_bootstrap: int = 2000, seed: int = 0,
                     skipped: Mapping[str, str] | None = None,
                     run_all: RunAll | None = None) -> PhysicsDiagnosis:
    """Diagnose the physics model against measured vehicle-averaged series.

    simulate : {parameter: value} -> simulation (``mileage_km``, ``mean(q)`` for the
        quantities q of :data:`SERIES`: ``sd_mm``, ``sh_mm``, ``qr_mm``);
        called once per parameter set with only the cause's parameter set (empty = null); it
        must simulate far enough for the fitted scales: :func:`diagnosis_mileage_km` (scales
        up to :data:`DIAGNOSIS_SCALE_MAX` on simulated mileage; SCALE_BOUNDS x the largest
        mileage is not required: a scale that needs more is simply not reachable, and a fit
        that ends at its runs' reach is listed in ``at_reach``)
    measured : columns ``vehicle``, ``distance_km`` and any of ``FT_mm``, ``FH_mm``,
        ``QR_mm`` (each scored where measured)
    skipped : {cause: reason} of causes left out of ``catalogue`` because the model lacks
        what they need (reported as such); default: the curve-classes cause, when the
        catalogue has none, with :data:`NO_SEGMENTS`
    run_all : how the loop runs are made: (simulate, [parameter sets]) -> [simulation or the
        exception it raised], in order (:func:`run_sequentially` by default; a caller may run
        them in parallel, :func:`catalogue_runs` lists them). Every run is independent of the
        others and of the measurements, so the order and the workers change nothing.
    """
    cols, data = _measured_points(measured)
    km = data["distance_km"].to_numpy(float)
    y = data[cols].to_numpy(float)
    vehicles = data["vehicle"].astype(str).to_numpy()
    groups = np.unique(vehicles)
    if groups.size < 2:
        raise ValueError("the physics diagnosis needs measurements of at least 2 vehicles")
    group_by = "vehicle" if groups.size >= 5 else "point"
    if skipped is None:
        has = any(c.parameter == CURVE_CLASSES_PARAMETER for c in catalogue)
        skipped = {} if has else {"curve_classes": NO_SEGMENTS}
    skipped = dict(skipped)
    runs: dict[Any, dict[Any, _Series]] = {}
    sets = catalogue_runs(catalogue)
    done = (run_all or run_sequentially)(simulate, sets)
    if isinstance(done[0], BaseException):
        raise done[0]  # the model itself does not run: nothing to diagnose
    by_params = {_run_key(p): r for p, r in zip(sets, done, strict=True)}
    null_runs = {None: _Series(done[0], cols)}
    at_reach: list[str] = []

    def fit(cause: PhysicsCause | None, cands: list[tuple[Any, list[_Series], NDArray]],
            at: NDArray) -> tuple[Any, float, float, tuple[Any, list[_Series], NDArray]]:
        """``_fit`` on the points ``at``, plus the chosen candidate; notes the fit in
        ``at_reach`` when it ended at its runs' reach."""
        theta, scale, sse = _fit(cands, km[at], y[at], cols)
        chosen = next(c for c in cands if c[0] == theta)
        name = "null" if cause is None else cause.name
        weighted = [r for r, w in zip(chosen[1], chosen[2], strict=True) if w != 0]
        if name not in at_reach and _at_reach(scale, sse, weighted, km[at]):
            at_reach.append(name)
        return theta, scale, sse, chosen

    def held_out(cause: PhysicsCause | None, cause_runs: Mapping[Any, _Series]) -> NDArray:
        cands = _blends(cause, cause_runs)
        err = np.zeros(km.size)
        for g in groups:
            test = vehicles == g
            _, scale, _, chosen = fit(cause, cands, ~test)
            pred = _predict(chosen[1], chosen[2], scale, km[test], cols, strict=False)
            err[test] = np.nansum((pred - y[test]) ** 2, axis=1)
        return err

    before = held_out(None, null_runs)
    every = np.ones(km.size, dtype=bool)
    def rms_by_series(chosen: tuple[Any, list[_Series], NDArray], scale: float
                      ) -> dict[str, float]:
        """RMS error [mm] of each scored series of a fit on all points."""
        pred = _predict(chosen[1], chosen[2], scale, km, cols, strict=False)
        return {c: float(np.sqrt(np.nanmean((pred[:, j] - y[:, j]) ** 2)))
                for j, c in enumerate(cols)}

    theta0, scale0, sse0, chosen0 = fit(None, _blends(None, null_runs), every)
    null_fit = {"wear_scale": scale0,
                "rms_mm": float(np.sqrt(sse0 / np.isfinite(y).sum())), "series": cols,
                "rms_mm_by_series": rms_by_series(chosen0, scale0)}
    rows = []
    for cause in catalogue:
        made = {v: by_params[_run_key(cause.run_params(v))] for v in cause.values
                if v != cause.null}
        failed = [r for r in made.values() if isinstance(r, BaseException)]
        if failed:  # a run that fails leaves the cause unscored, saying why
            skipped[cause.name] = f"the loop failed for this extension: {failed[0]}"
            continue
        cause_runs = {v: (null_runs[None] if v == cause.null else
                          _Series(made[v], cols, cause.run_scale(v)))
                      for v in cause.values}
        runs[cause.name] = cause_runs
        after = held_out(cause, cause_runs)
        rows.append((cause, after))
    rng = np.random.default_rng(seed)
    unit = vehicles if group_by == "vehicle" else np.arange(km.size).astype(str)
    units = np.unique(unit)
    pvals: list[float] = []
    findings: list[tuple[PhysicsCause, Gain, dict[str, Any], float]] = []
    for cause, after in rows:
        d_units = np.array([np.sum(before[unit == u] - after[unit == u]) for u in units])
        b_units = np.array([np.sum(before[unit == u]) for u in units])
        a_units = np.array([np.sum(after[unit == u]) for u in units])
        if np.allclose(d_units, 0):
            p = 1.0
        else:
            p = float(stats.ttest_1samp(d_units, 0.0, alternative="greater").pvalue)
        pvals.append(p if np.isfinite(p) else 1.0)
        lo, hi = bootstrap_gain_interval(b_units, a_units, n_bootstrap, rng)
        rel = 1.0 - after.sum() / before.sum() if before.sum() > 0 else 0.0
        theta, scale, sse, chosen = fit(cause, _blends(cause, runs[cause.name]), every)
        findings.append((cause, Gain(float(before.mean()), float(after.mean()), float(rel), lo,
                                     hi, metric=METRIC),
                         {"parameter": cause.parameter, "value": theta, "wear_scale": scale,
                          "null_value": cause.null,
                          "rms_mm_by_series": rms_by_series(chosen, scale)}, p))
    adj = _holm(pvals) if pvals else np.array([])
    out = []
    for (cause, gain, ext, p), p_holm in zip(findings, adj, strict=True):
        significant = bool(p_holm < alpha and gain.ci95_low > 0)
        material = bool(gain.relative >= min_relative_gain)
        out.append(Finding(
            cause.name, cause.summary,
            {"p_value": p, "p_holm": float(p_holm), "test_groups": group_by,
             "values_run": [v for v in cause.values]},
            ext, gain, significant, material))
    out.sort(key=lambda f: -f.gain.relative)
    after_of = {cause.name: after for cause, after in rows}
    verdict, runner_up, margin, margin_p, candidates = _verdict(out, after_of, unit, alpha, rng)
    return PhysicsDiagnosis(verdict, tuple(out), skipped, int(km.size), int(groups.size),
                            group_by, null_fit, runner_up=runner_up, margin=margin,
                            margin_p_value=margin_p, candidates=candidates,
                            at_reach=tuple(at_reach))


def _verdict(ranked: Sequence[Finding], after_of: Mapping[str, NDArray], unit: NDArray,
             alpha: float, rng: np.random.Generator
             ) -> tuple[str, str | None, float | None, float | None, tuple[str, ...]]:
    """(verdict, runner_up, margin, margin_p_value, candidates) from the findings ranked by
    gain.

    The best significant and material cause is named only if it also beats every other
    cause that explains anything (a positive held-out gain, significant or not) by a tested
    margin: the held-out error of the other minus the best's, summed per test unit (vehicle,
    or point below 5 vehicles), one-sided sign-flip randomisation p < ``alpha``
    (``finder_scoring.sign_flip_p``, as the hybrid finder's margin test); a cause with no
    gain is worse than the null the best significantly beats. Otherwise the verdict is
    ``ambiguous`` and ``candidates`` lists the best and the causes it could not be separated
    from (causes the measured series cannot tell apart, e.g. flange lubrication and traction
    on the motor axles, which both ease the motor wheels' flanges). ``runner_up`` is the
    other cause with the largest gain, ``margin`` the difference of their relative gains
    (negative when a cause that is not significant gains more).
    """
    chosen = [f for f in ranked if f.significant and f.material]
    if not chosen:
        return "none", None, None, None, ()
    best = chosen[0]
    others = [f for f in ranked if f.cause != best.cause]
    runner = others[0] if others else None
    p_of = {f.cause: sign_flip_p(group_sums(after_of[f.cause] - after_of[best.cause], unit),
                                 4000, rng)
            for f in others if f.gain.relative > 0}
    unseparated = tuple(c for c, p in p_of.items() if p >= alpha)
    margin = None if runner is None else float(best.gain.relative - runner.gain.relative)
    margin_p = None if runner is None else p_of.get(runner.cause)
    if unseparated:
        return "ambiguous", runner.cause if runner else None, margin, margin_p, (
            best.cause, *unseparated)
    return best.cause, runner.cause if runner else None, margin, margin_p, ()
