"""Out-of-sample scoring and resampling tests of the discrepancy finder.

* ``held_out``: held-out working residuals of an extension, folds grouped by vehicle.
* ``NuisanceModel``: the fitted baseline's per-vehicle and per-wheel log-scale effects and
  the remaining per-measurement residuals; ``draws`` resamples them into datasets with the
  baseline's nuisance variation and no effect (no assumed noise distribution): by default a
  wild cluster bootstrap (every vehicle effect, wheel effect and residual kept at its rows
  with an independent random sign, so noise that depends on the mileage, the wheel position
  or the instrument keeps its place), or effects resampled across vehicles and wheels with
  each wheel's residuals permuted within the wheel (``scheme="permute"``).
* ``bootstrap_gains``: the held-out relative gain of every candidate on those datasets,
  computed exactly as on the data but with each extension linearised at its nominal value
  (closed-form refits by precomputed pseudo-inverses, so hundreds of datasets cost little).
* ``min_p``: Westfall-Young single-step max-T adjustment over the candidates (the family-wise
  error across the catalogue comes from the same resampled datasets).
* ``margin_p``: the margin of the best cause over the runner-up, tested by a parametric
  bootstrap under "the runner-up is the cause": datasets carrying the runner-up's fitted
  effect plus nuisance resampled from the fit carrying both causes, on which both are
  scored as on the data;
* ``sign_flip_p``: randomisation test of a paired difference over groups (the former margin
  test, ``MARGIN_TEST = "sign_flip"``).

The residual structure outside the catalogue, tested against the same resampled datasets, is
:mod:`wearcast.statistics.finder_structure`.

Pure numpy/pandas.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from itertools import product
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.statistics import causes as cz

Array = NDArray[np.float64]

# resampling scheme of the nuisance-only datasets (``NuisanceModel.draws``)
RESAMPLING = "wild"
# nuisance of the margin's parametric bootstrap: the residuals of the model carrying both
# causes ("encompassing", ``margin_p``) or of the runner-up's own fit ("runner_up")
NUISANCE_OF_MARGIN = "encompassing"
# the margin is the best cause's held-out gain over max(runner-up's gain, floor): a runner-up
# that does worse out of sample than the baseline explains nothing, and its overfitting on
# the resampled datasets (held-out gains of -5 to -10 % with a few parameters on nine
# vehicles) is noise of the runner-up's, not evidence for it (None: the plain difference)
RUNNER_GAIN_FLOOR: float | None = 0.0
# test of the verdict's margin over the runner-up: "combined" (Bonferroni of the two below),
# "bootstrap" (``margin_p``) or "sign_flip" (``sign_flip_p`` over the groups)
MARGIN_TEST = "combined"
# metric of the held-out error in the tests of a cause whose contrast lies within the
# vehicles (``cause_base.Cause.within_vehicle``: traction) -- its resampled null, max-T
# statistic and margin; the reported gains, their materiality and the other causes' tests
# stay in the rows' own metric: "gls_vehicle" (the held-out residuals after
# ``finder_random_effects.vehicle_demean``, a random log-scale per vehicle: the vehicles'
# own rate factors, which no candidate explains, no longer make most of the error; depot
# traction 1.1: 13 -> 15 of 20; applied to every cause (16 of 20), depot flange lubrication,
# a contrast between the cars, fell to 3 of 5 at 0.8 and 4 of 5 at 0.6), "gls" (after the
# nested vehicle and wheel transform ``quasi_demean``: a contrast between wheels is then
# scored on the share 1 - c_j of it the wheel transform keeps; with it for every cause
# traction 1.1 on the twin lost its margin over the runner-up on 5 of 20 seeds) or "ols"
# (the rows' weighted squared residuals, the finder before stop 26)
SCORE_METRIC = "gls_vehicle"
# metric of the margin test over the runner-up: "test" (``SCORE_METRIC``) or "ols" (the rows'
# weighted squared residuals, the metric of the reported gains)
MARGIN_METRIC = "test"
# margin test of a best cause whose contrast lies within the vehicles, scored in the vehicle
# metric (``MARGIN_METRIC = "test"``; traction) when ``MARGIN_TEST`` is "combined":
# "bootstrap" (``margin_p`` alone, at the full alpha) or "combined" (as every other cause).
# The sign-flip half of the combined test is there for a best cause acting between the
# vehicles (vehicle load), whose effect the bootstrap keeps as vehicle-level nuisance; in the
# vehicle metric that nuisance no longer enters the score, while a sign-flip over the
# vehicles compares within-car contrasts only the motor cars carry (depot traction 1.1, seeds
# 107 and 109: sign-flip p 0.44 and 0.49 against wear_measure, bootstrap 0.07 and 0.03)
WITHIN_VEHICLE_MARGIN = "bootstrap"
# the causes the verdict's margin is tested against: "named" (the other causes that are
# themselves significant and material at the step, ``discrepancy_findings.is_named``, or gain
# at least as much as the verdict: a weaker cause the finder would not name on its own is no
# rival explanation, and the verdict's margin over it is reported but does not make the
# verdict ``ambiguous``) or "all" (every other cause, the finder before)
MARGIN_RIVALS = "named"


def codes_of(values: NDArray[Any]) -> NDArray[np.int64]:
    return np.asarray(pd.factorize(pd.Series(values).astype(str))[0], dtype=np.int64)


def relative_gain(before: Array, after: Array) -> float:
    """Relative gain 1 - sum(after) / sum(before) of held-out errors (0 before -> 1e-300)."""
    return float(1.0 - after.sum() / max(before.sum(), 1e-300))


def held_out(data: cz.FinderData, cause: cz.Cause, folds: NDArray[np.int64]) -> Array:
    """(n, 2) held-out working residual e - phi (b + g(theta)) of ``cause`` over the folds."""
    out = np.zeros((data.n, 2))
    for k in np.unique(folds):
        test = folds == k
        est = cause.fit(data, ~test)
        g = est.log_factor(data, est.theta_)
        r = data.e - data.phi * (est.log_scale_[None, :] + g)
        out[test] = r[test]
    return out


def held_out_shape(coef: Array, instrument: NDArray[Any] | None,
                   folds: NDArray[np.int64], weights: Array | None = None) -> Array:
    """(n, 3) held-out shape residual coefficients: common mean (instrument None) or one
    mean per instrument, fitted on the other folds; ``weights`` (n,): the means are
    weighted by them (``finder_shape_weights``; plain means when None)."""
    out = np.zeros_like(coef)
    inst = np.zeros(coef.shape[0], dtype=np.int64) if instrument is None else codes_of(instrument)
    w = np.ones(coef.shape[0]) if weights is None else np.asarray(weights, dtype=float)

    def mean_of(rows: NDArray[np.bool_]) -> Array:
        # no weight at all (rows the test leaves out): the minimum-norm fit, 0
        if float(w[rows].sum()) <= 0.0:
            return np.zeros(coef.shape[1])
        return np.asarray(np.average(coef[rows], axis=0, weights=w[rows]))

    for k in np.unique(folds):
        test = folds == k
        for i in np.unique(inst[test]):
            tr = ~test & (inst == i)
            mean = mean_of(tr) if tr.any() else mean_of(~test)
            sel = test & (inst == i)
            out[sel] = coef[sel] - mean
    return out


@dataclass(frozen=True)
class NuisanceModel:
    """Per-vehicle and per-wheel random log-scale effects of a fitted baseline (n, m columns).

    vehicle_effect, wheel_effect : (n, m) each row's vehicle / wheel effect [log rate]
    residual : (n, m) what remains; weight : (n, m) phi (1 for the shape metric)
    sd : {'vehicle', 'wheel', 'measurement'} standard deviations per column
    """

    vehicle: NDArray[np.int64]
    wheel: NDArray[np.int64]
    vehicle_effect: Array
    wheel_effect: Array
    residual: Array
    weight: Array
    sd: dict[str, list[float]]

    @classmethod
    def fit(cls, residual: Array, weight: Array, vehicle: NDArray[Any],
            wheel: NDArray[Any]) -> NuisanceModel:
        v, w = codes_of(vehicle), codes_of(wheel)
        r = np.asarray(residual, dtype=float)
        wt = np.asarray(weight, dtype=float)

        def level_effect(values: Array, codes: NDArray[np.int64]) -> Array:
            g = int(codes.max()) + 1
            num = np.zeros((g, values.shape[1]))
            den = np.zeros((g, values.shape[1]))
            np.add.at(num, codes, wt * values)
            np.add.at(den, codes, wt * wt)
            return np.asarray(np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0))

        ve = level_effect(r, v)[v]
        we = level_effect(r - wt * ve, w)[w]
        eps = r - wt * (ve + we)
        sd = {"vehicle": np.std(np.unique(np.column_stack([v, ve]), axis=0)[:, 1:],
                                axis=0).tolist(),
              "wheel": np.std(np.unique(np.column_stack([w, we]), axis=0)[:, 1:],
                              axis=0).tolist(),
              "measurement": np.std(eps, axis=0).tolist()}
        return cls(v, w, ve, we, eps, wt, sd)

    def draws(self, n_draws: int, rng: np.random.Generator,
              used_dof: float | tuple[float, float] = 0, scheme: str | None = None) -> Array:
        """(n * m, B) resampled residual datasets without any effect (module docstring).

        ``used_dof``: parameters of an effect fitted before the residuals were taken; the
        vehicle and wheel effects are widened by sqrt(G / (G - used_dof)) for the variance
        that fit absorbed; a pair (vehicle, wheel) gives each level its own degrees of
        freedom (``level_dof``).

        ``scheme`` (default :data:`RESAMPLING`):

        * ``wild``: every vehicle effect, wheel effect and measurement residual stays where
          it was and gets an independent random sign (a wild cluster bootstrap with
          Rademacher weights at the three levels). Each measurement keeps its own spread, so
          noise that is larger for small areas (early mileage, trailing flanges) or on one
          instrument stays where it is, and so does a larger scatter of one wheel position;
        * ``permute``: effects resampled across vehicles / wheels, each wheel's residuals
          permuted within the wheel with random signs (exchangeable noise within a wheel).
        """
        scheme = scheme or RESAMPLING
        if scheme not in ("wild", "permute"):
            raise ValueError(f"scheme must be 'wild' or 'permute', got {scheme!r}")
        n, m = self.residual.shape
        vf = pd.Series(np.arange(n)).groupby(self.vehicle).first().to_numpy()
        wf = pd.Series(np.arange(n)).groupby(self.wheel).first().to_numpy()
        v_eff, w_eff = self.vehicle_effect[vf], self.wheel_effect[wf]
        dof_v, dof_w = used_dof if isinstance(used_dof, tuple) else (used_dof, used_dof)
        if dof_v:
            v_eff = v_eff * np.sqrt(v_eff.shape[0] / max(v_eff.shape[0] - dof_v, 1))
        if dof_w:
            w_eff = w_eff * np.sqrt(w_eff.shape[0] / max(w_eff.shape[0] - dof_w, 1))
        if scheme == "wild":
            # codes from codes_of are the positions of the first occurrences' order, so
            # v_eff[self.vehicle] puts every vehicle's own effect back on its rows. Built in
            # the (n, m, B) layout of the result (signs gathered to the rows, then the
            # products): the same numbers as signing the effects first, without the transpose
            sv = rng.choice((-1.0, 1.0), size=(n_draws, v_eff.shape[0], 1))
            sw = rng.choice((-1.0, 1.0), size=(n_draws, w_eff.shape[0], 1))
            se = rng.choice((-1.0, 1.0), size=(n_draws, n, 1))
            vs = v_eff[self.vehicle][:, :, None] * sv[:, :, 0].T[self.vehicle][:, None, :]
            ws = w_eff[self.wheel][:, :, None] * sw[:, :, 0].T[self.wheel][:, None, :]
            eps = self.residual[:, :, None] * se[:, :, 0].T[:, None, :]
            out = self.weight[:, :, None] * (vs + ws) + eps
            return np.asarray(out.reshape(n * m, n_draws))
        by_wheel = np.argsort(self.wheel, kind="stable")
        # all draws at once: effects resampled across vehicles / wheels, each wheel's
        # residuals permuted within the wheel (argsort of wheel code + uniform key) with
        # random signs
        vs = v_eff[rng.integers(0, v_eff.shape[0], (n_draws, v_eff.shape[0]))][
            :, self.vehicle]
        ws = w_eff[rng.integers(0, w_eff.shape[0], (n_draws, w_eff.shape[0]))][
            :, self.wheel]
        order = np.argsort(self.wheel[None, :] + rng.random((n_draws, n)), axis=1)
        eps = np.empty((n_draws, n, m))
        eps[:, by_wheel] = self.residual[order]
        eps *= rng.choice((-1.0, 1.0), size=(n_draws, n, 1))
        out = self.weight[None, :, :] * (vs + ws) + eps
        return np.ascontiguousarray(np.moveaxis(out, 0, -1)).reshape(n * m, n_draws)


def area_design(data: cz.FinderData, features: Array) -> Array:
    """(2n, 2 + k) design of the linearised area fit: phi (b_r + x theta), rows (i, region),
    times the square root of the rows' robustness weights."""
    n, _, k = features.shape
    d = np.zeros((n, 2, 2 + k))
    d[:, 0, 0] = 1.0
    d[:, 1, 1] = 1.0
    d[:, :, 2:] = features
    w = np.sqrt(data.weights)[:, :, None]
    return np.asarray((d * data.phi[:, :, None] * w).reshape(2 * n, 2 + k))


def _fold_sse(design: Array, ys: Sequence[Array], yty: Sequence[Array],
              slices: Sequence[slice], re: tuple[Array, Sequence[Array], Array] | None = None,
              score: tuple[Array, Sequence[Array], Sequence[Array]] | None = None) -> Array:
    """(B,) held-out sum of squares of the least-squares fit of y on ``design`` over folds.

    Rows are sorted by fold (``slices``); ``ys``/``yty`` are each fold's y block (N_k, B)
    and its column sums of squares. Normal equations from per-fold cross-products: the
    training fit of fold k uses the totals minus fold k's own.

    ``re`` = (design_q, ys_q, columns): the ``columns`` of the fit come from the
    random-effects GLS fit (transformed design and y blocks, sorted as ``design``/``ys``),
    the other columns by least squares given them
    (``finder_random_effects.two_stage``), scored on the untransformed rows.
    """
    xs = [design[sl] for sl in slices]
    # small products by einsum (single-threaded: no BLAS thread oversubscription)
    xtx = [np.einsum("np,nq->pq", x, x) for x in xs]
    xty = [np.einsum("np,nb->pb", x, y) for x, y in zip(xs, ys, strict=True)]
    xtx_all, xty_all = sum(xtx), sum(xty)
    if re is not None:
        xqs = [re[0][sl] for sl in slices]
        xtx_q = [np.einsum("np,nq->pq", x, x) for x in xqs]
        xty_q = [np.einsum("np,nb->pb", x, y) for x, y in zip(xqs, re[1], strict=True)]
        xtx_q_all, xty_q_all = sum(xtx_q), sum(xty_q)
        cols = np.asarray(re[2], dtype=bool)
        rest = ~cols
    sse = np.zeros(ys[0].shape[1])
    for k in range(len(slices)):
        a, c = xtx_all - xtx[k], xty_all - xty[k]
        if re is None:
            beta = np.linalg.pinv(a) @ c
        else:
            theta = (np.linalg.pinv(xtx_q_all - xtx_q[k]) @ (xty_q_all - xty_q[k]))[cols]
            beta = np.zeros((a.shape[0], c.shape[1]))
            beta[cols] = theta
            beta[rest] = np.linalg.pinv(a[np.ix_(rest, rest)]) @ (
                c[rest] - a[np.ix_(rest, cols)] @ theta)
        if score is None:
            sse += yty[k] - 2.0 * np.sum(beta * xty[k], axis=0) \
                + np.sum(beta * (xtx[k] @ beta), axis=0)
        else:
            xs_k = score[0][slices[k]]
            sse += score[2][k] - 2.0 * np.sum(beta * np.einsum("np,nb->pb", xs_k,
                                                               score[1][k]), axis=0) \
                + np.sum(beta * (np.einsum("np,nq->pq", xs_k, xs_k) @ beta), axis=0)
    return np.asarray(sse)


@dataclass(frozen=True)
class RandomEffectsFit:
    """Which design columns are fitted by random-effects GLS, and the transform Q
    (``finder_random_effects.quasi_demean``) on (2n, k) arrays of the finder's space."""

    transform: Any                         # Callable[[Array], Array]
    null_columns: Array | None             # (p0,) bool of the null design, or None
    alt_columns: Sequence[Array | None]    # per alternative design
    score: Any = None                      # transform of the scored held-out rows
    scored: Sequence[bool] | None = None   # per alternative: scored after ``score``


def bootstrap_gains(null_design: Array, alt_designs: Sequence[Array], draws: Array,
                    folds_flat: NDArray[np.int64], re: RandomEffectsFit | None = None
                    ) -> Array:
    """(n_alt, B) held-out relative gains 1 - SSE_alt / SSE_null on resampled datasets.

    ``re``: designs with columns fitted by random-effects GLS (the same estimator as
    ``cause_base.solve`` applies to the data); the draws are transformed once. The
    alternatives ``re.scored`` marks are scored (and so is their baseline) on the held-out
    rows after ``re.score`` (the tests' metric of a cause whose contrast lies within the
    vehicles, ``cause_base.Cause.within_vehicle``).
    """
    order = np.argsort(folds_flat, kind="stable")
    f_sorted = folds_flat[order]
    bounds = np.flatnonzero(np.diff(f_sorted)) + 1
    starts = np.concatenate([[0], bounds])
    ends = np.concatenate([bounds, [f_sorted.size]])
    slices = [slice(int(a), int(b)) for a, b in zip(starts, ends, strict=True)]
    y = draws[order]
    ys = [y[sl] for sl in slices]
    yty = [np.sum(b * b, axis=0) for b in ys]
    ys_q: list[Array] = []
    uses_re = re is not None and any(
        c is not None and bool(np.any(c)) for c in [re.null_columns, *re.alt_columns])
    if uses_re:
        assert re is not None
        y_q = re.transform(draws)[order]
        ys_q = [y_q[sl] for sl in slices]
    score_y = None
    if re is not None and re.score is not None and re.scored is not None and any(re.scored):
        y_s = re.score(draws)[order]
        ys_s = [y_s[sl] for sl in slices]
        score_y = (ys_s, [np.sum(b * b, axis=0) for b in ys_s])

    def scoring(design: Array) -> tuple[Array, Sequence[Array], Sequence[Array]] | None:
        if score_y is None or re is None:
            return None
        return re.score(design)[order], score_y[0], score_y[1]

    def spec(design: Array, columns: Array | None
             ) -> tuple[Array, Sequence[Array], Array] | None:
        if re is None or columns is None or not np.any(columns):
            return None
        return re.transform(design)[order], ys_q, np.asarray(columns, dtype=bool)

    null_spec = spec(null_design, None if re is None else re.null_columns)
    before = _fold_sse(null_design[order], ys, yty, slices, null_spec)
    before_s = None if score_y is None else _fold_sse(null_design[order], ys, yty, slices,
                                                      null_spec, scoring(null_design))
    out = np.empty((len(alt_designs), draws.shape[1]))
    for i, d in enumerate(alt_designs):
        cols = None if re is None else re.alt_columns[i]
        by_score = before_s is not None and re is not None and re.scored is not None \
            and bool(re.scored[i])
        base = before_s if by_score else before
        assert base is not None
        out[i] = 1.0 - _fold_sse(d[order], ys, yty, slices, spec(d, cols),
                                 scoring(d) if by_score else None) / np.maximum(base, 1e-300)
    return out


def margin_p(y: Array, weight: Array, null_design: Array, best_design: Array,
             runner_design: Array, observed: float, vehicle: NDArray[Any],
             wheel: NDArray[Any], folds_flat: NDArray[np.int64], n_draws: int,
             rng: np.random.Generator, re: RandomEffectsFit | None = None) -> float:
    """p-value of the best cause's margin over the runner-up under H0 "the runner-up is the
    cause" (a parametric bootstrap, Cox's test of non-nested models by simulation).

    y : (2n,) the working residual of the data in the designs' space (sqrt(robustness
        weight) x e, rows (measurement, region)); weight : (n, 2) sqrt(w) phi
    null_design, best_design, runner_design : (2n, p) linearised designs (``area_design``)
        of the step's baseline and of the baseline plus each cause
    observed : the margin on the data, (SSE_runner - SSE_best) / SSE_baseline held out, the
        runner-up's gain floored at ``RUNNER_GAIN_FLOOR`` (as on every resampled dataset)
    re : random-effects columns of (null, [best, runner]) (``bootstrap_gains``)

    The runner-up's design is fitted to y (its effect on top of the baseline). The nuisance
    model (vehicle and wheel effects, per-measurement residuals) comes from the residuals of
    the encompassing fit that carries both causes, widened for both causes' parameters
    (``NUISANCE_OF_MARGIN = "encompassing"``): under H0 they are nuisance as much as the
    runner-up's own residuals, but under H1 the runner-up's residuals still hold the best
    cause's effect, which, resampled as vehicle effects, widens the null of the margin
    until a real margin on a few vehicles cannot stand out (the same reason the main test
    takes its nuisance from the leading candidate's fit). ``"runner_up"``: from the
    runner-up's own residuals (the former test). The draws are resampled as in the main
    test (``NuisanceModel.draws``) and added to the runner-up's fitted values. On each
    dataset both causes are scored held out exactly as on the data;
    p = (1 + #{margin* >= observed}) / (B + 1). Unlike a sign-flip over the groups, whose
    power is capped by the number of vehicles (and by half of them carrying no contrast when
    the causes differ only on motor cars), the null keeps the runner-up's own explanation of
    the data and the data's nuisance variation.
    """
    coef, *_ = np.linalg.lstsq(runner_design, y, rcond=None)
    signal = runner_design @ coef
    n = y.size // 2
    k0 = null_design.shape[1]
    if NUISANCE_OF_MARGIN == "encompassing":
        both = np.hstack([runner_design, best_design[:, k0:]])
        coef_both, *_ = np.linalg.lstsq(both, y, rcond=None)
        residual = y - both @ coef_both
        used = both.shape[1] - k0
    else:
        residual = y - signal
        used = runner_design.shape[1] - k0
    nm = NuisanceModel.fit(residual.reshape(n, 2), weight, vehicle, wheel)
    dof: float | tuple[float, float] = max(used, 0)
    if NUISANCE_OF_MARGIN == "encompassing" and used > 0:
        dof = level_dof(null_design, both[:, k0:], vehicle, wheel)
    draws = signal[:, None] + nm.draws(n_draws, rng, used_dof=dof)
    gains = bootstrap_gains(null_design, [best_design, runner_design], draws, folds_flat, re)
    margins = margin_statistic(gains[0], gains[1])
    return float((1.0 + np.sum(margins >= observed)) / (n_draws + 1.0))


def margin_statistic(gain_best: Any, gain_runner: Any) -> Array:
    """The margin of the best cause over the runner-up: held-out relative gain of the best
    minus the runner-up's floored at ``RUNNER_GAIN_FLOOR`` (elementwise)."""
    runner = np.asarray(gain_runner, dtype=float)
    if RUNNER_GAIN_FLOOR is not None:
        runner = np.maximum(runner, RUNNER_GAIN_FLOOR)
    return np.asarray(np.asarray(gain_best, dtype=float) - runner)


def level_dof(null_design: Array, effect_columns: Array, vehicle: NDArray[Any],
              wheel: NDArray[Any]) -> tuple[float, float]:
    """Degrees of freedom a fit of ``effect_columns`` (2n, p; rows (measurement, region))
    takes from the vehicle and from the wheel level: trace((X'X)^-1 X' P X), X the columns
    with the null design projected out, P the projection on the (vehicle, region) means and
    on the (wheel, region) means less it.

    A column that is constant over each vehicle (a motor-car indicator) takes a whole degree
    of freedom from the vehicle effects, one that varies only within the wheels (a season)
    almost none; widening the vehicle effects by sqrt(G / (G - p)) for every parameter
    alike would, with nine vehicles and a few within-wheel parameters, resample vehicle
    effects far larger than the data's.
    """
    coef, *_ = np.linalg.lstsq(null_design, effect_columns, rcond=None)
    x = effect_columns - null_design @ coef
    region = np.tile(np.arange(2), x.shape[0] // 2)

    def projected(codes: NDArray[np.int64]) -> Array:
        key = codes_of(np.repeat(codes, 2) * 2 + region)
        g = int(key.max()) + 1
        sums = np.zeros((g, x.shape[1]))
        np.add.at(sums, key, x)
        return np.asarray((sums / np.bincount(key, minlength=g)[:, None])[key])

    pv = projected(codes_of(vehicle))
    pw = projected(codes_of(wheel))
    xtx_inv = np.linalg.pinv(x.T @ x)
    dof_v = float(np.trace(xtx_inv @ (x.T @ pv)))
    dof_w = float(np.trace(xtx_inv @ (x.T @ (pw - pv))))
    return max(dof_v, 0.0), max(dof_w, 0.0)


@dataclass
class MarginTest:
    """The margin test of one forward-selection step (``finder_scoring.MARGIN_TEST``)."""

    data: cz.FinderData
    rows: dict[str, NDArray[np.float64]]      # held-out error per cause
    before: NDArray[np.float64]               # held-out error of the step's baseline
    best: str
    designs: dict[str, NDArray[np.float64]]   # linearised design per cause
    base_design: NDArray[np.float64]
    vehicle: NDArray[Any]
    wheel: NDArray[Any]
    groups: NDArray[Any]
    folds: NDArray[np.int64]
    n_null: int
    rng: np.random.Generator
    # random-effects columns per cause's design and of the baseline's (``bootstrap_gains``)
    re_transform: Any = None
    re_columns: dict[str, Array] | None = None
    re_base: Array | None = None
    score: Any = None                         # transform of the scored rows, or None

    def p_value(self, other: str) -> float:
        """p of "``other`` explains the data as well as the best cause"."""
        diff = self.rows[other] - self.rows[self.best]
        flip = 1.0
        # a within-vehicle best cause scored in the vehicle metric (``score`` set): the
        # bootstrap alone (``WITHIN_VEHICLE_MARGIN``)
        bootstrap_only = MARGIN_TEST == "combined" and self.score is not None \
            and WITHIN_VEHICLE_MARGIN == "bootstrap"
        if MARGIN_TEST in ("sign_flip", "combined") and not bootstrap_only:
            flip = sign_flip_p(group_sums(diff, self.groups), 4000, self.rng)
            if MARGIN_TEST == "sign_flip":
                return flip
        total = max(float(self.before.sum()), 1e-300)
        observed = float(margin_statistic(1.0 - float(self.rows[self.best].sum()) / total,
                                          1.0 - float(self.rows[other].sum()) / total))
        if observed <= 0.0:
            # the other cause does at least as well out of sample: nothing to test (under its
            # own fitted effect the bootstrap would call a small deficit "large")
            return 1.0
        sw = np.sqrt(self.data.weights)
        boot = margin_p((sw * self.data.e).reshape(-1), sw * self.data.phi,
                        self.base_design, self.designs[self.best], self.designs[other],
                        observed, self.vehicle, self.wheel, np.repeat(self.folds, 2),
                        self.n_null, self.rng, self._re(other))
        if MARGIN_TEST == "bootstrap" or bootstrap_only:
            return boot
        # Bonferroni over the two tests of the same hypothesis: the bootstrap is powerful when
        # the contrast sits on a few vehicles (traction: motor cars only) but keeps a
        # vehicle-level effect the runner-up leaves unexplained as nuisance, which caps it
        # with few vehicles (vehicle_load on nine cars); the sign-flip has the opposite
        # strengths. min(1, 2 min p) keeps the level.
        return float(min(1.0, 2.0 * min(boot, flip)))


    def _re(self, other: str) -> RandomEffectsFit | None:
        if self.re_transform is None or self.re_columns is None:
            return None
        return RandomEffectsFit(self.re_transform, self.re_base,
                                [self.re_columns[self.best], self.re_columns[other]],
                                score=self.score, scored=[self.score is not None] * 2)


def separated(p_margin: float, alpha: float) -> bool:
    """The margin test rejects "the runner-up explains the data as well": a resampling p at
    <= alpha (the sign-flip test, exact over few groups, at < alpha as before)."""
    return p_margin < alpha if MARGIN_TEST == "sign_flip" else p_margin <= alpha


def raw_p(observed: Array, null: Array) -> Array:
    """Per-candidate one-sided resampling p-values (1 + #{null >= obs}) / (B + 1)."""
    b = null.shape[1]
    return np.asarray((1.0 + np.sum(null >= observed[:, None], axis=1)) / (b + 1.0))


def min_p(observed: Array, null: Array) -> tuple[Array, Array]:
    """(raw p, family-wise adjusted p) of each candidate's observed statistic.

    Westfall-Young single-step max-T on the same resamples: each candidate's statistic is
    standardised by its own null mean and standard deviation (so candidates with more
    parameters, whose null gains are larger, do not dominate), and the adjusted p-value is
    the share of resamples whose largest standardised statistic reaches the observed one.
    """
    p = raw_p(observed, null)
    b = null.shape[1]
    mu = null.mean(axis=1)
    sd = np.maximum(null.std(axis=1, ddof=1), 1e-12)
    z_obs = (observed - mu) / sd
    z_max = ((null - mu[:, None]) / sd[:, None]).max(axis=0)
    adj = (1.0 + np.sum(z_max[None, :] >= z_obs[:, None], axis=1)) / (b + 1.0)
    return p, np.asarray(np.maximum(adj, p))


def sign_flip_p(diff_by_group: Array, n_draws: int, rng: np.random.Generator) -> float:
    """One-sided randomisation p-value that the mean of ``diff_by_group`` exceeds 0 (signs
    of the groups flipped; exact enumeration up to 14 groups)."""
    d = np.asarray(diff_by_group, dtype=float)
    g = d.size
    if g == 0:
        return 1.0
    obs = d.sum()
    if g <= 14:
        signs = np.array(list(product((-1.0, 1.0), repeat=g)))
    else:
        signs = rng.choice((-1.0, 1.0), size=(n_draws, g))
    stat = signs @ d
    return float((np.sum(stat >= obs - 1e-12) + (0 if g <= 14 else 1))
                 / (signs.shape[0] + (0 if g <= 14 else 1)))


def group_sums(values: Array, groups: NDArray[Any]) -> Array:
    c = codes_of(groups)
    return np.asarray(np.bincount(c, weights=values, minlength=int(c.max()) + 1), dtype=float)
