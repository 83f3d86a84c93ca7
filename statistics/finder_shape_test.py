"""The instrument cause's test on the wear-curve shape (``profile_misalignment``) in the
discrepancy finder (:mod:`wearcast.statistics.discrepancy`, step 3 of its docstring).

An instrument's geometric signature (lateral offset, lateral scale, flange offset) is the same
at every measurement it takes, so the finder tests per-instrument means of the wheels'
signature coefficients (``whitened_shape``: the shape coefficients less each wheel life's
growth with the wear, in curve-space units) in the metric of their nuisance
(``noise_whitened``: a generalised least-squares, Hotelling-type contrast against the
wheel-to-wheel scatter), and inside the wheel lives measured by more than one instrument
(``within_life_p``, nuisance resampled by measurement session, ``sessions``). The resampled
nulls are the finder's (``finder_scoring.NuisanceModel``, ``finder_scoring.bootstrap_gains``).

Pure numpy/pandas.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.statistics import causes as cz
from wearcast.statistics import finder_scoring as fs
from wearcast.statistics import finder_shape_growth as fsg
from wearcast.statistics import finder_shape_weights as fsw


def whitened_shape(data: cz.FinderData) -> NDArray[np.float64]:
    """Signature coefficients (shape coefficients less each wheel life's growth with the
    wear, ``finder_shape_growth``) scaled so that their squared norm is the curve-space
    error."""
    gram = data.basis @ data.basis.T
    chol = np.linalg.cholesky(gram + 1e-12 * np.eye(gram.shape[0]))
    return np.asarray(cz.signature_coefficients(data) @ chol)


def instrument_centred(coef: NDArray[np.float64], inst_codes: NDArray[np.int64]
                        ) -> NDArray[np.float64]:
    """Residuals of the per-instrument mean fit of the shape coefficients (n, 3)."""
    out = np.array(coef, dtype=float)
    for i in np.unique(inst_codes):
        out[inst_codes == i] -= out[inst_codes == i].mean(axis=0)
    return out


def noise_whitened(coef: NDArray[np.float64], inst_codes: NDArray[np.int64],
                    wheel: NDArray[Any], rows: NDArray[np.bool_] | None = None
                    ) -> NDArray[np.float64]:
    """Shape coefficients (n, 3) in the metric of their nuisance: times L^-T, where L L^T is
    the covariance of the wheels' mean coefficients about their instrument's mean.

    An instrument's signature is constant over a wheel's measurements, so what it must stand
    out against is the wheel-to-wheel scatter of the mean signature (the wheel's own
    as-turned shape, vehicle effects, averaged measurement noise). That scatter is strongly
    correlated between the three basis directions (the flange offset and the lateral shift
    share z' on the flange), so a sum of squares in curve space spends most of its weight on
    noise directions; in the metric of its inverse covariance (a generalised least-squares,
    Hotelling-type contrast) every direction carries equal nuisance. The transform is fixed
    before the test and applied to the data and to every resampled dataset alike, so the
    resampling p-value keeps its level.

    ``rows``: the rows the test uses (``causes_route.signature_rows``); when they are the
    within-life contrasts (each life's own level removed, ``finder_shape_growth``), a
    wheel's mean carries no nuisance left and the scatter is the rows' own.
    """
    keep = np.ones(len(inst_codes), dtype=bool) if rows is None else np.asarray(rows, bool)
    c = instrument_centred(np.asarray(coef, dtype=float)[keep], inst_codes[keep])
    w = fs.codes_of(np.asarray(wheel)[keep] if keep.all() else np.arange(int(keep.sum())))
    g = int(w.max()) + 1
    sums = np.zeros((g, c.shape[1]))
    np.add.at(sums, w, c)
    means = sums / np.bincount(w, minlength=g)[:, None]
    cov = np.atleast_2d(np.cov(means.T)) if g > 1 else np.eye(c.shape[1])
    ridge = 1e-9 * max(float(np.trace(cov)), 1e-300)
    chol = np.linalg.cholesky(cov + ridge * np.eye(c.shape[1]))
    return np.asarray(np.linalg.solve(chol, np.asarray(coef, dtype=float).T).T)


def sessions(frame: pd.DataFrame, instrument: NDArray[Any]) -> NDArray[Any]:
    """(n,) measurement session of each row: its instrument and its day (``measured_on``;
    the instrument alone without dates)."""
    inst = np.asarray(instrument).astype(str)
    if "measured_on" not in frame.columns:
        return inst
    day = pd.to_datetime(frame["measured_on"]).dt.strftime("%Y-%m-%d").to_numpy().astype(str)
    return np.char.add(np.char.add(inst, "|"), day)


def within_life_p(data: cz.FinderData, coef: NDArray[np.float64], inst: NDArray[Any],
                   wheel: NDArray[Any], folds: NDArray[np.int64], n_null: int,
                   rng: np.random.Generator) -> tuple[float, NDArray[np.float64]] | None:
    """Observed held-out gain and its resampled null gains (B,) of the instrument signature
    tested on the contrasts inside the wheel lives measured by more than one instrument
    (``finder_shape_growth.within_life_contrasts``), or None when the data hold too few
    such lives. ``diagnose`` adjusts it over the catalogue like the between-wheel test.

    The between-wheel test of the per-instrument means takes a shape level shared by the
    wheels of a unit measured by one instrument for the instrument's; inside one life every
    wheel, vehicle and unit level cancels. The same statistic as the between-wheel test
    (held-out gain of per-instrument means in the nuisance metric, precision weights, rows
    outside the mixed lives with weight 0); the nuisance is resampled by measurement session
    (one instrument on one day, ``sessions``: the wheels a unit's visit measured share its
    point of wear and its conditions) and by wheel.
    """
    mixed, within = fsg.within_life_contrasts(
        coef, cz.life_ids(data.frame, data.mileage_km), np.asarray(inst).astype(str))
    if mixed is None:
        return None
    codes = fs.codes_of(inst)
    z = noise_whitened(within, codes, wheel, mixed)
    centred = instrument_centred(z, codes)
    w = np.zeros(data.n)
    w[mixed] = fsw.shape_weights(centred[mixed], data.base.sum(axis=1)[mixed])
    gain = fs.relative_gain(w * np.sum(fs.held_out_shape(z, None, folds, w) ** 2, axis=1),
                     w * np.sum(fs.held_out_shape(z, inst, folds, w) ** 2, axis=1))
    sw = np.sqrt(w)[:, None] * np.ones_like(z)
    nm = fs.NuisanceModel.fit(sw * centred, sw, sessions(data.frame, inst), wheel)
    draws = nm.draws(n_null, rng, used_dof=int(codes.max()))
    sw_flat = sw.reshape(-1)[:, None]
    boot = fs.bootstrap_gains(sw_flat * shape_design(data.n, None),
                              [sw_flat * shape_design(data.n, inst)], draws, np.repeat(folds, 3))
    return gain, boot[0]


def shape_design(n: int, instrument: NDArray[Any] | None) -> NDArray[np.float64]:
    codes = np.zeros(n, dtype=np.int64) if instrument is None else fs.codes_of(instrument)
    levels = int(codes.max()) + 1
    d = np.zeros((n, 3, levels * 3))
    for j in range(3):
        d[np.arange(n), j, codes * 3 + j] = 1.0
    return d.reshape(n * 3, levels * 3)
