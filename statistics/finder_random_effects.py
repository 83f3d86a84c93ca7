"""Random-effects (GLS) weighting of the discrepancy finder's within-wheel causes.

The working residual of a measurement i of wheel j in region r is, in the finder's weighted
space (``finder_scoring.area_design``: rows times sqrt(robustness weight)),

    y_ir = X_ir beta + w_ir u_jr + eps_ir,   w_ir = sqrt(weight_ir) phi_ir,

with u_jr the wheel's random log-scale (its vehicle's and its own rate factor, variance
s_u^2 per region) and eps_ir the measurement's (variance s_e^2). Ordinary least squares
weights every row alike, so a covariate whose contrast lies mostly within the wheels (the
calendar season of each interval) also takes the between-wheel part of its variation, where
a few units or vehicles with their own rate factors decide the fit: the fitted amplitude is
then biased towards the wheels' scatter, and on resampled nuisance-only datasets the same
between-wheel scatter produces large spurious gains (a wide null).

Generalised least squares under the random-intercept covariance V_j = s_e^2 I + s_u^2 w w'
(the random-effects model of Laird and Ware 1982, Biometrics 38:963; the quasi-demeaning of
Fuller and Battese 1973, J. Am. Stat. Assoc. 68:626) is ordinary least squares after the
transform

    Q_j y = y - c_j w (w'y) / (w'w),   c_j = 1 - sqrt(s_e^2 / (s_e^2 + s_u^2 w'w)),

which keeps a share 1 - c_j of every wheel's level: the between-wheel information counts
with the weight its nuisance deserves (all of it when s_u = 0, none when the wheels'
scatter dominates), instead of being dropped (fixed wheel effects) or taken at face value
(OLS). The variance components come from the baseline's residuals (method of moments,
``shrinkage``) and are fixed before any test, so the same linear estimator is applied to
the data, to every cross-validation fold and to every resampled dataset
(``finder_scoring.bootstrap_gains``): the resampling p-value keeps its level.

The causes marked ``random_effects`` (``cause_base.Cause``) take their parameters theta from
the GLS fit; the per-region log-scales b are then refitted by ordinary least squares given
theta (``two_stage``), so the baseline and the held-out scoring are unchanged.

Pure numpy/pandas.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from numpy.typing import NDArray

if TYPE_CHECKING:
    from wearcast.statistics.cause_base import FinderData

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]


def _group_codes(data: FinderData) -> NDArray[np.int64]:
    """(2n,) code of (wheel, region) per row of the flattened (measurement, region) space."""
    wheel = pd.factorize(data.frame["wheel_id"].astype(str))[0]
    return np.asarray(np.repeat(wheel, 2) * 2 + np.tile(np.arange(2), data.n),
                      dtype=np.int64)


def variance_components(residual: Array, loading: Array, codes: NDArray[np.int64]
                        ) -> tuple[Array, Array]:
    """Method-of-moments (s_u^2, s_e^2) per region of y = w u_g + eps.

    residual, loading : (n, 2) weighted residual and loading w; codes : (2n,) (group, region)
    codes whose parity is the region. u_g is estimated per group by w'y / w'w; s_e^2 from
    the within-group residual sum of squares over N - G degrees of freedom; s_u^2 from the
    spread of the group estimates less their mean sampling variance s_e^2 / w'w (floored
    at 0).
    """
    y = np.asarray(residual, dtype=float).reshape(-1)
    w = np.asarray(loading, dtype=float).reshape(-1)
    g = int(codes.max()) + 1
    ww = np.bincount(codes, weights=w * w, minlength=g)
    wy = np.bincount(codes, weights=w * y, minlength=g)
    u = np.where(ww > 0, wy / np.where(ww > 0, ww, 1.0), 0.0)
    eps = y - w * u[codes]
    region_of_group = np.zeros(g, dtype=np.int64)
    region_of_group[codes] = codes % 2
    s_u2, s_e2 = np.zeros(2), np.zeros(2)
    for r in range(2):
        rows = codes % 2 == r
        groups = (region_of_group == r) & (ww > 0)
        n_g = int(groups.sum())
        s_e2[r] = float(np.sum(eps[rows] ** 2)) / max(int(rows.sum()) - n_g, 1)
        if n_g > 1:
            spread = float(np.var(u[groups], ddof=1))
            s_u2[r] = max(spread - s_e2[r] * float(np.mean(1.0 / ww[groups])), 0.0)
    return s_u2, s_e2


def shrinkage(data: FinderData) -> Array:
    """(2n,) c_j of the GLS transform at every (measurement, region) row (module docstring),
    from the variance components of the baseline's residual (the per-region log-scales
    refitted, robustness weights applied); computed once per data."""
    if "re_shrink" not in data.cache:
        codes = _group_codes(data)
        sw = np.sqrt(data.weights)
        w = sw * data.phi
        y = sw * data.e
        b = np.sum(w * y, axis=0) / np.maximum(np.sum(w * w, axis=0), 1e-300)
        s_u2, s_e2 = variance_components(y - w * b[None, :], w, codes)
        ww = np.bincount(codes, weights=(w * w).reshape(-1))
        region = np.arange(ww.size) % 2
        c = 1.0 - np.sqrt(s_e2[region] / np.maximum(s_e2[region] + s_u2[region] * ww,
                                                        1e-300))
        data.cache["re_shrink"] = (codes, c)
    codes, c = data.cache["re_shrink"]
    return np.asarray(c[codes])


def quasi_demean(data: FinderData, values: Array) -> Array:
    """Q values for (2n,) or (2n, k) arrays in the finder's weighted (measurement, region)
    space: each (wheel, region) group loses a share c_j of its projection on its loading
    w = sqrt(weight) phi (module docstring)."""
    from scipy import sparse

    shrink = shrinkage(data)
    if "re_loading" not in data.cache:
        codes = data.cache["re_shrink"][0]
        w = (np.sqrt(data.weights) * data.phi).reshape(-1)
        g = int(codes.max()) + 1
        # S[g, i] = w_i for the rows i of group g: S v are the groups' w'v, S' z puts w_i z_g
        loading = sparse.csr_matrix((w, (codes, np.arange(w.size))), shape=(g, w.size))
        den = np.bincount(codes, weights=w * w, minlength=g)
        data.cache["re_loading"] = (loading, np.where(den > 0, den, 1.0))
    loading, den = data.cache["re_loading"]
    v = np.asarray(values, dtype=float)
    flat = v.reshape(v.shape[0], -1)
    proj = loading.T @ ((loading @ flat) / den[:, None])
    return np.asarray((flat - shrink[:, None] * proj).reshape(v.shape))


def two_stage(x: Array, y: Array, xq: Array, yq: Array, re_columns: Mask) -> Array:
    """Coefficients of y on x: the ``re_columns`` from the GLS fit (xq, yq: the transformed
    design and target), the other columns by ordinary least squares of y less the
    random-effects columns' part."""
    from wearcast.statistics.cause_base import _least_squares

    coef_q = _least_squares(xq, yq)
    out = np.zeros(x.shape[1])
    out[re_columns] = coef_q[re_columns]
    rest = ~re_columns
    if rest.any():
        out[rest] = _least_squares(x[:, rest], y - x[:, re_columns] @ coef_q[re_columns])
    return out


def two_stage_map(x: Array, xq: Array, re_columns: Mask,
                  transform: Callable[[Array], Array]) -> Array:
    """(p, N) linear map L of ``two_stage``: coefficients = L y.

    GLS part: the ``re_columns`` rows of (xq'xq)^+ (Q xq)' (GLS coefficients are
    (xq'xq)^+ xq' Q y, and Q is symmetric); the rest: (x_R'x_R)^+ x_R' (I - x_S L_S).
    ``transform`` is Q on (N, k) arrays.
    """
    p = x.shape[1]
    out = np.zeros((p, x.shape[0]))
    l_q = np.linalg.pinv(xq.T @ xq) @ transform(xq).T
    out[re_columns] = l_q[re_columns]
    rest = ~re_columns
    if rest.any():
        x_r = x[:, rest]
        out[rest] = np.linalg.pinv(x_r.T @ x_r) @ (x_r.T - (x_r.T @ x[:, re_columns])
                                                   @ out[re_columns])
    return out
