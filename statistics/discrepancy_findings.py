"""The discrepancy finder's findings: one per scored cause, with its held-out gain and 95 %
bootstrap interval over the groups, its p-values, fitted parameters and intervals, the
subgroup it acts on, the causes it is confounded with, and the extension it would add.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from wearcast.statistics import causes as cz
from wearcast.statistics import finder_scoring as fs
from wearcast.statistics.findings import Finding, Gain, bootstrap_gain_interval
from wearcast.statistics.residuals import residual_structure


@dataclass
class Scored:
    """One cause scored at one step of the forward selection."""

    cause: cz.Cause
    before: NDArray[np.float64]            # (n,) held-out error of the step's baseline
    after: NDArray[np.float64]             # (n,) held-out error with the cause added
    gain: float
    p_raw: float = 1.0
    p_adj: float = 1.0
    step: int = 0
    metric: str = "area"


def _gain_interval(s: Scored, groups: NDArray[Any], n_boot: int,
                   rng: np.random.Generator) -> tuple[float, float]:
    return bootstrap_gain_interval(fs.group_sums(s.before, groups),
                                   fs.group_sums(s.after, groups), n_boot, rng)


def is_named(s: Scored, alpha: float, min_gain: float, groups: NDArray[Any], n_boot: int,
             rng: np.random.Generator) -> bool:
    return bool(s.p_adj <= alpha and s.gain >= min_gain)   # resampling p: reject at <= alpha


_SUBGROUPS = {
    "traction": "tread of motor bogies vs other bogies",
    "running_direction": "axle 1 vs axle 2 per running mode",
    "curve_asymmetry": "left vs right wheels per curved route",
    "flange_lubrication": "flanges on lubricated vs dry routes",
    "wear_measure": "all wheel positions (ratio of the two measures)",
    "nonlinear_progression": "mileage since reprofiling",
    "seasonal_friction": "season of the running intervals",
    "vehicle_load": "vehicles by load_t",
    "profile_misalignment": "wear curves per instrument_id",
}


def scored_findings(data: cz.FinderData, scored: Mapping[str, Scored], selected: Sequence[cz.Cause],
                    names: Sequence[str], vehicle: NDArray[Any], chosen: Sequence[cz.Cause],
                    n_boot: int, groups: NDArray[Any], alpha: float, min_gain: float,
                    rng: np.random.Generator) -> list[Finding]:
    everything = np.ones(data.n, dtype=bool)
    joint: dict[str, cz.Cause] = {}
    if selected:
        comp = cz.Composite(tuple(selected)).fit(data, everything, cluster=vehicle)
        assert isinstance(comp, cz.Composite)
        joint = {m.code: m for m in comp.members}
    calibrated = float(np.sum(data.e ** 2) / data.n)
    out = []
    for code, s in scored.items():
        est = joint.get(code) or s.cause.fit(data, everything, cluster=vehicle)
        lo, hi = _gain_interval(s, groups, n_boot, rng)
        n = data.n
        gain = Gain(before_error=float(s.before.sum() / n), after_error=float(s.after.sum() / n),
                    relative=s.gain, ci95_low=lo, ci95_high=hi, calibrated_error=calibrated,
                    metric="wear_curve_shape" if s.metric == "shape" else "log_area")
        params = est.public()
        if code == "wear_measure":
            w = est.intervals().get("share_other_measure") if hasattr(est, "intervals") \
                else None
            if w is not None and w["ci95_low"] <= 1.0 <= w["ci95_high"]:
                params.update(c_s_flange=float(data.c_s[0] * np.exp(est.log_scale_[0])),
                              c_s_tread=float(data.c_s[1] * np.exp(est.log_scale_[1])))
        intervals = est.intervals()
        evidence: dict[str, Any] = {
            "p_value": s.p_adj, "p_value_raw": s.p_raw,
            "test": ("held-out gain against resampled nuisance-only datasets, "
                     "Westfall-Young max-T across the catalogue"
                     + (f" (forward-selection step {s.step + 1}: baseline includes "
                        f"{', '.join(c.code for c in selected[:s.step])})" if s.step else "")),
            "effect_size": params.get("instruments", params) if code == "profile_misalignment"
            else params,
            "intervals": intervals,
            "subgroup": _SUBGROUPS.get(code, ""),
            "interval": {"relative_gain_ci95": [lo, hi]},
            "confounded_with": _confounded(s.cause, chosen, data),
            "step": s.step + 1,
        }
        if s.metric != "shape" and s.cause.covariate_name in data.frame.columns \
                and data.frame[s.cause.covariate_name].nunique() <= 20:
            evidence["residual_by_level"] = residual_structure(
                data.frame, s.cause.covariate_name).to_dict(orient="records")
        extension = {"cause": code, "parameters": params,
                     "log_scale": {"flange": float(est.log_scale_[0]),
                                   "tread": float(est.log_scale_[1])},
                     "intervals": intervals,
                     "explanation": s.cause.explanation, "needs": list(s.cause.needs)}
        ci = "; ".join(f"{k} {v['value']:.3g} [{v['ci95_low']:.3g}, {v['ci95_high']:.3g}]"
                       for k, v in intervals.items() if math.isfinite(v["ci95_low"]))
        summary = (f"{est.describe()}; held-out error "
                   f"{'down' if s.gain >= 0 else 'up'} {100 * abs(s.gain):.1f} % "
                   f"(95 % CI {100 * lo:.1f} to {100 * hi:.1f} %)"
                   + (f"; 95 % intervals: {ci}" if ci else ""))
        significant = bool(s.p_adj <= alpha)
        material = bool(s.gain >= min_gain)
        out.append(Finding(code, summary, evidence, extension, gain, significant and
                           (code in names or not names), material))
    return out


def _numeric(values: NDArray[Any]) -> NDArray[np.float64]:
    v = pd.to_numeric(pd.Series(values), errors="coerce")
    if v.notna().all():
        return np.asarray(v.to_numpy(dtype=float))
    return pd.factorize(pd.Series(values).astype(str))[0].astype(float)


def covariate_codes(cause: cz.Cause, data: cz.FinderData) -> NDArray[np.float64]:
    key = f"covariate_codes:{cause.code}"
    if key not in data.cache:
        data.cache[key] = _numeric(np.asarray(cause.covariate(data)))
    return np.asarray(data.cache[key])


def _confounded(cause: cz.Cause, chosen: Sequence[cz.Cause], data: cz.FinderData) -> list[str]:
    """Other scored causes whose covariate is nearly collinear with this one's (|r| > 0.9)."""
    x = covariate_codes(cause, data)
    if np.std(x) == 0:
        return []
    out = []
    for other in chosen:
        if other.code == cause.code or f"covariate_codes:{other.code}" not in data.cache:
            continue
        y = covariate_codes(other, data)
        if np.std(y) > 0 and abs(np.corrcoef(x, y)[0, 1]) > 0.9:
            out.append(other.code)
    return out
