"""Residual structure outside the discrepancy finder's catalogue (issue 13 §6).

When no catalogue cause explains the baseline's residuals, the finder says where they are
structured instead of answering ``none``: by wheel position, route, calendar quarter, mileage
quintile or instrument (``structure_factors``), each grouping's share of the residual sum of
squares (``structure_share``) tested against the same share on nuisance-only resamples of the
fitted baseline (``finder_scoring.NuisanceModel``, wild cluster bootstrap) with the max-T
adjustment over the groupings (``finder_scoring.min_p``, Westfall & Young 1993), and reported
with each level's rate change (``level_effects``).

Pure numpy/pandas.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics import causes as cz
from wearcast.statistics.finder_scoring import NuisanceModel, codes_of, min_p

Array = NDArray[np.float64]

def structure_factors(frame: pd.DataFrame, mileage_km: Array,
                      min_rows: int = 8) -> dict[str, NDArray[Any]]:
    """Candidate groupings of the residuals: wheel position, route, calendar quarter,
    mileage quintile, instrument (each with at least two levels of ``min_rows`` rows)."""
    out: dict[str, NDArray[Any]] = {}
    pos_cols = [c for c in ("bogie_type", "axle", "side") if c in frame.columns]
    if pos_cols:
        out["wheel_position"] = frame[pos_cols].astype(str).agg("/".join, axis=1).to_numpy()
    rcol = "route" if "route" in frame.columns else "route_id" if "route_id" in frame.columns \
        else None
    if rcol:
        out["route"] = frame[rcol].astype(str).to_numpy()
    if "measured_on" in frame.columns:
        d = pd.to_datetime(frame["measured_on"], errors="coerce")
        if d.notna().all():
            out["date_quarter"] = ("Q" + d.dt.quarter.astype(str)).to_numpy()
    s = pd.Series(mileage_km)
    if s.nunique() >= 5:
        out["mileage"] = pd.qcut(s.rank(method="first"), 5, labels=False).astype(str).to_numpy()
    if "instrument_id" in frame.columns:
        out["instrument"] = frame["instrument_id"].astype(str).to_numpy()
    keep = {}
    for name, values in out.items():
        counts = pd.Series(values).value_counts()
        if (counts >= min_rows).sum() >= 2:
            keep[name] = values
    return keep


def structure_scan(data: cz.FinderData, residual: NDArray[np.float64], vehicle: NDArray[Any],
               wheel: NDArray[Any], n_null: int, rng: np.random.Generator, alpha: float,
               min_share: float) -> list[dict[str, Any]]:
    """Residual structure outside the catalogue: the share of the baseline residual explained
    by each ``structure_factors`` grouping against the same share on nuisance-only resamples
    (max-T adjusted), kept when significant and material, largest first."""
    factors = structure_factors(data.frame, data.mileage_km)
    if not factors:
        return []
    sw = np.sqrt(data.weights)
    nm = NuisanceModel.fit(sw * residual, sw * data.phi, vehicle, wheel)
    draws = nm.draws(n_null, rng).reshape(data.n, 2, n_null)
    names = list(factors)
    observed = np.array([float(structure_share(sw * residual, sw * data.phi,
                                                  factors[f])[0]) for f in names])
    null = np.vstack([structure_share(draws, sw * data.phi, factors[f]) for f in names])
    p_raw, p_adj = min_p(observed, null)
    out: list[dict[str, Any]] = []
    for i, name in enumerate(names):
        excess = float(observed[i] - np.median(null[i]))
        if p_adj[i] <= alpha and excess >= min_share:   # resampling p: reject at <= alpha
            out.append({"by": name, "share_of_residual": float(observed[i]),
                        "share_beyond_null": excess, "p_value": float(p_adj[i]),
                        "levels": level_effects(residual, data.phi, factors[name],
                                                   REGIONS)})
    out.sort(key=lambda u: -u["share_beyond_null"])
    return out


def structure_share(residual: Array, weight: Array, factor: NDArray[Any]) -> Array:
    """Share of the residual sum of squares explained by per-level means, per column of a
    (n, m, B) or (n, m) residual (weighted least squares by level)."""
    r = residual if residual.ndim == 3 else residual[:, :, None]
    c = codes_of(factor)
    g = int(c.max()) + 1
    w = weight[:, :, None]
    num = np.zeros((g,) + r.shape[1:])
    den = np.zeros((g, r.shape[1], 1))
    np.add.at(num, c, w * r)
    np.add.at(den, c, w * w)
    explained = np.sum(num * num / np.where(den > 0, den, np.inf), axis=(0, 1))
    total = np.sum(r * r, axis=(0, 1))
    return np.asarray(explained / np.maximum(total, 1e-300))


def level_effects(residual: Array, weight: Array, factor: NDArray[Any],
                  columns: Sequence[str]) -> list[dict[str, Any]]:
    """Per level: rows and the mean log-rate deviation per column as a percentage."""
    out = []
    for lev in sorted({str(v) for v in factor}):
        sel = np.asarray(factor).astype(str) == lev
        row: dict[str, Any] = {"level": lev, "n": int(sel.sum())}
        for j, col in enumerate(columns):
            den = float(np.sum(weight[sel, j] ** 2))
            u = float(np.sum(weight[sel, j] * residual[sel, j]) / den) if den > 0 else 0.0
            row[f"{col}_rate_change_pct"] = 100.0 * float(np.expm1(u))
        out.append(row)
    return out
