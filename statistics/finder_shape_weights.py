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

The nuisance also depends on where the wheel runs (``SHAPE_WEIGHTING = "position_area"``,
the default): the hybrid model gives every worn wheel one shape per region, and a wheel
whose contact wears it differently from that mean shape departs from it the more, the more
its position differs from the fleet's mean. On the loop generator (the physics wear loop as
truth, stop 33's curving) the wheels that always lead their bogie (lead-mode units' axle 1:
flange contact in every curve) scatter far more per measurement than the others at the same
worn area (mean squared norm of the instrument-centred, noise-whitened coefficients 43-93
against 3-6 on seeds 103 and 115) and carried two thirds to three quarters of the weighted
nuisance sum of squares, while an instrument's signature is the same in every position
(its squared norm 5-9 in each); with the variance function of the area alone they kept
weights of ~0.9-1.1 against 1.5-2.5 for the others, and a 0.1 mm flange offset's held-out
gain fell under the finder's 1 % materiality bar on 4 of 20 seeds although its test was
significant (p 0.005). The variance function then carries the position as a multiplicative
factor: s_i^2 = v(A_i) k_pos(i), v the pooled binned variance function of the area above and
k_pos the mean over the position's rows of |c_i|^2 / (k v(A_i)) (a method-of-moments factor,
not a robust scale: the heavy tail of a position's wheels is what its weight must carry; a
robust (MAD) scale per position left two seeds' gains under the bar), for every position
with at least ``4 NOISE_BINS`` rows (inverse-variance weights with a known covariate in the
variance function, Carroll and Ruppert 1988, ch. 3). Where the positions scatter alike the
factors are ~1 up to sampling noise. ``discrepancy`` applies the position factor to the
between-wheel test (``position`` given); the within-life test of the lives measured by
several instruments (``finder_shape_test.within_life_p``, the depot) keeps the area's
variance function: with the factor there too the depot's effect-free seed 110 was named an
instrument error (both tests at p 0.005; the within-life test alone had raw p 0.015 before),
one more false alarm than the bar allows.

``SHAPE_WEIGHTING``: "position_area" (the above), "area" (one variance function of the area
for all positions: the finder before this factor) or "none" (every measurement alike: the
finder before these weights).

Pure numpy.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from wearcast.statistics.cause_base import NOISE_BINS, noise_scale

Array = NDArray[np.float64]

SHAPE_WEIGHTING = "position_area"


def shape_weights(centred: Array, predicted_area_mm2: Array,
                  position: NDArray[Any] | None = None) -> Array:
    """(n,) precision weight of every measurement's shape coefficients.

    centred : (n, k) shape coefficients less their instrument's mean (whitened metric)
    predicted_area_mm2 : (n,) the model's predicted worn area (flange + tread) [mm^2]
    position : (n,) wheel position of each row (``finder_shape_position.wheel_positions``),
        or None (one variance function for all rows)
    Ones with ``SHAPE_WEIGHTING = "none"``; ``"area"`` ignores ``position``.
    """
    c = np.asarray(centred, dtype=float)
    n = c.shape[0]
    if SHAPE_WEIGHTING == "none" or n == 0:
        return np.ones(n)
    if SHAPE_WEIGHTING not in ("position_area", "area"):
        raise ValueError("SHAPE_WEIGHTING must be 'position_area', 'area' or 'none', "
                         f"got {SHAPE_WEIGHTING!r}")
    area = np.repeat(np.asarray(predicted_area_mm2, dtype=float)[:, None], c.shape[1], axis=1)
    variance = np.mean(noise_scale(c, area, "area") ** 2, axis=1)
    if SHAPE_WEIGHTING == "position_area" and position is not None:
        # a multiplicative factor per position: the mean square of its rows' coefficients
        # over the pooled variance function (method of moments; not a robust scale -- the
        # positions' heavy tails are what the weights must carry)
        labels = np.asarray(position).astype(str)
        ratio = np.sum(c ** 2, axis=1) / (c.shape[1] * variance)
        for lev in np.unique(labels):
            rows = labels == lev
            if rows.sum() >= 4 * NOISE_BINS and rows.sum() < n:
                variance[rows] *= float(np.mean(ratio[rows]))
    variance = np.maximum(variance, 1e-12 * max(float(np.max(variance)), 1e-300))
    return np.asarray(float(np.mean(variance)) / variance)
