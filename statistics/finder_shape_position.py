"""The part of the wear-curve shape residual that belongs to a wheel's position (discrepancy
finder, wear-curve (instrument) cause).

The profile_misalignment cause compares per-instrument mean signatures of the wear-curve
shape residual (three coefficients per measurement on the geometric basis, ``causes_route``;
each wheel life's growth with the wear removed, ``finder_shape_growth``) with one common
mean. The hybrid model gives every worn wheel one shape per region, scaled by its area, but a
wheel's wear shape depends on where it runs: the leading wheelset of a bogie takes the flange
contact in the curves, the trailing one mostly does not, and a motor bogie's suspension is
not a trailer's. The hybrid model's own table already tells these positions apart (its rates
are per bogie type and wheelset, ``route_measure.leading_shares``); its wear-curve shape does
not. On the loop generator (``generators.fleet_twin_loop``: the physics wear loop as truth,
units running in mixed and in lead mode) the position (bogie type x nominal leading share)
accounts for a quarter of the signature coefficients' sum of squares (0.23-0.30 on seeds
100-105), an instrument's 0.1 mm flange offset for 0.03-0.04: left in the rows, the
position's shape is nuisance that every held-out error carries, and the relative gain of the
per-instrument means falls under the finder's materiality bar although its test is
significant.

Model, per basis direction: c_i = a_position(i) + delta_instrument(i) + u_i, fitted by least
squares with both factors (a two-way additive layout; the position effects are estimated
within the instruments, so a position measured by one instrument more than by another does
not move that instrument's signature into the position's effect: the instrument indicators
are partialled out; the fixed-effects two-way layout of Searle, Casella & McCulloch 1992).
``without_position_shape`` returns c_i - a_position(i): the instrument's signature passes
unchanged, the positions' own shapes go. A direction of the
position effects the instruments alone could explain (a position measured by one instrument
only, every position of an instrument nested in it) is not identifiable: a small ridge on
the position effects (not on the instruments) leaves it at zero, so such data keep the
coefficients as they were and the instrument keeps its signature. The transform is linear,
fixed before the test and applied to the data's coefficients once (like the growth removal);
every resampled dataset is drawn from the nuisance of the transformed coefficients.

``SHAPE_POSITION``: "position" (the above; the default) or "none" (the coefficients as the
growth removal leaves them: the finder before this step).

Pure numpy.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

SHAPE_POSITION = "position"

# ridge on the position effects relative to the rows' count: leaves the directions the
# instrument indicators already span (not identifiable) at zero, changes nothing else
_RIDGE = 1e-8


def wheel_positions(bogie_type: NDArray[Any] | None, lead_share: Array) -> NDArray[Any]:
    """(n,) position label of every row: its bogie type (when known) and its nominal leading
    share (``FinderData.lead_share``: 1 leading, 0 trailing, 0.5 mixed)."""
    share = np.round(np.asarray(lead_share, dtype=float), 3).astype(str)
    if bogie_type is None:
        return np.asarray(share, dtype=object)
    return np.asarray(np.char.add(np.char.add(np.asarray(bogie_type).astype(str), "|"), share),
                      dtype=object)


def _indicators(labels: NDArray[Any]) -> Array:
    _, codes = np.unique(np.asarray(labels).astype(str), return_inverse=True)
    return np.asarray(np.eye(int(codes.max()) + 1)[codes], dtype=float)


def without_position_shape(coef: Array, position: NDArray[Any],
                           instrument: NDArray[Any] | None = None) -> Array:
    """(n, k) shape coefficients less their wheel position's effect (module docstring).

    coef : (n, k) signature coefficients (``finder_shape_growth.without_wear_growth``)
    position : (n,) position label of each row (``wheel_positions``)
    instrument : (n,) instrument of each row, or None
    Unchanged (a copy) with ``SHAPE_POSITION = "none"`` or a single position.
    """
    c = np.array(coef, dtype=float)
    if SHAPE_POSITION == "none":
        return c
    if SHAPE_POSITION != "position":
        raise ValueError(f"SHAPE_POSITION must be 'position' or 'none', got {SHAPE_POSITION!r}")
    n = c.shape[0]
    pos = _indicators(position) if n else np.zeros((0, 1))
    if pos.shape[1] < 2:
        return c
    inst = (np.ones((n, 1)) if instrument is None else _indicators(instrument))
    p = pos.shape[1]
    # two-way additive least squares, ridge on the position effects only (module docstring)
    design = np.vstack([np.hstack([pos, inst]),
                        np.hstack([np.sqrt(_RIDGE * n) * np.eye(p),
                                   np.zeros((p, inst.shape[1]))])])
    target = np.vstack([c, np.zeros((p, c.shape[1]))])
    beta, *_ = np.linalg.lstsq(design, target, rcond=None)
    effect = beta[:p]
    # the position effects about their rows' mean: the common level stays in the rows
    effect = effect - pos.mean(axis=0) @ effect
    return np.asarray(c - pos @ effect)
