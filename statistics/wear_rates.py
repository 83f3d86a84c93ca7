"""Wear rates: robust through-origin regression of wear area on mileage (seed 001 §2.2, §3.2).

Seed 001 assumes (and its Fig. 8 shows) that the wear area of a region grows linearly with
mileage from the (re)profiled state, A(s) = k s, and draws a corridor in which the
measurements scatter (Fig. 11, dashed lines through the origin). The model fitted here:

    A_i = k s_i (1 + e_i),  e_i ~ i.i.d. with spread sigma_k / k,

i.e. every wheel wears at its own rate around the fleet rate k, so the scatter grows in
proportion to mileage (a fan of lines through the origin, as in Fig. 11). Under this model
the weighted least-squares slope is the mean of the per-measurement rates r_i = A_i / s_i;
we take a Huber M-estimate of that mean (IRLS, tuning 1.345, scale from the MAD) so that a
few misaligned profiles do not drag the rate. Measurements at mileage <= 0 carry no rate
information in this model and are left out.

Reported: the rate k [mm²/km], its standard error (Huber sandwich), the spread sigma_k of
individual rates [mm²/km] and n. The prediction corridor for a new measurement at mileage s
is s * (k + z_q sqrt(sigma_k² + se²)), clipped at 0.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ndtri

HUBER_C = 1.345
_MAD_TO_STD = 1.482602218505602


@dataclass(frozen=True)
class RatioFit:
    """Robust through-origin slope y = b x of positive-x data (fan-shaped scatter)."""

    slope: float
    std_error: float
    spread: float
    n: int


def fit_ratio(x: ArrayLike, y: ArrayLike, *, huber_c: float = HUBER_C,
              max_iter: int = 50, tol: float = 1e-10) -> RatioFit:
    """Huber M-estimate of the slope b in y = b x (1 + e) through the origin.

    Parameters
    ----------
    x : regressor (> 0 to be used; e.g. mileage [km] or P·s)
    y : response (e.g. wear area [mm²])

    Returns
    -------
    RatioFit(slope, std_error, spread, n): slope b, its standard error, the robust spread of
    the individual ratios y/x and the number of points used.

    Raises ValueError when fewer than two points have finite y and x > 0.
    """
    xa = np.asarray(x, dtype=float).ravel()
    ya = np.asarray(y, dtype=float).ravel()
    if xa.shape != ya.shape:
        raise ValueError("x/y: must have the same length")
    use = np.isfinite(xa) & np.isfinite(ya) & (xa > 0)
    n = int(use.sum())
    if n < 2:
        raise ValueError(f"mileage_km: need at least 2 measurements with mileage > 0, got {n}")
    r = ya[use] / xa[use]
    centre = float(np.median(r))
    scale = _MAD_TO_STD * float(np.median(np.abs(r - centre)))
    if scale <= 0.0:
        scale = float(np.std(r, ddof=1))
    if scale <= 0.0:  # all ratios identical
        return RatioFit(slope=centre, std_error=0.0, spread=0.0, n=n)
    b = centre
    for _ in range(max_iter):
        u = (r - b) / scale
        w = np.minimum(1.0, huber_c / np.maximum(np.abs(u), 1e-300))
        b_new = float(np.sum(w * r) / np.sum(w))
        if abs(b_new - b) <= tol * max(abs(b_new), 1e-300):
            b = b_new
            break
        b = b_new
    u = (r - b) / scale
    psi = np.clip(u, -huber_c, huber_c)
    dpsi = float(np.mean(np.abs(u) <= huber_c))
    dpsi = max(dpsi, 1.0 / n)
    var_b = scale**2 * float(np.sum(psi**2)) / (n - 1) / dpsi**2 / n
    # spread of individual ratios: the MAD scale (consistent for Gaussian scatter, robust to
    # the outliers the Huber weights discount)
    return RatioFit(slope=b, std_error=math.sqrt(var_b), spread=scale, n=n)


def normal_quantile(q: ArrayLike) -> NDArray[np.float64]:
    """Standard normal quantile z_q; ValueError unless 0 < q < 1."""
    qa = np.asarray(q, dtype=float)
    if np.any(~((qa > 0) & (qa < 1))):
        raise ValueError(f"q: quantiles must lie in (0, 1), got {q!r}")
    return ndtri(qa)


def predictive_std(spread: float, std_error: float) -> float:
    """Std of the rate of one new wheel: sqrt(spread² + se²), the spread of individual rates
    about the fleet's and the standard error of the fleet's estimate, in the units given
    (absolute [mm²/km] or relative [-] alike)."""
    return math.hypot(spread, std_error)


@dataclass(frozen=True)
class WearRate:
    """Wear rate of one region: A(s) = k s.

    Attributes
    ----------
    rate_mm2_per_km : fleet wear rate k [mm²/km]
    std_error_mm2_per_km : standard error of k [mm²/km]
    spread_mm2_per_km : standard deviation of individual measurements' rates A/s [mm²/km]
    n : number of measurements used (mileage > 0)
    """

    rate_mm2_per_km: float
    std_error_mm2_per_km: float
    spread_mm2_per_km: float
    n: int

    @property
    def predictive_std_mm2_per_km(self) -> float:
        """Std of the rate of a new measurement: sqrt(spread² + se²) [mm²/km]."""
        return predictive_std(self.spread_mm2_per_km, self.std_error_mm2_per_km)

    def rate_quantile(self, q: ArrayLike) -> NDArray[np.float64]:
        """Rate [mm²/km] at quantile q of the predictive distribution, clipped at 0."""
        z = normal_quantile(q)
        return np.maximum(0.0, self.rate_mm2_per_km + z * self.predictive_std_mm2_per_km)

    def residual_std_mm2(self, mileage_km: ArrayLike) -> NDArray[np.float64]:
        """Std of a measurement's area about the line at ``mileage_km`` [mm²]."""
        return np.abs(np.asarray(mileage_km, dtype=float)) * self.spread_mm2_per_km

    def area_mm2(self, mileage_km: ArrayLike) -> NDArray[np.float64]:
        """Expected wear area k s [mm²]."""
        return self.rate_mm2_per_km * np.asarray(mileage_km, dtype=float)

    def corridor(self, mileage_km: ArrayLike, q: ArrayLike = 0.9) -> NDArray[np.float64]:
        """Wear area [mm²] below which a fraction q of new measurements falls at ``mileage_km``.

        ``corridor(s, 0.05)`` and ``corridor(s, 0.95)`` bound the 90 % band of seed 001
        Fig. 11. Broadcasts mileage against q.
        """
        s = np.asarray(mileage_km, dtype=float)
        return s * self.rate_quantile(q)

    def to_dict(self) -> dict[str, Any]:
        return {
            "rate_mm2_per_km": self.rate_mm2_per_km,
            "std_error_mm2_per_km": self.std_error_mm2_per_km,
            "spread_mm2_per_km": self.spread_mm2_per_km,
            "n": self.n,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> WearRate:
        return cls(
            rate_mm2_per_km=float(data["rate_mm2_per_km"]),
            std_error_mm2_per_km=float(data["std_error_mm2_per_km"]),
            spread_mm2_per_km=float(data["spread_mm2_per_km"]),
            n=int(data["n"]),
        )


def fit_wear_rate(mileage_km: ArrayLike, area_mm2: ArrayLike, *,
                  huber_c: float = HUBER_C) -> WearRate:
    """Fit the wear rate of one region from (mileage, area) measurements.

    Parameters
    ----------
    mileage_km : mileage since (re)profiling of each measurement [km]
    area_mm2 : wear area of the region [mm²]

    Returns
    -------
    WearRate (Huber through-origin fit, see the module docstring; seed 001 §2.2, Fig. 8/11).
    """
    fit = fit_ratio(mileage_km, area_mm2, huber_c=huber_c)
    return WearRate(
        rate_mm2_per_km=fit.slope,
        std_error_mm2_per_km=fit.std_error,
        spread_mm2_per_km=fit.spread,
        n=fit.n,
    )
