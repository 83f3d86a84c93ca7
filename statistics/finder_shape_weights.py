"""Precision weights of the wear-curve (instrument) cause's rows.

The profile_misalignment cause compares per-instrument mean signatures of the wear-curve
shape residual (three coefficients per measurement on the geometric basis, ``causes_route``)
with one common mean. Its nuisance is not the same at every measurement: the shape the
hybrid model gives a worn wheel departs from the measured one by an amount that grows with
the wear, so on the fleet twin the squared norm of the instrument-centred coefficients is
~25 times larger in the last sixth of the measurements (by predicted worn area) than in
the first. An instrument's signature is the same at every mileage; an unweighted mean and
an unweighted held-out sum of squares spend most of their weight on the late, noisy rows.

The weight of measurement i is s_ref^2 / s_i^2, s_i^2 the variance function of the
coefficients at the row's predicted worn area (flange + tread) [mm^2]: per basis direction
a binned robust scale (1.4826 MAD in ``NOISE_BINS`` bins of equal count, interpolated in
log area; ``cause_base.noise_scale``), s_i^2 the mean of the directions' squared scales and
s_ref^2 the rows' mean s_i^2 -- inverse-variance (weighted least squares) estimation of the
instrument means, the same estimator the area causes use per region (Carroll and Ruppert
1988, Transformation and Weighting in Regression, ch. 3). The weights are fixed before the
test and applied to the data's held-out score and to every resampled dataset alike (the
draws are made in the weighted space), so the resampling p-value keeps its level.

``SHAPE_WEIGHTING``: "area" (the above) or "none" (every measurement alike: the finder
before these weights).

Pure numpy.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from wearcast.statistics.cause_base import noise_scale

Array = NDArray[np.float64]

SHAPE_WEIGHTING = "area"


def shape_weights(centred: Array, predicted_area_mm2: Array) -> Array:
    """(n,) precision weight of every measurement's shape coefficients.

    centred : (n, k) shape coefficients less their instrument's mean (whitened metric)
    predicted_area_mm2 : (n,) the model's predicted worn area (flange + tread) [mm^2]
    Ones with ``SHAPE_WEIGHTING = "none"``.
    """
    c = np.asarray(centred, dtype=float)
    n = c.shape[0]
    if SHAPE_WEIGHTING == "none" or n == 0:
        return np.ones(n)
    if SHAPE_WEIGHTING != "area":
        raise ValueError(f"SHAPE_WEIGHTING must be 'area' or 'none', got {SHAPE_WEIGHTING!r}")
    area = np.repeat(np.asarray(predicted_area_mm2, dtype=float)[:, None], c.shape[1], axis=1)
    variance = np.mean(noise_scale(c, area, "area") ** 2, axis=1)
    return np.asarray(float(np.mean(variance)) / variance)
