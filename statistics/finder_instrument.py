"""Is a named area cause the echo of a named instrument error? (discrepancy finder)

An instrument whose lateral scale or flange-tread offset is off distorts the wear curves it
measures (``profile_misalignment``, scored on the curves' shape) and with them the flange
and tread areas it reports: every area measured with it is off by a roughly constant factor
per region. When the fleet's instruments are not spread evenly over the routes, units or
visits, an area cause whose covariate follows the instrument (lubricated routes measured
mostly with one instrument, a season sampled by alternating instruments) picks that factor
up and can out-gain the instrument on the areas. The two gains are in different metrics
(curve space and log area), so comparing them does not say which explains the other.

``InstrumentAreaScale`` is the instrument's area distortion as a model extension: a free
log-scale per instrument and region (the reference instrument's fixed at the common scale).
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


class InstrumentAreaScale(Cause):
    """Per-instrument log-scale of the flange and tread areas (nuisance of a named instrument
    error; not in the catalogue). theta: one log-scale per (non-reference instrument, region),
    rate factor exp(theta) on the rows measured with that instrument."""

    code = "instrument_area_scale"
    covariate_name = "instrument_id"

    def __init__(self, instruments: NDArray[Any], reference: str) -> None:
        self.instruments = np.asarray(instruments).astype(str)
        self.reference = reference
        self.levels = sorted(set(self.instruments.tolist()) - {reference})

    def skip_reason(self, data: FinderData) -> str | None:
        return None if self.levels else "needs at least two instruments"

    def param_names(self) -> list[str]:
        return [f"log_scale_{r}_{i}" for i in self.levels for r in REGIONS]

    def features(self, data: FinderData, theta: Array) -> Array:
        x = np.zeros((data.n, 2, 2 * len(self.levels)))
        for j, lev in enumerate(self.levels):
            on = (self.instruments == lev).astype(float)
            x[:, 0, 2 * j] = on
            x[:, 1, 2 * j + 1] = on
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
