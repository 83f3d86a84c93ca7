"""Reprofiling mileage from the hybrid model (docs/conventions.md "The hybrid model" 7).

The wheel's region areas grow as A_r(s) = A_r,0 + k_r s (seed 001 eq. 4, k_r = c_s,r P_s,r);
the wear states turn areas into a worn profile, whose Sd, Sh and qR are compared with the
limits (Sd >= 22, Sh <= 36, qR >= 6.5 mm by default). The reprofiling mileage is the first
mileage at which any limit is crossed: bracketed on a geometric mileage grid, the bracket
refined on finer grids to max(0.1 % of the mileage, 50 km) and the crossing interpolated in
it (``_first_crossings``). The three rate quantiles are evaluated together: every step is one
vectorised batch of worn profiles and flange parameters, not a scalar root finder.

P10/P50/P90 come from the rate uncertainty of the calibration: the P10 mileage uses the
high (90 %) rates, the P90 mileage the low (10 %) rates. When the wheel starts from a
measured state, ``start_areas`` gives its measured areas; the remaining mileage counts from
there (the wheel's equivalent mileage per region is A_r,0 / k_r).

Starting from what was measured (``start_parameters``): a wheel whose measured Sd, Sh or qR
is already past a limit has 0 km remaining, and the answer names the crossed limits and by
how much. Otherwise the model's parameters are followed from the measured ones: the model
gives how Sd/Sh/qR *change* from the start areas, the measured values give where they start
(P(s) = P_measured + P_model(A_0 + k s) - P_model(A_0)); the limits are crossed when that
sum crosses them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
import pandas as pd

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics.hybrid import HybridModel
from wearcast.statistics.hybrid_prediction import region_rates
from wearcast.statistics.hybrid_prediction import start_areas as start_areas_of
from wearcast.statistics.hybrid_profiles import parameters_at_areas
from wearcast.statistics.json_values import finite_or_none
from wearcast.statistics.profile_parameters import DEFAULT_LIMITS, WheelLimits
from wearcast.statistics.routes import Route
from wearcast.statistics.wear_tables import WearTable

LIMIT_NAMES = ("sd", "sh", "qr")
DEFAULT_HORIZON_KM = 3_000_000.0
#: Mileage tolerance of the reprofiling mileage: the crossing is bracketed to within
#: max(MILEAGE_RTOL · mileage, MILEAGE_ATOL_KM) before the final interpolation.
MILEAGE_RTOL = 1e-3
MILEAGE_ATOL_KM = 50.0


def _margins(params: np.ndarray, limits: WheelLimits) -> np.ndarray:
    """(M, 3) signed margins to the limits [mm]; negative = crossed; NaN parameter = crossed."""
    m = np.column_stack([
        params[:, 0] - limits.sd_min_mm,
        limits.sh_max_mm - params[:, 1],
        params[:, 2] - limits.qr_min_mm,
    ])
    return np.where(np.isfinite(m), m, -np.inf)


def _as_limits(limits: WheelLimits | Mapping[str, float] | None) -> WheelLimits:
    if limits is None:
        return DEFAULT_LIMITS
    if isinstance(limits, WheelLimits):
        return limits
    allowed = {"sd_min_mm", "sh_max_mm", "qr_min_mm"}
    for key, value in limits.items():
        if key not in allowed:
            raise ValueError(f"limits.{key}: unknown limit (allowed: {sorted(allowed)})")
        if value is None or not math.isfinite(float(value)):
            raise ValueError(f"limits.{key}: must be a finite number")
    return WheelLimits(**{k: float(v) for k, v in limits.items()})


_SIGNS = np.array([1.0, -1.0, 1.0])


def _margin_offsets(limits: WheelLimits) -> np.ndarray:
    """Offsets with which ``params · _SIGNS + offsets`` are the margins of :func:`_margins`."""
    return np.array([-limits.sd_min_mm, limits.sh_max_mm, -limits.qr_min_mm])


@lru_cache(maxsize=16)
def _search_grid(horizon_km: float, n_grid: int) -> np.ndarray:
    """0 and the geometric grid horizon/1e5 ... horizon (``n_grid`` points) [km], read-only."""
    grid = np.concatenate([[0.0], np.geomspace(horizon_km / 1e5, horizon_km, n_grid)])
    grid.setflags(write=False)
    return grid


@dataclass(frozen=True)
class LimitCrossing:
    """First limit crossing for one set of rates."""

    mileage_km: float
    governing_limit: str | None
    sd_mm: float
    sh_mm: float
    qr_mm: float
    extrapolated: bool


def _evaluate(model: HybridModel, start: Mapping[str, float], rates: Mapping[str, np.ndarray],
              limits: WheelLimits, s_km: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Parameters (Q, n, 3), margins (Q, n, 3) and extrapolation flags (Q, n) at mileages
    ``s_km`` (Q, n), row q grown with the rates ``rates[region][q]`` [mm²/km] — one batch."""
    q, n = s_km.shape
    flange = (start["flange"] + rates["flange"][:, None] * s_km).reshape(-1)
    tread = (start["tread"] + rates["tread"][:, None] * s_km).reshape(-1)
    params, extra = parameters_at_areas(model, flange, tread)
    margins = params * _SIGNS + _margin_offsets(limits)
    margins[~np.isfinite(margins)] = -np.inf  # an undefined parameter counts as crossed
    return params.reshape(q, n, 3), margins.reshape(q, n, 3), extra.reshape(q, n)


def _params_from_margins(margins: np.ndarray, limits: WheelLimits) -> np.ndarray:
    """Sd, Sh, qR [mm] back from their margins (..., 3) (inverse of :func:`_margins`)."""
    params = np.stack([margins[..., 0] + limits.sd_min_mm, limits.sh_max_mm - margins[..., 1],
                       margins[..., 2] + limits.qr_min_mm], axis=-1)
    return np.where(np.isfinite(margins), params, np.nan)


@dataclass
class _Bracket:
    """The bracket [lo, hi] [km] of one rate set's first crossing: margins (3,) [mm] and
    extrapolation flags at both ends (all margins >= 0 at lo, some < 0 at hi)."""

    lo: float
    hi: float
    m_lo: np.ndarray
    m_hi: np.ndarray
    e_lo: bool
    e_hi: bool


#: First-guess search on the model's parameter surface: points of its geometric grid.
SURFACE_GRID_POINTS = 96
#: Half-width of the exact bracket around a surface estimate, relative to the estimate.
SURFACE_BRACKET_RTOL = 0.0075


def _surface_estimates(model: HybridModel, start: Mapping[str, float],
                       rates: Mapping[str, np.ndarray], limits: WheelLimits,
                       horizon_km: float) -> np.ndarray:
    """First-crossing mileage estimates (Q,) [km] from the bilinear parameter surface
    (:attr:`HybridModel.parameter_surface`); NaN where the surface gives none inside the
    horizon (no crossing, crossed at the start, or the path leaves the surface first).

    The smallest interpolated margin on the geometric grid 0, horizon/1e5 ... horizon
    (``SURFACE_GRID_POINTS`` points) brackets its first crossing, which is interpolated
    linearly. Pure numpy on the surface: no profile is evaluated.
    """
    n_q = rates["flange"].size
    grid = _search_grid(float(horizon_km), SURFACE_GRID_POINTS)
    fa = (start["flange"] + rates["flange"][:, None] * grid).reshape(-1)
    ta = (start["tread"] + rates["tread"][:, None] * grid).reshape(-1)
    params, inside = model.parameter_surface.at(fa, ta)
    worst = (params * _SIGNS + _margin_offsets(limits)).min(axis=1).reshape(n_q, -1)
    crossed = worst < 0
    j = crossed.argmax(axis=1)
    rows = np.arange(n_q)
    # a crossing after the start, on the surface (areas grow: then so is all before it)
    ok = crossed[rows, j] & (j > 0) & inside.reshape(n_q, -1)[rows, j]
    j = np.maximum(j, 1)
    m0, m1 = worst[rows, j - 1], worst[rows, j]
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.clip(m0 / (m0 - m1), 0.0, 1.0)
    s0, s1 = grid[j - 1], grid[j]
    return np.where(ok, s0 + frac * (s1 - s0), np.nan)


def _grid_outcome(q: int, s_row: np.ndarray, params: np.ndarray, margins: np.ndarray,
                  extra: np.ndarray, any_crossed: bool, j: int,
                  out: list[LimitCrossing | None], brackets: dict[int, _Bracket]) -> None:
    """Row q of mileages ``s_row`` [km] whose first crossed point is j (``any_crossed``):
    no crossing, crossed at the first point (0 km on a grid from 0), or a bracket."""
    nan = float("nan")
    if not any_crossed:
        out[q] = LimitCrossing(math.inf, None, nan, nan, nan, bool(extra.any()))
    elif j == 0:
        sd_mm, sh_mm, qr_mm = (float(v) for v in params[0])
        out[q] = LimitCrossing(0.0, LIMIT_NAMES[int(np.argmin(margins[0]))],
                               sd_mm, sh_mm, qr_mm, bool(extra[0]))
    else:
        brackets[q] = _Bracket(float(s_row[j - 1]), float(s_row[j]), margins[j - 1],
                               margins[j], bool(extra[j - 1]), bool(extra[j]))


def _first_crossings(model: HybridModel, start: Mapping[str, float],
                     rates: Mapping[str, np.ndarray], limits: WheelLimits, horizon_km: float,
                     n_grid: int = 32, n_refine: int = 24, rtol: float = MILEAGE_RTOL,
                     atol_km: float = MILEAGE_ATOL_KM, use_surface: bool = True
                     ) -> list[LimitCrossing]:
    """First limit crossing for each of Q rate sets, all evaluated together.

    0. (``use_surface``) Each rate set's crossing is estimated on the model's bilinear
       parameter surface (:func:`_surface_estimates`, no profile evaluated); a set with an
       estimate s_e gets ``n_grid`` + 1 evenly spaced exact points on
       s_e (1 ± ``SURFACE_BRACKET_RTOL``) instead of the geometric grid of step 1, in the
       same batch. If the exact margins there do not change sign (all >= 0, or some < 0 at
       its first point) the set is searched again from step 1; so every crossing found is
       one of exact margins, bracketed as below.
    1. Worn-profile parameters for every rate set on the geometric mileage grid 0,
       horizon/1e5 ... horizon (``n_grid`` points) in one batch; the first grid point where
       any margin is negative brackets the crossing.
    2. The brackets are refined together, ``n_refine`` evenly spaced points per level and
       one batch per level, until each is no wider than max(``rtol`` · mileage, ``atol_km``)
       (with the surface estimate the exact points are usually that close already).
    3. Within the final bracket each crossed limit's margin is interpolated linearly in
       mileage and the earliest crossing taken (its limit governs); the parameters there are
       interpolated the same way (evaluated anew only where a bracket end has an undefined
       parameter or the extrapolation flag changes inside the bracket).

    The result lies in a bracket no wider than the tolerance around a sign change of the
    smallest exact margin; on smooth margins the interpolation makes it far closer (about
    1e-7 relative to a Brent root on the test models).
    """
    n_q = rates["flange"].size
    grid = _search_grid(float(horizon_km), int(n_grid))
    est = (_surface_estimates(model, start, rates, limits, horizon_km) if use_surface
           else np.full(n_q, np.nan))
    near = np.isfinite(est)
    if near.all():  # points no further apart than the tolerance: usually no refinement
        s_km = est[:, None] * (1.0 + _bracket_offsets(SURFACE_BRACKET_RTOL, rtol))
    else:
        s_km = np.array(np.broadcast_to(grid, (n_q, grid.size)))
        if near.any():
            t = np.linspace(-SURFACE_BRACKET_RTOL, SURFACE_BRACKET_RTOL, grid.size)
            s_km[near] = est[near, None] * (1.0 + t)
    np.minimum(s_km, horizon_km, out=s_km)
    params, margins, extra = _evaluate(model, start, rates, limits, s_km)
    crossed = margins.min(axis=2) < 0
    any_crossed = crossed.any(axis=1).tolist()
    first = crossed.argmax(axis=1).tolist()
    out: list[LimitCrossing | None] = [None] * n_q
    brackets: dict[int, _Bracket] = {}
    again: list[int] = []
    near_rows = near.tolist()
    for q in range(n_q):
        j = first[q]
        if near_rows[q] and j == 0:  # nothing crossed near the estimate, or before it
            again.append(q)
        else:
            _grid_outcome(q, s_km[q], params[q], margins[q], extra[q], any_crossed[q], j, out,
                          brackets)
    if again:
        params, margins, extra = _evaluate(model, start, _subset(rates, again), limits,
                                           np.broadcast_to(grid, (len(again), grid.size)))
        crossed = margins.min(axis=2) < 0
        for a, q in enumerate(again):
            _grid_outcome(q, grid, params[a], margins[a], extra[a], bool(crossed[a].any()),
                          int(crossed[a].argmax()), out, brackets)
    if brackets:
        _refine(model, start, rates, limits, brackets, n_refine, rtol, atol_km)
        for q, crossing in _crossings_in(model, start, rates, limits, brackets).items():
            out[q] = crossing
    return [o for o in out if o is not None]


@lru_cache(maxsize=8)
def _bracket_offsets(half_width: float, rtol: float) -> np.ndarray:
    """Relative offsets -half_width ... half_width of the exact points around a surface
    estimate, evenly spaced and no further apart than ``rtol`` times the lowest point
    (so that a bracket between two of them needs no refinement), read-only."""
    n = math.ceil(2 * half_width / (rtol * (1 - half_width))) + 1
    t = np.linspace(-half_width, half_width, n)
    t.setflags(write=False)
    return t


def _subset(rates: Mapping[str, np.ndarray], rows: list[int]) -> dict[str, np.ndarray]:
    return {r: rates[r][rows] for r in REGIONS}


def _refine(model: HybridModel, start: Mapping[str, float], rates: Mapping[str, np.ndarray],
            limits: WheelLimits, brackets: dict[int, _Bracket], n_refine: int, rtol: float,
            atol_km: float) -> None:
    """Shrink the brackets (by rate-set row) of the first crossing in place until no wider
    than max(rtol · hi, atol_km): one batch per level, each shrinking (n_refine + 1)-fold."""
    t = np.arange(1, n_refine + 1) / (n_refine + 1)
    for _ in range(64):
        rows = [q for q, b in brackets.items() if b.hi - b.lo > max(rtol * b.hi, atol_km)]
        if not rows:
            return
        lo = np.array([brackets[q].lo for q in rows])
        hi = np.array([brackets[q].hi for q in rows])
        s_new = lo[:, None] + t[None, :] * (hi - lo)[:, None]
        _, m_new, e_new = _evaluate(model, start, _subset(rates, rows), limits, s_new)
        hit = m_new.min(axis=2) < 0
        any_hit = hit.any(axis=1).tolist()
        k_hit = hit.argmax(axis=1).tolist()
        for a, q in enumerate(rows):
            b = brackets[q]
            k = k_hit[a] if any_hit[a] else n_refine  # n_refine: the old hi
            if k < n_refine:
                b.hi, b.m_hi, b.e_hi = float(s_new[a, k]), m_new[a, k], bool(e_new[a, k])
            if k > 0:
                b.lo, b.m_lo, b.e_lo = (float(s_new[a, k - 1]), m_new[a, k - 1],
                                        bool(e_new[a, k - 1]))


def _crossings_in(model: HybridModel, start: Mapping[str, float],
                  rates: Mapping[str, np.ndarray], limits: WheelLimits,
                  brackets: dict[int, _Bracket]) -> dict[int, LimitCrossing]:
    """The first crossing inside each final bracket (step 3 of :func:`_first_crossings`)."""
    found: dict[int, tuple[float, int, Any, bool]] = {}
    again: list[int] = []
    for q, b in brackets.items():
        m_lo, m_hi = b.m_lo.tolist(), b.m_hi.tolist()
        s_limit = [math.inf] * 3
        for i in range(3):
            if m_hi[i] < 0:  # crossed at hi
                if math.isfinite(m_lo[i]) and math.isfinite(m_hi[i]):
                    frac = min(max(m_lo[i] / (m_lo[i] - m_hi[i]), 0.0), 1.0)
                else:  # a limit whose parameter vanishes (margin -inf) at hi crosses there
                    frac = 1.0
                s_limit[i] = b.lo + frac * (b.hi - b.lo)
        limit = s_limit.index(min(s_limit))
        root = s_limit[limit]
        w = (root - b.lo) / (b.hi - b.lo) if b.hi > b.lo else 1.0
        m_root = [lo_i + w * (hi_i - lo_i) for lo_i, hi_i in zip(m_lo, m_hi, strict=True)]
        params = [m_root[0] + limits.sd_min_mm, limits.sh_max_mm - m_root[1],
                  m_root[2] + limits.qr_min_mm]  # as _params_from_margins, on floats
        params = [v if math.isfinite(m) else math.nan
                  for v, m in zip(params, m_root, strict=True)]
        found[q] = (root, limit, params, b.e_hi)
        if b.e_lo != b.e_hi or not all(map(math.isfinite, m_lo + m_hi)):
            again.append(q)
    if again:
        roots = np.array([[found[q][0]] for q in again])
        p_root, _, e_root = _evaluate(model, start, _subset(rates, again), limits, roots)
        for a, q in enumerate(again):
            found[q] = (found[q][0], found[q][1], p_root[a, 0], bool(e_root[a, 0]))
    out: dict[int, LimitCrossing] = {}
    for q, (root, limit, params, extra) in found.items():
        sd_mm, sh_mm, qr_mm = (float(v) for v in params)
        out[q] = LimitCrossing(root, LIMIT_NAMES[limit], sd_mm, sh_mm, qr_mm, extra)
    return out


@dataclass(frozen=True)
class ReprofilingResult:
    """When a wheel reaches a limit (mileages in km from its start state; inf = not reached).

    ``mileage_p10_km`` is the early (high-rate) estimate, ``mileage_p90_km`` the late one.
    The governing limit and the parameter values are those of the median (P50) crossing.
    """

    mileage_p10_km: float
    mileage_p50_km: float
    mileage_p90_km: float
    governing_limit: str | None
    sd_mm: float
    sh_mm: float
    qr_mm: float
    extrapolated: bool
    reason: str | None
    rates_mm2_per_km: dict[str, float] = field(default_factory=dict)
    equivalent_mileage_km: dict[str, float] = field(default_factory=dict)
    limits: dict[str, float] = field(default_factory=dict)
    #: limits the measured start state is already past, and by how much [mm] (> 0)
    crossed_limits: dict[str, float] = field(default_factory=dict)
    #: measured Sd/Sh/qR the prediction started from [mm] (empty: the model's own)
    start_parameters: dict[str, float] = field(default_factory=dict)

    @property
    def reached(self) -> bool:
        return math.isfinite(self.mileage_p50_km)

    def to_dict(self) -> dict[str, Any]:
        return {
            "mileage_p10_km": finite_or_none(self.mileage_p10_km),
            "mileage_p50_km": finite_or_none(self.mileage_p50_km),
            "mileage_p90_km": finite_or_none(self.mileage_p90_km),
            "governing_limit": self.governing_limit,
            "sd_mm": finite_or_none(self.sd_mm),
            "sh_mm": finite_or_none(self.sh_mm),
            "qr_mm": finite_or_none(self.qr_mm),
            "extrapolated": self.extrapolated,
            "reason": self.reason,
            "rates_mm2_per_km": {k: finite_or_none(v) for k, v in self.rates_mm2_per_km.items()},
            "equivalent_mileage_km": {k: finite_or_none(v)
                                      for k, v in self.equivalent_mileage_km.items()},
            "limits": dict(self.limits),
            "crossed_limits": dict(self.crossed_limits),
            "start_parameters": dict(self.start_parameters),
        }


def reprofiling_mileage(
    model: HybridModel,
    route: Route,
    table: pd.DataFrame | WearTable,
    *,
    bogie_type: str,
    axle: int,
    side: str,
    limits: WheelLimits | Mapping[str, float] | None = DEFAULT_LIMITS,
    start_areas: Mapping[str, float] | None = None,
    horizon_km: float = DEFAULT_HORIZON_KM,
    n_grid: int = 32,
    weighted_measures: Mapping[str, float] | None = None,
    start_parameters: Mapping[str, float] | None = None,
) -> ReprofilingResult:
    """First mileage at which Sd, Sh or qR crosses its limit, as P10/P50/P90.

    Parameters
    ----------
    model, route, table : calibrated hybrid model, the route and the curve-radius table
    bogie_type, axle (1|2), side ('left'|'right') : the wheel's position
    limits : WheelLimits or a mapping with ``sd_min_mm``, ``sh_max_mm``, ``qr_min_mm`` [mm]
    start_areas : measured areas {'flange', 'tread'} [mm²] of the wheel's latest measurement
        (default: new profile)
    horizon_km : search horizon [km]; beyond it the limit counts as not reached
    n_grid : points of the geometric search grid before the refinement
    weighted_measures : P_s per region if known already (see ``hybrid_prediction.region_rates``)
    start_parameters : measured ``sd_mm``, ``sh_mm``, ``qr_mm`` [mm] of the start state; the
        prediction starts from them (module docstring); past a limit: 0 km remaining

    Returns
    -------
    ReprofilingResult; mileages are inf with a ``reason`` when no limit is reached within the
    horizon (e.g. tangent track where the flange does not wear and the tread alone never
    crosses a limit).
    """
    lim = _as_limits(limits)
    if not (math.isfinite(horizon_km) and horizon_km > 0):
        raise ValueError("horizon_km: must be finite and > 0")
    start = start_areas_of(start_areas, "start_areas")
    measured = _measured_start(start_parameters)
    if measured:
        crossed = crossed_limits(measured, lim)
        if crossed:
            return _already_crossed(measured, crossed, lim, start)
        p0, _ = parameters_at_areas(model, np.array([start["flange"]]),
                                    np.array([start["tread"]]))
        offset = np.array([measured["sd_mm"], measured["sh_mm"], measured["qr_mm"]]) - p0[0]
        if not np.all(np.isfinite(offset)):
            raise ValueError("start_areas: the model gives no Sd/Sh/qR at the start areas")
        search_limits = WheelLimits(sd_min_mm=lim.sd_min_mm - float(offset[0]),
                                    sh_max_mm=lim.sh_max_mm - float(offset[1]),
                                    qr_min_mm=lim.qr_min_mm - float(offset[2]))
    else:
        offset = np.zeros(3)
        search_limits = lim
    _, rates = region_rates(model, route, table, bogie_type=bogie_type, axle=axle, side=side,
                            quantiles=(0.9, 0.5, 0.1), weighted_measures=weighted_measures)
    crossings = _first_crossings(model, start, rates, search_limits, horizon_km, n_grid)
    median = crossings[1]
    reason = None
    if not math.isfinite(median.mileage_km):
        if rates["flange"][1] == 0 and rates["tread"][1] == 0:
            reason = "the route gives zero wear rate in both regions"
        else:
            reason = f"no limit is crossed within the horizon of {horizon_km:g} km"
    elif median.mileage_km == 0.0:
        reason = "a limit is already crossed at the start state"
    equivalent: dict[str, float] = {
        r: (start[r] / float(rates[r][1]) if rates[r][1] > 0 else (0.0 if start[r] == 0
                                                                  else math.inf))
        for r in REGIONS
    }
    return ReprofilingResult(
        mileage_p10_km=crossings[0].mileage_km,
        mileage_p50_km=median.mileage_km,
        mileage_p90_km=crossings[2].mileage_km,
        governing_limit=median.governing_limit,
        sd_mm=median.sd_mm + float(offset[0]),
        sh_mm=median.sh_mm + float(offset[1]),
        qr_mm=median.qr_mm + float(offset[2]),
        extrapolated=median.extrapolated,
        reason=reason,
        rates_mm2_per_km={r: float(rates[r][1]) for r in REGIONS},
        equivalent_mileage_km=equivalent,
        limits=_limit_dict(lim),
        start_parameters=measured,
    )


def _limit_dict(lim: WheelLimits) -> dict[str, float]:
    return {"sd_min_mm": lim.sd_min_mm, "sh_max_mm": lim.sh_max_mm, "qr_min_mm": lim.qr_min_mm}


def _measured_start(parameters: Mapping[str, float] | None) -> dict[str, float]:
    if parameters is None:
        return {}
    out = {}
    for key in ("sd_mm", "sh_mm", "qr_mm"):
        value = parameters.get(key)
        if value is None or not math.isfinite(float(value)):
            raise ValueError(f"start_parameters.{key}: must be a finite number [mm]")
        out[key] = float(value)
    return out


def crossed_limits(parameters: Mapping[str, float], limits: WheelLimits) -> dict[str, float]:
    """Limits that measured Sd/Sh/qR [mm] are past, with the exceedance [mm] (> 0)."""
    excess = {"sd": limits.sd_min_mm - parameters["sd_mm"],
              "sh": parameters["sh_mm"] - limits.sh_max_mm,
              "qr": limits.qr_min_mm - parameters["qr_mm"]}
    return {name: float(v) for name, v in excess.items() if v > 0.0}


def _already_crossed(measured: dict[str, float], crossed: dict[str, float],
                     lim: WheelLimits, start: Mapping[str, float]) -> ReprofilingResult:
    """The answer for a wheel measured past a limit: 0 km, which limits, by how much."""
    governing = max(crossed, key=lambda name: crossed[name])
    text = {"sd": ("Sd", "sd_mm", "<", lim.sd_min_mm), "sh": ("Sh", "sh_mm", ">", lim.sh_max_mm),
            "qr": ("qR", "qr_mm", "<", lim.qr_min_mm)}
    parts = [f"{text[n][0]} {measured[text[n][1]]:.2f} mm {text[n][2]} {text[n][3]:g} mm by "
             f"{crossed[n]:.2f} mm" for n in crossed]
    return ReprofilingResult(
        mileage_p10_km=0.0, mileage_p50_km=0.0, mileage_p90_km=0.0,
        governing_limit=governing, sd_mm=measured["sd_mm"], sh_mm=measured["sh_mm"],
        qr_mm=measured["qr_mm"], extrapolated=False,
        reason="the measured wheel is already past its limit(s): " + "; ".join(parts),
        equivalent_mileage_km={r: math.nan for r in start}, limits=_limit_dict(lim),
        crossed_limits=crossed, start_parameters=measured)


@dataclass(frozen=True)
class ParameterCorridor:
    """Sd, Sh, qR [mm] along a mileage grid for the P10/P50/P90 rates.

    ``parameters_mm`` has shape (3, n, 3): rate quantile (high = early, median, low = late)
    x mileage x (Sd, Sh, qR); ``mileage_km`` (n,) counts from the start state.
    """

    mileage_km: np.ndarray
    parameters_mm: np.ndarray
    extrapolated: np.ndarray


def parameter_corridor(
    model: HybridModel,
    route: Route,
    table: pd.DataFrame | WearTable,
    mileage_km: np.ndarray,
    *,
    bogie_type: str,
    axle: int,
    side: str,
    start_areas: Mapping[str, float] | None = None,
    start_parameters: Mapping[str, float] | None = None,
    weighted_measures: Mapping[str, float] | None = None,
) -> ParameterCorridor:
    """The predicted Sd/Sh/qR band from a start state (as :func:`reprofiling_mileage`
    follows it: measured parameters plus the model's changes), for pictures.

    Parameters
    ----------
    mileage_km : (n,) mileages [km] from the start state, >= 0
    start_areas, start_parameters : the measured start (see :func:`reprofiling_mileage`)
    """
    s = np.asarray(mileage_km, dtype=float)
    if s.ndim != 1 or not np.all(np.isfinite(s)) or np.any(s < 0):
        raise ValueError("mileage_km: must be finite mileages >= 0")
    start: dict[str, float] = {r: float((start_areas or {}).get(r, 0.0) or 0.0) for r in REGIONS}
    _, rates = region_rates(model, route, table, bogie_type=bogie_type, axle=axle, side=side,
                            quantiles=(0.9, 0.5, 0.1), weighted_measures=weighted_measures)
    params, _, extra = _evaluate(model, start, rates, DEFAULT_LIMITS,
                                 np.broadcast_to(s, (3, s.size)).copy())
    measured = _measured_start(start_parameters)
    if measured:
        p0, _ = parameters_at_areas(model, np.array([start["flange"]]),
                                    np.array([start["tread"]]))
        params = params + (np.array([measured["sd_mm"], measured["sh_mm"], measured["qr_mm"]])
                           - p0[0])
    return ParameterCorridor(s, params, extra)
