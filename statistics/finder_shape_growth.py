"""The part of each wheel's wear-curve shape residual that grows with its wear (discrepancy
finder, wear-curve (instrument) cause).

The profile_misalignment cause compares per-instrument mean signatures of the wear-curve
shape residual (three coefficients per measurement on the geometric basis: lateral scale,
flange offset, lateral shift; ``causes_route``). An instrument's geometric error gives the
same signature at every mileage. What it must stand out against is mostly not measurement
noise but each wheel's own shape departure from the hybrid model's mean worn shape: a new
(just turned) wheel's wear curve is zero, and a wheel whose contact wears it a little
differently from the model's shape departs from that shape in proportion to how much it has
worn. On the fleet twin the per-wheel slope of the flange-offset coefficient against the
predicted worn area scatters by 0.004 per mm^2, so over a life to 130 mm^2 the wheel's own
departure grows to ~0.4 (the coefficient's standard deviation is 0.05 on the first
measurements, 0.39 on the last sixth), while a 0.1 mm flange offset moves it by 0.09 at every
measurement. Treated as a per-wheel constant plus independent noise (the nuisance model the
test resamples), a wheel's departure that grows with the wear stays in the rows as
correlated noise that neither the wheel effect nor the precision weights remove.

Model, per wheel life (``residuals.life_ids``; a reprofiling starts a new one) and basis
direction: c_i = a_life + delta_instrument(i) + b_life A_i + e_i, with A_i the row's
predicted worn area (flange + tread) [mm^2] -- a random-coefficient growth model (Laird and
Ware 1982, Biometrics 38:963, random intercept and slope per subject), here with the slope
estimated per life by least squares and removed: ``without_wear_growth`` returns
c_i - b_life A_i, so the instrument signature (a constant at every wear) passes unchanged and
the per-instrument means and their test (``discrepancy``) see the lives' intercepts plus
noise. When the instrument changes within a life, the life's design carries an indicator per
further instrument, so a change of instrument is not taken for growth. A life with too few
measurements to estimate its slope with a residual degree of freedom (or without a spread of
areas) has the pooled within-life slope removed instead (sum S_xy / sum S_xx over the lives
that have one). The transform is linear, fixed before the test and applied to the data's
coefficients once; every resampled dataset is drawn from the nuisance of the transformed
coefficients, so the resampling p-value keeps its level.

``SHAPE_GROWTH``: "life" (the above) or "none" (the coefficients as measured; the default).
Not the default because it fails the null control on the independent generators: with the
wheels' growth removed the instrument test is about four times as sensitive (the twin's
0.1 mm flange offset named on 20 of 20 seeds against 5 of 20), and so it also finds what the
finder's nuisance model does not carry -- a shape difference shared by all the cars of a unit
(fleet_twin_alt: the calibration unit U1's lives sit at -0.016 to -0.030 in the lateral-shift
coefficient, unit U2's at +0.024 to +0.038, and each unit has one instrument). The wild
cluster bootstrap flips every vehicle's effect independently, so a unit-level difference is
not in its null: on effect-free data ``profile_misalignment`` was named on 3 of 20 alt
datasets (0 without) and 1 of 20 depot datasets (0 without). Using it needs a unit (or
route) level in the shape test's nuisance model first.

Pure numpy.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

SHAPE_GROWTH = "none"


def without_wear_growth(coef: Array, area_mm2: Array, life: NDArray[Any],
                        instrument: NDArray[Any] | None = None) -> Array:
    """(n, k) shape coefficients less each wheel life's growth with the worn area.

    coef : (n, k) shape coefficients of the measurements (any linear metric)
    area_mm2 : (n,) predicted worn area of each measurement (flange + tread) [mm^2]
    life : (n,) wheel life of each measurement (``residuals.life_ids``)
    instrument : (n,) instrument of each measurement, or None
    Unchanged (a copy) with ``SHAPE_GROWTH = "none"``.
    """
    c = np.array(coef, dtype=float)
    if SHAPE_GROWTH == "none":
        return c
    if SHAPE_GROWTH != "life":
        raise ValueError(f"SHAPE_GROWTH must be 'life' or 'none', got {SHAPE_GROWTH!r}")
    a = np.asarray(area_mm2, dtype=float)
    inst = (np.zeros(len(a), dtype=object) if instrument is None
            else np.asarray(instrument).astype(str))
    lives = np.asarray(life).astype(str)
    order = np.argsort(lives, kind="stable")
    bounds = np.flatnonzero(np.r_[True, lives[order][1:] != lives[order][:-1], True])
    sxy = np.zeros(c.shape[1])
    sxx = 0.0
    pending: list[NDArray[np.int64]] = []
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        rows = order[lo:hi]
        levels = np.unique(inst[rows])
        x = a[rows]
        design = np.column_stack([np.ones(rows.size), x]
                                 + [(inst[rows] == lev).astype(float) for lev in levels[1:]])
        spread = float(np.ptp(x)) if rows.size else 0.0
        if rows.size <= design.shape[1] or spread <= 1e-6 * max(float(np.max(np.abs(x))), 1.0) \
                or np.linalg.matrix_rank(design) < design.shape[1]:
            pending.append(rows)
            continue
        beta, *_ = np.linalg.lstsq(design, c[rows], rcond=None)
        # the slope's information (the area's spread left after the intercept and the
        # instrument indicators) for the pooled slope of the short lives
        rest = design[:, [0] + list(range(2, design.shape[1]))]
        fitted, *_ = np.linalg.lstsq(rest, x, rcond=None)
        dx = x - rest @ fitted
        info = float(dx @ dx)
        sxx += info
        sxy += info * beta[1]
        c[rows] -= np.outer(x, beta[1])
    if pending:
        pooled = sxy / sxx if sxx > 0 else np.zeros(c.shape[1])
        for rows in pending:
            c[rows] -= np.outer(a[rows], pooled)
    return c
