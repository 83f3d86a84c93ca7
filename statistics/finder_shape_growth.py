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

``SHAPE_GROWTH``: "life" (the above; the default) or "none" (the coefficients as measured).
With the wheels' growth removed the instrument test is about four times as sensitive (the
twin's 0.1 mm flange offset named on 20 of 20 seeds against 5 of 20), and so the
between-wheel test alone also found what the finder's nuisance model does not carry -- a
shape level shared by all the wheels of a unit measured by one instrument (fleet_twin_alt:
the calibration unit U1's lives sit at -0.016 to -0.030 in the lateral-shift coefficient,
unit U2's at +0.024 to +0.038, one instrument each); the wild cluster bootstrap flips every
vehicle's effect independently, so a unit-level difference is not in its null
(``profile_misalignment`` named on 3 of 20 effect-free alt datasets and 2 of 20 depot ones).
Where the data hold wheel lives measured by several instruments (``within_life_contrasts``:
at least ``MIN_MIXED_LIVES`` of them), every wheel, vehicle and unit level cancels inside a
life, and ``discrepancy`` names the instrument only when its signature stands out both
between the wheels and inside those lives (an intersection-union test, Berger 1982). Data
with one instrument per unit and no such life (the twin, the loop) keep the between-wheel
test alone: there a unit-level shape difference and an instrument's signature cannot be
told apart by any test.

Pure numpy.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

Array = NDArray[np.float64]

SHAPE_GROWTH = "life"

# fewest wheel lives measured by more than one instrument for the test to use only the
# contrasts within them (``within_life_contrasts``)
MIN_MIXED_LIVES = 2


def _mixed_lives(life: NDArray[Any], instrument: NDArray[Any] | None
                 ) -> NDArray[np.bool_] | None:
    """(n,) rows of the wheel lives measured by two or more instruments, or None when fewer
    than ``MIN_MIXED_LIVES`` lives are."""
    if instrument is None:
        return None
    frame = pd.DataFrame({"life": np.asarray(life).astype(str),
                          "inst": np.asarray(instrument).astype(str)})
    per_life = frame.groupby("life")["inst"].nunique()
    mixed = per_life.index[per_life.to_numpy() >= 2]
    if mixed.size < MIN_MIXED_LIVES:
        return None
    return np.asarray(frame["life"].isin(mixed).to_numpy(), dtype=bool)


def within_life_contrasts(coef: Array, life: NDArray[Any], instrument: NDArray[Any] | None
                          ) -> tuple[NDArray[np.bool_] | None, Array]:
    """Rows of the wheel lives measured by more than one instrument and their coefficients
    less each such life's own mean (a fixed effect per life: what is left are the contrasts
    between instruments inside a life, free of every wheel, vehicle and unit level).

    coef : (n, k) signature coefficients (``without_wear_growth``)
    Returns (mask, contrasts): mask None (and the coefficients unchanged) with
    ``SHAPE_GROWTH = "none"`` or when fewer than ``MIN_MIXED_LIVES`` lives are mixed.
    """
    c = np.array(coef, dtype=float)
    mixed = _mixed_lives(life, instrument) if SHAPE_GROWTH == "life" else None
    if mixed is None:
        return None, c
    lives = np.asarray(life).astype(str)
    for lev in np.unique(lives[mixed]):
        rows = lives == lev
        c[rows] -= c[rows].mean(axis=0)
    return mixed, c


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

