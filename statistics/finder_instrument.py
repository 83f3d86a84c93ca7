"""Is a named area cause the echo of a named instrument error? (discrepancy finder)

An instrument whose lateral scale or flange-tread offset is off distorts the wear curves it
measures (``profile_misalignment``, scored on the curves' shape) and with them the flange
and tread areas it reports. Its signature in the wear curve is the same at every mileage
(``residuals.geometric_basis``), so to first order the area it adds to a region is a
constant in mm^2, not a factor: on large areas that is close to a constant factor per
region, on small ones (the loop generator's 0.5-8 mm^2 early in a life) it is a large share
of the first measurements and a small one of the last, which the log-area residuals read as
a progression slower than the model's. When the fleet's instruments are not spread evenly
over the routes, units or visits, an area cause whose covariate follows the instrument
(lubricated routes measured mostly with one instrument, a season sampled by alternating
instruments), or one that bends with the wear (``nonlinear_progression``), picks that
distortion up and can out-gain the instrument on the areas. The two gains are in different metrics
(curve space and log area), so comparing them does not say which explains the other.

``InstrumentAreaScale`` is the instrument's area distortion as a model extension: a free
log-scale and a free additive area [mm^2] per instrument and region (the reference
instrument's fixed at the common scale and at no offset; the offset enters the log residual
to first order, d / (A_pred + a0), as the rate scale enters it, ``cause_base.solve``: the
exact log(1 + d / (A_pred + a0)) by Gauss-Newton left the echo gains of the loop's offset
seeds 121 and 130 the same to 4e-4). ``AREA_DISTORTION = "scale"`` keeps the log-scales
alone (the finder before the offsets).
``instrument_echo`` scores an area cause held out on top of it, as forward selection
scores a cause on top of one already named: an area cause whose held-out gain over the
instrument's area scales stays below the materiality threshold explains nothing the named
instrument error does not, so the instrument is the verdict.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.vocabulary import REGIONS
from wearcast.statistics import causes as cz
from wearcast.statistics import finder_scoring as fs
from wearcast.statistics.cause_base import Array, Cause, FinderData, Mask

# the named instrument's area distortion the echo test fits: "scale_offset" (a log-scale and
# an additive area per instrument and region) or "scale" (the log-scale alone)
AREA_DISTORTION = "scale_offset"


class InstrumentAreaScale(Cause):
    """Per-instrument log-scale and additive offset of the flange and tread areas (nuisance of
    a named instrument error; not in the catalogue). theta: per (non-reference instrument,
    region) a log-scale (rate factor exp(theta) on the rows measured with that instrument)
    and an area offset [mm^2] (module docstring)."""

    code = "instrument_area_scale"
    covariate_name = "instrument_id"

    def __init__(self, instruments: NDArray[Any], reference: str) -> None:
        self.instruments = np.asarray(instruments).astype(str)
        self.reference = reference
        self.levels = sorted(set(self.instruments.tolist()) - {reference})

    def skip_reason(self, data: FinderData) -> str | None:
        return None if self.levels else "needs at least two instruments"

    def _kinds(self) -> tuple[str, ...]:
        if AREA_DISTORTION not in ("scale_offset", "scale"):
            raise ValueError("AREA_DISTORTION must be 'scale_offset' or 'scale', "
                             f"got {AREA_DISTORTION!r}")
        return ("log_scale", "area_offset") if AREA_DISTORTION == "scale_offset" \
            else ("log_scale",)

    def param_names(self) -> list[str]:
        return [f"{kind}_{r}_{i}" for i in self.levels for kind in self._kinds()
                for r in REGIONS]

    def features(self, data: FinderData, theta: Array) -> Array:
        # d e = phi x theta (``cause_base.solve``): an area offset d adds d / (A_pred + a0) to
        # the log residual (to first order), so its feature is 1 / A_pred (phi = A_pred /
        # (A_pred + a0)); rows the model predicts (nearly) no wear get the bounded 1 / a0
        p = np.clip(data.base, 0.0, None)
        per_area = 1.0 / np.maximum(p, data.floor[None, :])
        kinds = self._kinds()
        per = 2 * len(kinds)
        x = np.zeros((data.n, 2, per * len(self.levels)))
        for j, lev in enumerate(self.levels):
            on = (self.instruments == lev).astype(float)
            for r in range(2):
                x[:, r, per * j + r] = on
                if "area_offset" in kinds:
                    x[:, r, per * j + 2 + r] = on * per_area[:, r]
        return x

    def from_params(self, params: Mapping[str, Any]) -> Cause:
        est = copy.copy(self)
        est.theta_ = np.array([float(params[k]) for k in self.param_names()])
        return est


def instrument_echo(data: FinderData, area_cause: Cause, instrument_scale: Cause,
                    folds: NDArray[np.int64], min_relative_gain: float) -> tuple[bool, float]:
    """(is an echo, held-out relative gain of ``area_cause`` over the instrument's area
    scales): the gain 1 - SSE(scales + cause) / SSE(scales), both held out over the same
    vehicle folds with the data's robustness weights; an echo when it is below
    ``min_relative_gain``."""
    def loss(cause: Cause) -> NDArray[np.float64]:
        r = fs.held_out(data, cause, folds)
        return np.asarray(np.sum(data.weights * r ** 2, axis=1))

    before = loss(cz.Composite((instrument_scale,)))
    after = loss(cz.Composite((instrument_scale, area_cause)))
    gain = float(1.0 - after.sum() / max(float(before.sum()), 1e-300))
    return gain < min_relative_gain, gain


def reference_instrument(shape_cause: Cause, data: FinderData, rows: Mask) -> str:
    """The instrument the model's wear states came from (``ProfileMisalignment``'s)."""
    inst = shape_cause.instruments(data)  # type: ignore[attr-defined]
    return str(shape_cause.reference_instrument(data, inst, rows))  # type: ignore[attr-defined]
