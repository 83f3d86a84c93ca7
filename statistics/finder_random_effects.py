"""Random-effects (GLS) weighting of the discrepancy finder's causes and of its tests.

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

Nested vehicle and wheel effects (``LEVELS = "vehicle_wheel"``, the default): the wheel's
log-scale is its vehicle's v_k plus its own u_j, V = s_e^2 I + s_u^2 sum_j w_j w_j' + s_v^2
w_k w_k' per (vehicle, region). The transform is T = Q_v Q_w: Q_w as above with the wheels'
own variance s_u^2, then, since Q_w turns the vehicle effect's covariance into s_v^2 z z'
with z = Q_w w, the same quasi-demeaning per (vehicle, region) with loading z; T V T' =
s_e^2 I (``quasi_demean``; the components by ``nested_components``). The traction
cause's contrast lies between the wheels but within the cars (a car's motor bogie against
its trailer bogie: same load, route and calendar), so its multiplier comes from this fit:
the cars' own rate factors count with the weight their scatter leaves them.

The tests' metric of a cause whose contrast lies within the vehicles (traction,
``cause_base.Cause.within_vehicle``; ``finder_scoring.SCORE_METRIC = "gls_vehicle"``): its
held-out residuals are scored after ``vehicle_demean``, the transform of one random
log-scale per (vehicle, region) alone, so the held-out error of a vehicle is mostly its
contrast within the vehicle: the vehicles' own rate factors, which every candidate leaves
unexplained, no longer make most of the error the cause is scored on (the held-out
Gaussian log-likelihood of the vehicle's rows under a random vehicle intercept, up to
constants). The reported gains stay in the rows' own metric.

The causes marked ``random_effects`` (``cause_base.Cause``) take their parameters theta from
the GLS fit; the per-region log-scales b are then refitted by ordinary least squares given
theta (``two_stage``), so the baseline is unchanged.

Pure numpy/pandas.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

if TYPE_CHECKING:
    from wearcast.statistics.cause_base import FinderData

Array = NDArray[np.float64]
Mask = NDArray[np.bool_]


# levels of the random-effects GLS transform: "vehicle_wheel" (a random log-scale per
# (vehicle, region) and one per (wheel, region) within it, nested: ``quasi_demean``) or
# "wheel" (one per (wheel, region), the vehicle's share in it: the transform before stop 26)
LEVELS = "vehicle_wheel"
_CACHE_KEYS = ("re_shrink", "re_loading", "re_nested", "re_vehicle", "re_designs")


def _group_codes(data: FinderData, column: str = "wheel_id") -> NDArray[np.int64]:
    """(2n,) code of (``column`` level, region) per row of the flattened (measurement,
    region) space."""
    level = pd.factorize(data.frame[column].astype(str))[0]
    return np.asarray(np.repeat(level, 2) * 2 + np.tile(np.arange(2), data.n),
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
    u, ww = _group_estimates(codes, w, y)
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


def _group_estimates(codes: NDArray[np.int64], w: Array, y: Array) -> tuple[Array, Array]:
    """Each group's least-squares effect w'y / w'w of y = w u_g + eps (0 for an empty group)
    and its w'w, over groups 0 .. max(codes)."""
    g = int(codes.max()) + 1
    ww = np.bincount(codes, weights=w * w, minlength=g).astype(float)
    wy = np.bincount(codes, weights=w * y, minlength=g)
    return np.where(ww > 0, wy / np.where(ww > 0, ww, 1.0), 0.0).astype(float), ww


def nested_components(residual: Array, loading: Array, wheel: NDArray[np.int64],
                      vehicle: NDArray[np.int64], iterations: int = 5
                      ) -> tuple[Array, Array, Array]:
    """Method-of-moments (s_v^2, s_u^2, s_e^2) per region of y = w (v_k + u_j) + eps, wheels
    j nested in vehicles k (codes (2n,) of (level, region) as ``variance_components``).

    s_e^2 and the wheels' total s_v^2 + s_u^2 come from ``variance_components`` over the
    wheels. The vehicle estimates v_k = w'y / w'w over the vehicle's rows scatter by
    s_v^2 + s_u^2 sum_j (w_j'w_j)^2 / (w'w)^2 + s_e^2 / w'w (its wheels' effects and its
    measurements averaged with the loadings' weights); s_v^2 is their spread less the
    mean of the last two terms, s_u^2 the wheels' total less s_v^2 (both floored at 0),
    iterated from s_u^2 = the total (the moment equations of the nested one-way model,
    Searle, Casella and McCulloch 1992, Variance Components, ch. 4, with the loadings'
    weights).
    """
    total, s_e2 = variance_components(residual, loading, wheel)
    y = np.asarray(residual, dtype=float).reshape(-1)
    w = np.asarray(loading, dtype=float).reshape(-1)
    gv = int(vehicle.max()) + 1
    v_hat, ww_v = _group_estimates(vehicle, w, y)
    ww_j = np.bincount(wheel, weights=w * w, minlength=int(wheel.max()) + 1)
    # sum over each vehicle's wheels of (w_j'w_j)^2: every (wheel, region) group once
    first = np.unique(wheel, return_index=True)[1]
    sq = np.bincount(vehicle[first], weights=ww_j[wheel[first]] ** 2, minlength=gv)
    s_u2, s_v2 = total.copy(), np.zeros(2)
    for r in range(2):
        groups = (np.arange(gv) % 2 == r) & (ww_v > 0)
        if int(groups.sum()) < 2:
            continue
        spread = float(np.var(v_hat[groups], ddof=1))
        for _ in range(iterations):
            sampling = float(np.mean(s_u2[r] * sq[groups] / ww_v[groups] ** 2
                                     + s_e2[r] / ww_v[groups]))
            s_v2[r] = min(max(spread - sampling, 0.0), total[r])
            s_u2[r] = total[r] - s_v2[r]
    return s_v2, s_u2, s_e2


def _loading_matrix(codes: NDArray[np.int64], w: Array) -> tuple[Any, Array]:
    """S (G x N) with S[g, i] = w_i for the rows i of group g (S v: the groups' w'v;
    S' z puts w_i z_g) and the groups' w'w (1 where empty)."""
    from scipy import sparse

    g = int(codes.max()) + 1
    loading = sparse.csr_matrix((w, (codes, np.arange(w.size))), shape=(g, w.size))
    den = np.bincount(codes, weights=w * w, minlength=g)
    return loading, np.where(den > 0, den, 1.0)


def _baseline(data: FinderData) -> tuple[Array, Array]:
    """(n, 2) weighted residual of the baseline (per-region log-scales refitted) and the
    loading w = sqrt(weight) phi."""
    sw = np.sqrt(data.weights)
    w = sw * data.phi
    y = sw * data.e
    b = np.sum(w * y, axis=0) / np.maximum(np.sum(w * w, axis=0), 1e-300)
    return y - w * b[None, :], w


def shrinkage(data: FinderData) -> Array:
    """(2n,) c_j of the wheel-level GLS transform at every (measurement, region) row (module
    docstring), from the variance components of the baseline's residual (the per-region
    log-scales refitted, robustness weights applied); computed once per data. With
    ``LEVELS = "vehicle_wheel"`` s_u^2 is the wheel's own variance within its vehicle
    (``nested_components``)."""
    if "re_shrink" not in data.cache:
        codes = _group_codes(data)
        r, w = _baseline(data)
        if LEVELS == "vehicle_wheel":
            _, s_u2, s_e2 = nested_components(r, w, codes, _group_codes(data, "vehicle_id"))
        else:
            s_u2, s_e2 = variance_components(r, w, codes)
        ww = np.bincount(codes, weights=(w * w).reshape(-1))
        region = np.arange(ww.size) % 2
        c = 1.0 - np.sqrt(s_e2[region] / np.maximum(s_e2[region] + s_u2[region] * ww,
                                                        1e-300))
        data.cache["re_shrink"] = (codes, c)
    codes, c = data.cache["re_shrink"]
    return np.asarray(c[codes])


def _wheel_transform(data: FinderData, values: Array) -> Array:
    """Q_w values: each (wheel, region) group loses a share c_j of its projection on its
    loading (Fuller and Battese 1973); symmetric."""
    shrink = shrinkage(data)
    if "re_loading" not in data.cache:
        codes = data.cache["re_shrink"][0]
        w = (np.sqrt(data.weights) * data.phi).reshape(-1)
        data.cache["re_loading"] = _loading_matrix(codes, w)
    loading, den = data.cache["re_loading"]
    v = np.asarray(values, dtype=float)
    flat = v.reshape(v.shape[0], -1)
    proj = loading.T @ ((loading @ flat) / den[:, None])
    return np.asarray((flat - shrink[:, None] * proj).reshape(v.shape))


def _vehicle_step(data: FinderData) -> tuple[Array, Any, Array]:
    """(c_k per row, S_z, z'z) of the vehicle step of the nested transform: after Q_w the
    vehicle effect's covariance is s_v^2 z z' per (vehicle, region), z = Q_w w its
    loading, so the step is again a random-intercept quasi-demeaning with loading z."""
    if "re_nested" not in data.cache:
        r, w = _baseline(data)
        vehicle = _group_codes(data, "vehicle_id")
        s_v2, _, s_e2 = nested_components(r, w, _group_codes(data), vehicle)
        z = _wheel_transform(data, w.reshape(-1))
        loading, zz = _loading_matrix(vehicle, z)
        region = np.arange(zz.size) % 2
        c = 1.0 - np.sqrt(s_e2[region] / np.maximum(s_e2[region] + s_v2[region] * zz,
                                                        1e-300))
        data.cache["re_nested"] = (c[vehicle], loading, zz)
    return data.cache["re_nested"]  # type: ignore[no-any-return]


def _vehicle_transform(data: FinderData, values: Array) -> Array:
    c, loading, zz = _vehicle_step(data)
    v = np.asarray(values, dtype=float)
    flat = v.reshape(v.shape[0], -1)
    proj = loading.T @ ((loading @ flat) / zz[:, None])
    return np.asarray((flat - c[:, None] * proj).reshape(v.shape))


def vehicle_demean(data: FinderData, values: Array) -> Array:
    """Q_v values with one random log-scale per (vehicle, region) alone (the wheels' own
    scatter counted as the measurements'): each (vehicle, region) group loses a share c_k of
    its projection on its loading w, c_k = 1 - sqrt(s_e^2 / (s_e^2 + s_v^2 w'w)) from
    ``variance_components`` over the vehicles; symmetric. What remains of a vehicle's rows
    is mostly their contrast within the vehicle (motor against trailer bogies, axle 1
    against axle 2), which the vehicle's own rate factor cannot fake."""
    if "re_vehicle" not in data.cache:
        r, w = _baseline(data)
        codes = _group_codes(data, "vehicle_id")
        s_v2, s_e2 = variance_components(r, w, codes)
        loading, ww = _loading_matrix(codes, w.reshape(-1))
        region = np.arange(ww.size) % 2
        c = 1.0 - np.sqrt(s_e2[region] / np.maximum(s_e2[region] + s_v2[region] * ww,
                                                        1e-300))
        data.cache["re_vehicle"] = (c[codes], loading, ww)
    c, loading, ww = data.cache["re_vehicle"]
    v = np.asarray(values, dtype=float)
    flat = v.reshape(v.shape[0], -1)
    proj = loading.T @ ((loading @ flat) / ww[:, None])
    return np.asarray((flat - c[:, None] * proj).reshape(v.shape))


def quasi_demean(data: FinderData, values: Array) -> Array:
    """T values for (2n,) or (2n, k) arrays in the finder's weighted (measurement, region)
    space, T'T = s_e^2 V^-1 (module docstring). ``LEVELS = "wheel"``: T = Q_w, each (wheel,
    region) group loses a share c_j of its projection on its loading w = sqrt(weight) phi.
    ``"vehicle_wheel"``: T = Q_v Q_w (module docstring)."""
    if LEVELS == "wheel":
        return _wheel_transform(data, values)
    return _vehicle_transform(data, _wheel_transform(data, values))


def cached_quasi_demean(data: FinderData, design: Array) -> Array:
    """``quasi_demean`` of a (2n, k) design, kept per design (by a digest of its bytes): a
    cause's cross-validation folds and resampled datasets refit the same design again and
    again (the rows they use differ, not the design)."""
    import hashlib

    key = hashlib.blake2b(np.ascontiguousarray(design).tobytes(), digest_size=16).digest() \
        + str(design.shape).encode()
    store = data.cache.setdefault("re_designs", {})
    if key not in store:
        if len(store) >= 64:
            store.clear()
        store[key] = quasi_demean(data, design)
    return np.asarray(store[key])


def quasi_demean_transpose(data: FinderData, values: Array) -> Array:
    """T' values (``quasi_demean``): Q_w Q_v; T itself when ``LEVELS = "wheel"`` (Q_w is
    symmetric)."""
    if LEVELS == "wheel":
        return _wheel_transform(data, values)
    return _wheel_transform(data, _vehicle_transform(data, values))


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
                  transform_t: Callable[[Array], Array]) -> Array:
    """(p, N) linear map L of ``two_stage``: coefficients = L y.

    GLS part: the ``re_columns`` rows of (xq'xq)^+ (T' xq)' (GLS coefficients are
    (xq'xq)^+ xq' T y with xq = T x); the rest: (x_R'x_R)^+ x_R' (I - x_S L_S).
    ``transform_t`` is T' on (N, k) arrays (``quasi_demean_transpose``; T itself when T is
    symmetric, the wheel-level transform).
    """
    p = x.shape[1]
    out = np.zeros((p, x.shape[0]))
    l_q = np.linalg.pinv(xq.T @ xq) @ transform_t(xq).T
    out[re_columns] = l_q[re_columns]
    rest = ~re_columns
    if rest.any():
        x_r = x[:, rest]
        out[rest] = np.linalg.pinv(x_r.T @ x_r) @ (x_r.T - (x_r.T @ x[:, re_columns])
                                                   @ out[re_columns])
    return out
