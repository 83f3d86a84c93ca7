"""The discrepancy finder: what the calibrated model gets wrong, the cause, the gain.

``diagnose`` fits every extension of the catalogue (:mod:`wearcast.statistics.causes`),
scores it out of sample and names a cause only when it is specific:

1. residuals of the calibrated model per measurement and region (log-area residuals) and of
   the wear-curve shape (:mod:`wearcast.statistics.residuals`); every row weighted by its
   Huber weight times its region's precision (``cause_base.FinderData.set_robust_weights``:
   a noisy region does not drown the other in the fits, scores and resamples);
2. K-fold cross-validation with folds grouped by vehicle (by wheel when fewer than 5
   vehicles), never by row: each extension and the baseline (the model with its per-region
   scale refitted) are fitted on K-1 folds and their squared working residuals computed on
   the held-out fold; the relative gain is 1 - after / before, with a 95 % interval from a
   bootstrap over the groups. Causes whose contrast lies within the wheels (the calendar
   season) or within the cars (traction: a car's motor against its trailer bogie) take their
   parameters from a random-effects GLS fit (random log-scales per vehicle and per wheel
   within it, ``finder_random_effects``), so the wheels' and cars' own scatter neither
   drowns nor fakes them; the region scales are refitted by least squares, and the
   resampled datasets are fitted by the same estimator;
3. the nuisance model: the baseline's per-vehicle and per-wheel log-scale effects and its
   per-measurement residuals (``finder_scoring.NuisanceModel``). Datasets resampled from it
   (wild cluster bootstrap: every effect and residual kept at its rows with a random sign,
   so heteroscedastic noise keeps its place) carry the baseline's nuisance variation and no
   effect; every cause is fitted and scored on them exactly as on the data. A cause whose
   contrast lies within the vehicles (traction, ``Cause.within_vehicle``) is tested on the
   held-out error after a random log-scale per vehicle (``finder_scoring.SCORE_METRIC``,
   ``finder_random_effects.vehicle_demean``: the vehicles' own rate factors, which no cause
   explains, no longer make most of the error it is scored on), its margin over the
   runner-up too; the reported gains and their materiality are in the rows' own metric. A
   cause's p-value is the share of resampled gains at least as large as its observed gain,
   adjusted across the catalogue by the Westfall-Young max-T method (gains standardised by
   their own null distribution) on the same resamples (no asymptotic test, no assumed noise
   distribution). The nuisance is taken from the residuals of the baseline plus the leading
   candidate (so a real effect is not resampled as nuisance), widened for the degrees of
   freedom that fit used; the wear-curve shape cause is tested the same way on its
   coefficients, in the metric of their wheel-to-wheel nuisance covariance
   (``finder_shape_test.noise_whitened``; its gain is reported in curve space), every
   measurement weighted by
   the inverse of the shape nuisance's variance at its predicted worn area and, in the
   between-wheel test, its wheel position (``finder_shape_weights``: the late, worn rows
   and the always-leading wheels' scattered shapes no longer drown a signature that is the
   same at every mileage and position), each wheel life's growth with the wear removed
   (``finder_shape_growth``); where wheel lives measured by several instruments exist, the
   signature must also stand out inside them (``finder_shape_test.within_life_p``, nuisance
   resampled by measurement session), the larger of the two adjusted p-values counting
   (intersection-union test, Berger 1982);
4. specificity: the cause with the largest significant (adjusted p < alpha) and material
   (relative gain >= ``min_relative_gain``) gain must beat the
   runner-up (the next best cause) by a margin that is itself tested: a parametric
   bootstrap under "the runner-up is the cause" (datasets carrying the runner-up's fitted
   effect and nuisance resampled from the fit carrying both causes, both causes scored on
   them as on the data;
   ``finder_scoring.margin_p``) and a sign-flip randomisation over the groups, combined by
   Bonferroni (``finder_scoring.MarginTest``); a cause whose contrast lies within the
   vehicles (traction), its margin scored in the vehicle metric, by the bootstrap alone
   (``finder_scoring.WITHIN_VEHICLE_MARGIN``: the sign-flip's strength, a between-vehicle
   effect the bootstrap keeps as nuisance, is out of that metric, and only the motor cars
   carry the contrast it flips). Only the other causes that are themselves significant and
   material at the step, or gain at least as much as the verdict, are rivals
   (``finder_scoring.MARGIN_RIVALS``): the runner-up by gain is reported with its margin
   either way, but a weaker one the finder would not name on its own does not make the
   verdict ambiguous. If the verdict does not beat its leading rival, it
   is ``ambiguous`` and lists the candidates;
5. several causes at once: forward selection; after a cause is named it joins the baseline
   and the remaining causes are scored, resampled and tested again against it, each
   reported with its own gain;
   When the wear-curve (instrument) cause is named alongside area causes, the verdict is
   the named cause with the largest gain, except that an area cause whose held-out gain
   over the named instrument's per-instrument area scales is not material is dropped as
   that instrument's echo (``finder_instrument``; the two gains are in different metrics);
6. outside the catalogue: when no cause is named but the residuals are structured by wheel
   position, route, calendar quarter, mileage or instrument (tested against the same
   resamples), the verdict is ``outside_catalogue`` and the structure is reported with its
   size instead of ``none`` (``finder_structure``);
7. with ``expected_progression`` (``discrepancy_progression``) the baseline grows as a
   simulation of the route says instead of linearly in mileage, so every cause is a
   departure from the simulated progression;
8. effect sizes (multipliers, exponents, shares) with 95 % intervals from the
   vehicle-clustered (sandwich) covariance of the fit, Student t with groups - 1 degrees of
   freedom.

The finder's data are :mod:`wearcast.statistics.discrepancy_data`, its findings
:mod:`wearcast.statistics.discrepancy_findings`.

Pure: no I/O. The figures and the HTML report are in
:mod:`wearcast.statistics.discrepancy_report`; the gain and finding types in
:mod:`wearcast.statistics.findings`.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics import causes as cz
from wearcast.statistics import finder_instrument as fi
from wearcast.statistics import finder_random_effects as fre
from wearcast.statistics import finder_scoring as fs
from wearcast.statistics import finder_shape_position as fsp
from wearcast.statistics import finder_shape_test as fst
from wearcast.statistics import finder_shape_weights as fsw
from wearcast.statistics.discrepancy_data import build_data
from wearcast.statistics.discrepancy_findings import (
    Scored,
    covariate_codes,
    is_named,
    scored_findings,
)
from wearcast.statistics.discrepancy_progression import ExpectedProgression
from wearcast.statistics.finder_structure import structure_scan
from wearcast.statistics.findings import FinderResult, Finding
from wearcast.statistics.hybrid import HybridModel
from wearcast.statistics.json_values import json_value
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import WearTable, compile_wear_table

DEFAULT_ALPHA = 0.04
DEFAULT_STRUCTURE_ALPHA = 0.01
DEFAULT_MIN_RELATIVE_GAIN = 0.01
DEFAULT_N_NULL = 199
MAX_CAUSES = 3



@dataclass(frozen=True)
class Diagnosis(FinderResult):
    """Result of ``diagnose``.

    verdict : a cause code, ``none``, ``ambiguous`` (candidates listed) or
        ``outside_catalogue`` (structure in ``unexplained``)
    margin_p_value : the margin's randomisation p-value
    candidates : (``ambiguous``) the best cause and the rivals (other causes significant and
        material themselves) its margin does not beat
    nuisance : the baseline's per-vehicle, per-wheel and per-measurement standard deviations
    null_test : the test of the null, in words

    The attribute docstrings are the descriptions of the diagnosis answer's fields
    (``service.diagnosis_schemas.DiagnosisOut``); ``residuals``, ``covariates`` and
    ``predictions`` (kept out of repr and equality) are the report's working data.
    """

    residuals: pd.DataFrame = field(repr=False, compare=False)
    covariates: dict[str, list[Any]] = field(default_factory=dict, repr=False, compare=False)
    predictions: dict[str, list[list[float]]] = field(default_factory=dict, repr=False,
                                                      compare=False)
    selected: tuple[str, ...] = ()
    """causes named by forward selection, the verdict first"""
    runner_up: str | None = None
    """the best other cause"""
    margin: float | None = None
    """the verdict's held-out gain over the runner-up, relative to the baseline's error"""
    margin_p_value: float | None = None
    candidates: tuple[str, ...] = ()
    """verdict 'ambiguous': the causes no tested margin separates"""
    unexplained: tuple[dict[str, Any], ...] = ()
    """verdict 'outside_catalogue': residual structure by wheel position, route, date,
    mileage or instrument, with its size"""
    nuisance: dict[str, Any] = field(default_factory=dict)
    null_test: str = ""

    @property
    def reported(self) -> tuple[Finding, ...]:
        """Findings of the causes named by forward selection (the verdict first)."""
        return tuple(f for c in self.selected for f in self.findings if f.cause == c)

    def to_dict(self) -> dict[str, Any]:
        return {**super().to_dict(),
                "selected": list(self.selected), "runner_up": self.runner_up,
                "margin": json_value(self.margin),
                "margin_p_value": json_value(self.margin_p_value),
                "candidates": list(self.candidates),
                "unexplained": [json_value(u) for u in self.unexplained],
                "nuisance": json_value(self.nuisance), "null_test": self.null_test}


def _folds(groups: NDArray[Any], k: int, seed: int) -> NDArray[np.int64]:
    uniq = np.unique(groups)
    rng = np.random.default_rng(seed)
    perm = rng.permutation(uniq.size)
    fold_of = {g: int(perm[i] % k) for i, g in enumerate(uniq)}
    return np.array([fold_of[g] for g in groups], dtype=np.int64)


def diagnose(
    model: HybridModel,
    measurements_df: pd.DataFrame,
    wear_curves: Any,
    routes_by_name: Mapping[str, Route],
    table: pd.DataFrame | WearTable,
    *,
    calibration_wheel_ids: Collection[Any] = (),
    route_attributes: Mapping[str, Mapping[str, Any]] | None = None,
    expected_progression: ExpectedProgression | None = None,
    causes: Sequence[str] | None = None,
    alpha: float = DEFAULT_ALPHA,
    min_relative_gain: float = DEFAULT_MIN_RELATIVE_GAIN,
    n_folds: int = 5,
    n_boot: int = 1000,
    n_null: int = DEFAULT_N_NULL,
    structure_alpha: float = DEFAULT_STRUCTURE_ALPHA,
    max_causes: int = MAX_CAUSES,
    seed: int = 0,
) -> Diagnosis:
    """Find what the calibrated model gets wrong, name the cause and measure the gain.

    Parameters
    ----------
    model : calibrated hybrid model (seed 001)
    measurements_df : one row per measurement (``residuals.model_residuals`` lists the
        columns): the wheels not used in calibration and, ideally, the calibration wheels too
        (flagged via ``calibration_wheel_ids``; every extension refits its scale, so they
        inform the extension without favouring it). Optional ``reprofiled_on`` dates help the
        season; a wheel whose mileage falls between dated measurements was reprofiled.
    wear_curves : (n, g) measured wear curves [mm] on the model's grid, or None (then
        ``profile_misalignment`` is skipped)
    routes_by_name : Route per route name used in the ``route``/``route_id`` column
    table : curve-radius table (both measures for ``wear_measure``)
    route_attributes : attributes per route name (``flange_lubrication``, ...)
    expected_progression : the progression shape a simulation of the routes expects
        (``discrepancy_progression.ExpectedProgression``); the baseline and every cause then
        carry it, so wear that is as nonlinear as the physics says is not a discrepancy.
        None: the hybrid model's linear growth
    causes : cause codes to try (default: the whole catalogue)
    alpha : family-wise error rate of naming a cause (max-T over the catalogue) and level of
        the margin test
    min_relative_gain : smallest relative reduction of the held-out error that counts
    n_folds, n_boot, n_null, seed : folds, bootstrap resamples of the gain interval,
        resampled null datasets, random seed
    structure_alpha : level of the outside-the-catalogue structure test
    max_causes : most causes forward selection names

    Returns
    -------
    Diagnosis (module docstring for the procedure).
    """
    wt = compile_wear_table(table)
    data = build_data(model, measurements_df, wear_curves, routes_by_name, wt,
                      calibration_wheel_ids=calibration_wheel_ids,
                      route_attributes=route_attributes,
                      expected_progression=expected_progression)
    frame = data.frame
    vehicle = frame["vehicle_id"].astype(str).to_numpy()
    wheel = frame["wheel_id"].astype(str).to_numpy()
    group_by = "vehicle_id" if np.unique(vehicle).size >= 5 else "wheel_id"
    groups = vehicle if group_by == "vehicle_id" else wheel
    k = int(min(n_folds, np.unique(groups).size))
    if k < 2:
        raise ValueError("measurements: need at least two wheels to score out of sample")
    folds = _folds(groups, k, seed)
    everything = np.ones(data.n, dtype=bool)
    null_fit = cz.NullArea().fit(data, everything)
    data.set_robust_weights(data.e - data.phi * null_fit.log_scale_[None, :])
    sw = np.sqrt(data.weights)

    def loss(residual: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(np.sum(data.weights * residual ** 2, axis=1))

    score_transform: Any = {"gls": lambda v: fre.quasi_demean(data, v),
                            "gls_vehicle": lambda v: fre.vehicle_demean(data, v)
                            }.get(fs.SCORE_METRIC)

    def test_loss(residual: NDArray[np.float64]) -> NDArray[np.float64]:
        """Held-out error per row in the vehicle metric (``finder_scoring.SCORE_METRIC``)."""
        if score_transform is not None:
            z = score_transform((sw * residual).reshape(-1)).reshape(data.n, 2)
            return np.asarray(np.sum(z ** 2, axis=1))
        return loss(residual)

    chosen = cz.CATALOGUE if causes is None else tuple(cz.cause_by_code(c) for c in causes)
    rng = np.random.default_rng(seed + 1)
    skipped: dict[str, str] = {}
    area: list[cz.Cause] = []
    shape_cause: cz.Cause | None = None
    for cause in chosen:
        reason = cause.skip_reason(data)
        if reason is not None:
            skipped[cause.code] = reason
        elif cause.metric == "shape":
            shape_cause = cause
        else:
            area.append(cause)

    # the wear-curve shape cause: per-instrument mean signature vs one common signature.
    # The gain is reported in curve space; the test statistic is the same held-out gain in
    # the metric of the nuisance covariance (``finder_shape_test.noise_whitened``)
    shape_row: tuple[float, NDArray[np.float64]] | None = None
    shape_within: tuple[float, NDArray[np.float64]] | None = None
    scored: dict[str, Scored] = {}
    if shape_cause is not None:
        coef = fst.whitened_shape(data)
        inst = shape_cause.instruments(data)  # type: ignore[attr-defined]
        inst_codes = fs.codes_of(inst)
        z = fst.noise_whitened(coef, inst_codes, wheel)
        centred = fst.instrument_centred(z, inst_codes)
        # precision weights of the rows (``finder_shape_weights``): in the means, the
        # held-out errors and the resampled datasets alike
        w_shape = fsw.shape_weights(centred, data.base.sum(axis=1), fsp.row_positions(data))
        data.cache["shape_weights"] = w_shape
        before = w_shape * np.sum(fs.held_out_shape(coef, None, folds, w_shape) ** 2, axis=1)
        after = w_shape * np.sum(fs.held_out_shape(coef, inst, folds, w_shape) ** 2, axis=1)
        z_gain = fs.relative_gain(
            w_shape * np.sum(fs.held_out_shape(z, None, folds, w_shape) ** 2, axis=1),
            w_shape * np.sum(fs.held_out_shape(z, inst, folds, w_shape) ** 2, axis=1))
        sw_shape = np.sqrt(w_shape)[:, None] * np.ones_like(z)
        nm = fs.NuisanceModel.fit(sw_shape * centred, sw_shape, vehicle, wheel)
        draws = nm.draws(n_null, rng, used_dof=int(inst_codes.max()))
        sw_flat = sw_shape.reshape(-1)[:, None]
        boot = fs.bootstrap_gains(sw_flat * fst.shape_design(data.n, None),
                                  [sw_flat * fst.shape_design(data.n, inst)],
                                  draws, np.repeat(folds, 3))
        shape_row = (z_gain, boot[0])
        # its own random stream: the other causes' resampled datasets stay as they were
        shape_within = fst.within_life_p(data, coef, inst, wheel, folds, n_null,
                                        np.random.default_rng(seed + 2))
        scored[shape_cause.code] = Scored(shape_cause, before, after,
                                          fs.relative_gain(before, after), metric="shape")

    # forward selection over the area causes
    selected: list[cz.Cause] = []
    remaining = list(area)
    runner_up: str | None = None
    margin = margin_p = None
    candidates: list[str] = []
    nuisance: dict[str, Any] = {}
    base_residual = None
    step = 0
    while remaining and len(selected) < max_causes:
        base: cz.Cause = cz.Composite(tuple(selected)) if selected else cz.NullArea()
        held = fs.held_out(data, base, folds)
        before, before_t = loss(held), test_loss(held)
        rows, rows_t = {}, {}
        for c in remaining:
            est: cz.Cause = cz.Composite((*selected, c)) if selected else c
            held = fs.held_out(data, est, folds)
            rows[c.code], rows_t[c.code] = loss(held), test_loss(held)
        full = base.fit(data, everything)
        residual = data.e - data.phi * (full.log_scale_[None, :]
                                        + full.log_factor(data, full.theta_))
        nm = fs.NuisanceModel.fit(sw * residual, sw * data.phi, vehicle, wheel)
        if step == 0:
            nuisance = {"log_rate_sd_by_region": {"flange": {}, "tread": {}}}
            for lvl, sds in nm.sd.items():
                for j, r in enumerate(REGIONS):
                    nuisance["log_rate_sd_by_region"][r][lvl] = float(sds[j])
            base_residual = residual
        base_x = full.features(data, full.theta_)
        base_re = np.concatenate([[False, False], full.re_columns()])
        alt = []
        alt_re = []
        for c in remaining:
            prepared = cz.Composite((c,))
            prepared.prepare(data, everything)
            alt.append(fs.area_design(data, np.concatenate(
                [base_x, prepared.features(data, prepared.start())], axis=2)))
            alt_re.append(np.concatenate([base_re, prepared.re_columns()]))
        # a cause whose contrast lies within the vehicles is tested in the vehicle metric
        # (``Cause.within_vehicle``, ``finder_scoring.SCORE_METRIC``), the others in the rows'
        # own metric
        by_vehicle = [bool(c.within_vehicle) and score_transform is not None
                      for c in remaining]
        re_fit = fs.RandomEffectsFit(lambda v: fre.quasi_demean(data, v), base_re, alt_re,
                                     score=score_transform, scored=by_vehicle)
        plain = np.array([fs.relative_gain(before, rows[c.code]) for c in remaining])
        observed = np.array([fs.relative_gain(before_t, rows_t[c.code]) if v else plain[i]
                             for i, (c, v) in enumerate(zip(remaining, by_vehicle,
                                                            strict=True))])
        # the nuisance is taken from the residuals of the baseline plus the leading
        # candidate (its effect must not be resampled as nuisance), widened for the
        # degrees of freedom that fit used
        lead = remaining[int(np.argmax(plain))]
        lead_fit = (cz.Composite((*selected, lead)) if selected else lead).fit(data, everything)
        lead_res = data.e - data.phi * (lead_fit.log_scale_[None, :]
                                        + lead_fit.log_factor(data, lead_fit.theta_))
        nm_lead = fs.NuisanceModel.fit(sw * lead_res, sw * data.phi, vehicle, wheel)
        draws = nm_lead.draws(n_null, rng, used_dof=len(lead_fit.theta_) - len(full.theta_))
        boot = fs.bootstrap_gains(fs.area_design(data, base_x), alt, draws,
                                  np.repeat(folds, 2), re_fit)
        codes = [c.code for c in remaining]
        if step == 0 and shape_row is not None:
            observed = np.append(observed, shape_row[0])
            boot = np.vstack([boot, shape_row[1][None, :]])
            codes.append(shape_cause.code)  # type: ignore[union-attr]
        p_raw, p_adj = fs.min_p(observed, boot)
        if step == 0 and shape_row is not None and shape_within is not None:
            # intersection-union test (Berger 1982): the instrument is named only when its
            # signature stands out both between the wheels and inside the lives measured by
            # several instruments, each adjusted over the catalogue; its p-value is the larger
            obs_w, boot_w = observed.copy(), boot.copy()
            obs_w[-1], boot_w[-1] = shape_within
            p_raw_w, p_adj_w = fs.min_p(obs_w, boot_w)
            p_raw[-1] = max(p_raw[-1], p_raw_w[-1])
            p_adj[-1] = max(p_adj[-1], p_adj_w[-1])
        for i, code in enumerate(codes):
            if code in rows:
                # the gain (materiality, the verdict's order) in the rows' own metric, the
                # p-values from the cause's test metric
                scored[code] = Scored(next(c for c in remaining if c.code == code), before,
                                       rows[code], fs.relative_gain(before, rows[code]),
                                       float(p_raw[i]), float(p_adj[i]), step)
            else:
                s = scored[code]
                s.p_raw, s.p_adj = float(p_raw[i]), float(p_adj[i])

        eligible = [c for c in remaining if is_named(scored[c.code], alpha, min_relative_gain,
                                                     groups, n_boot, rng)]
        if not eligible:
            break
        best = max(eligible, key=lambda c: scored[c.code].gain)
        others = [c for c in remaining if c is not best]
        if others:
            runner = max(others, key=lambda c: scored[c.code].gain)

            # the margin in the best cause's test metric
            by_test = fs.MARGIN_METRIC == "test" and bool(best.within_vehicle) \
                and score_transform is not None
            step_ctx = fs.MarginTest(data, rows_t if by_test else rows,
                                     before_t if by_test else before, best.code, dict(
                zip([c.code for c in remaining], alt, strict=True)),
                fs.area_design(data, base_x), vehicle, wheel, groups, folds, n_null, rng,
                re_fit.transform, dict(zip([c.code for c in remaining], alt_re, strict=True)),
                base_re, score=re_fit.score if by_test else None)
            p_m = step_ctx.p_value(runner.code)
            m = float((rows[runner.code].sum() - rows[best.code].sum()) / max(before.sum(),
                                                                             1e-300))
            if step == 0:
                runner_up, margin, margin_p = runner.code, m, p_m
            # the rivals the verdict must be separated from (``finder_scoring.MARGIN_RIVALS``):
            # every other cause, or those the finder would name on their own at this step and
            # any cause that gains at least as much as the verdict (significant or not)
            rivals = others if fs.MARGIN_RIVALS == "all" else [
                c for c in others
                if c in eligible or scored[c.code].gain >= scored[best.code].gain]
            lead_rival = max(rivals, key=lambda c: scored[c.code].gain) if rivals else None
            p_rival = p_m if lead_rival is runner or lead_rival is None \
                else step_ctx.p_value(lead_rival.code)
            if lead_rival is not None and not fs.separated(p_rival, alpha):
                if step == 0:
                    # the leading rival with the p-value that decided (a fresh resample could
                    # separate it and list the verdict alone), the other rivals tested in turn
                    candidates = [best.code, lead_rival.code] + [
                        c.code for c in rivals if c is not lead_rival
                        and not fs.separated(step_ctx.p_value(c.code), alpha)]
                break
        selected.append(best)
        remaining.remove(best)
        step += 1

    names = [c.code for c in selected]
    echoes: list[str] = []
    if shape_cause is not None and is_named(scored[shape_cause.code], alpha, min_relative_gain,
                                            groups, n_boot, rng):
        names.append(shape_cause.code)
    if shape_cause is not None and shape_cause.code in names and len(names) > 1:
        # the gains are in different metrics: an area cause named beside the instrument that
        # gains nothing material over the named instrument's own area distortion is its
        # echo, not a cause of its own (whether or not it out-gains the instrument)
        scale = fi.InstrumentAreaScale(
            shape_cause.instruments(data),  # type: ignore[attr-defined]
            fi.reference_instrument(shape_cause, data, everything))
        for code in [c for c in names if c != shape_cause.code]:
            echo, echo_gain = fi.instrument_echo(data, scored[code].cause, scale, folds,
                                                 min_relative_gain)
            if echo:
                echoes.append(f"{code} (held-out gain over the instrument's area scales "
                              f"{echo_gain:.4f})")
                names.remove(code)
    if names:   # the verdict is the named cause with the largest relative gain
        top = max(names, key=lambda c: scored[c].gain)
        names = [top] + [c for c in names if c != top]
    # an ambiguous area step does not hide a named wear-curve (instrument) cause: an
    # instrument's geometric error also distorts the areas it measures
    if names:
        verdict = names[0]
    elif candidates:
        verdict = "ambiguous"
    else:
        verdict = "none"

    unexplained: list[dict[str, Any]] = []
    if verdict == "none" and base_residual is not None:
        unexplained = structure_scan(data, base_residual, vehicle, wheel, n_null, rng,
                                 structure_alpha, min_relative_gain)
        if unexplained:
            verdict = "outside_catalogue"

    for code in scored:
        covariate_codes(scored[code].cause, data)
    findings = scored_findings(data, scored, selected, names, vehicle, chosen, n_boot, groups,
                               alpha, min_relative_gain, rng)
    order = {c: i for i, c in enumerate(names)}
    findings.sort(key=lambda f: (order.get(f.cause, len(order)), -f.gain.relative))
    preds: dict[str, list[list[float]]] = {}
    covs: dict[str, list[Any]] = {}
    for cause in chosen:
        if cause.code in skipped:
            continue
        covs[cause.code] = [json_value(v) for v in np.asarray(cause.covariate(data)).tolist()]
        if cause.metric != "shape":
            preds[cause.code] = cause.fit(data, everything).predict(data).tolist()
    preds["none"] = cz.NullArea().fit(data, everything).predict(data).tolist()
    preds["calibrated"] = data.base.tolist()
    preds["measured"] = data.measured.tolist()
    margin_nuisance = (" (from the fit carrying both causes)"
                       if fs.NUISANCE_OF_MARGIN == "encompassing" else "")
    test = (f"held-out gain vs {n_null} datasets resampled from the baseline's nuisance model "
            "(vehicle and wheel log-scale effects and residuals, "
            + ("each kept at its rows with a random sign" if fs.RESAMPLING == "wild"
               else "residuals permuted within wheels") + "), "
            "Westfall-Young max-T across the catalogue; margin over the runner-up "
            + {"sign_flip": f"by a sign-flip test over {np.unique(groups).size} {group_by} "
                            "groups",
               "bootstrap": f"against {n_null} datasets carrying the runner-up's fitted "
                            f"effect and resampled nuisance{margin_nuisance}",
               "combined": f"against {n_null} datasets carrying the runner-up's fitted "
                           f"effect and resampled nuisance{margin_nuisance} and by a "
                           f"sign-flip test over {np.unique(groups).size} {group_by} groups "
                           "(Bonferroni)"
               }[fs.MARGIN_TEST])
    if fs.MARGIN_TEST == "combined" and fs.WITHIN_VEHICLE_MARGIN == "bootstrap":
        test += ("; a verdict whose contrast lies within the vehicles (traction) is tested "
                 "against its runner-up in the vehicle metric by the bootstrap alone")
    if fs.MARGIN_RIVALS == "named":
        test += ("; the verdict must beat only the causes that are themselves significant and "
                 "material or gain at least as much (a weaker runner-up that is neither is "
                 "reported with its margin but leaves the verdict standing)")
    if echoes:
        test += ("; named but dropped as the echo of the named instrument error: "
                 + ", ".join(echoes))
    if expected_progression is not None:
        test += ("; the baseline grows as the expected progression of "
                 f"{expected_progression.source} (not linearly in mileage)")
    return Diagnosis(verdict=verdict, findings=tuple(findings), skipped=skipped,
                     n_measurements=data.n, n_groups=int(np.unique(groups).size),
                     group_by=group_by, residuals=frame, covariates=covs, predictions=preds,
                     selected=tuple(names),
                     runner_up=runner_up, margin=margin, margin_p_value=margin_p,
                     candidates=tuple(candidates), unexplained=tuple(unexplained),
                     nuisance=nuisance, null_test=test)
