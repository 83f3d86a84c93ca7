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
squares with both factors (a two-way additive layout: the position effects are estimated
within the instruments, the instrument indicators partialled out, so a position measured by
one instrument more than by another does not move that instrument's signature into the
position's effect; the fixed-effects two-way layout of Searle, Casella & McCulloch 1992).
``without_position_shape`` returns c_i - a_position(i): the instrument's signature passes
unchanged, the positions' own shapes go. Where positions and instruments do not cross (every
position of a group measured only by that group's instruments) the difference between the
groups is not identifiable: a small ridge on the position effects (not on the instruments)
leaves it at zero, so the instrument keeps it.

The positions are removed only when they stand out (``position_test``, level
``POSITION_ALPHA``). A unit runs in one mode and is measured by one instrument, so the shape
level of each unit (its route, its own wheels) sits in the (position, instrument) cells; a
position effect fitted across units would take some of that level away from the rows while
the instrument contrast keeps it -- the resampled null (vehicle and wheel effects) does not
carry unit levels, and an effect-free fleet twin (units on four routes, no position in its
shapes) had its instrument named on 3 of 20 seeds against 1 of 20. The position effects are
therefore tested against their interaction with the instrument, which carries those unit
levels (the F-test of a fixed factor against the random interaction, Searle, Casella &
McCulloch 1992, ch. 4, with the conservative lower-bound degrees of freedom of Greenhouse &
Geisser 1959): on the effect-free twin F = 0.7-1.0 (seeds 100-109), on the loop F = 21-88
(seeds 100-105; 5 % critical value 9.3). Once the test has decided, the transform is linear,
fixed before the finder's test and applied to the data's coefficients once (like the growth
removal); every resampled dataset is drawn from the nuisance of the transformed
coefficients.

``SHAPE_POSITION``: "position" (the above; the default) or "none" (the coefficients as the
growth removal leaves them: the finder before this step).

Pure numpy (scipy.stats for the F distribution).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

SHAPE_POSITION = "position"

# level of the test that decides whether the positions' shapes are removed (``position_test``)
POSITION_ALPHA = 0.05

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


def row_positions(data: Any) -> NDArray[Any]:
    """(n,) position label of every row of the finder's data (``cause_base.FinderData``): its
    bogie type (when the data have one) and nominal leading share (``wheel_positions``)."""
    bogie = data.column("bogie_type")
    return wheel_positions(None if bogie is None else bogie.to_numpy(), data.lead_share)


def _indicators(labels: NDArray[Any]) -> Array:
    _, codes = np.unique(np.asarray(labels).astype(str), return_inverse=True)
    return np.asarray(np.eye(int(codes.max()) + 1)[codes], dtype=float)


def position_test(coef: Array, position: NDArray[Any], instrument: NDArray[Any] | None
                  ) -> tuple[float, int, int]:
    """(p-value, position dof, interaction dof) of the position effects against the scatter
    they would otherwise be confused with: the F-test of a fixed factor against its
    interaction with the other in a mixed two-way layout (Searle, Casella & McCulloch 1992,
    ch. 4), on the (position, instrument) cell means weighted by their rows, summed over the
    k basis directions. The interaction carries the levels of the units behind each cell (a
    unit runs in one mode and is measured by one instrument), so a position effect that is
    only some units' own shape does not stand out. The cells of one unit share its level, so
    the F ratio is referred to the conservative lower-bound degrees of freedom (k and
    k dof_int / dof_pos; Greenhouse & Geisser 1959): with k x dof on each side, four units
    whose own levels are three times the wheels' scatter passed the test in 25 % of
    simulated effect-free layouts, with the lower bound in at most 6 %. p = 1 when the layout leaves
    no interaction degree of freedom (nothing to test against)."""
    from scipy import stats

    c = np.asarray(coef, dtype=float)
    n = c.shape[0]
    inst = (np.zeros(n, dtype=object) if instrument is None
            else np.asarray(instrument).astype(str))
    pos = np.asarray(position).astype(str)
    cells = np.char.add(np.char.add(pos, "\u0000"), inst.astype(str))
    levels, first, code, count = np.unique(cells, return_index=True, return_inverse=True,
                                           return_counts=True)
    sums = np.zeros((levels.size, c.shape[1]))
    np.add.at(sums, code, c)
    means = sums / count[:, None]
    x_inst = _indicators(inst[first])
    x_both = np.hstack([_indicators(pos[first]), x_inst])
    w = np.sqrt(count.astype(float))[:, None]

    def rss(x: Array) -> tuple[float, int]:
        beta, *_ = np.linalg.lstsq(w * x, w * means, rcond=None)
        return float(np.sum((w * (means - x @ beta)) ** 2)), int(np.linalg.matrix_rank(x))

    rss_inst, rank_inst = rss(x_inst)
    rss_both, rank_both = rss(x_both)
    dof_pos, dof_int = rank_both - rank_inst, levels.size - rank_both
    if dof_pos < 1 or dof_int < 1 or rss_both <= 0.0:
        return 1.0, dof_pos, dof_int
    k = c.shape[1]
    f = ((rss_inst - rss_both) / dof_pos) / (rss_both / dof_int)
    # the lower-bound degrees of freedom (epsilon = 1 / dof_pos, Greenhouse-Geisser 1959):
    # the cells are not independent (the positions of one unit share its level), and when
    # one unit contrast dominates both mean squares each carries ~k degrees of freedom
    eps = 1.0 / dof_pos
    return float(stats.f.sf(f, k * dof_pos * eps, k * dof_int * eps)), dof_pos, dof_int


def without_position_shape(coef: Array, position: NDArray[Any],
                           instrument: NDArray[Any] | None = None,
                           metric: NDArray[Any] | None = None) -> Array:
    """(n, k) shape coefficients less their wheel position's effect (module docstring), when
    the position effects stand out against their interaction with the instrument
    (``position_test`` below ``POSITION_ALPHA``).

    coef : (n, k) signature coefficients (``finder_shape_growth.without_wear_growth``)
    position : (n,) position label of each row (``wheel_positions``)
    instrument : (n,) instrument of each row, or None
    metric : (k, k) map of the coefficients into the metric the test sums over (the
        curve-space error: ``finder_shape_test.whitened_shape``'s Cholesky factor), or None
        (the coefficients as given). The removal itself is the same in any linear metric.
    Unchanged (a copy) with ``SHAPE_POSITION = "none"``, a single position or positions
    that do not stand out.
    """
    c = np.array(coef, dtype=float)
    if SHAPE_POSITION == "none":
        return c
    if SHAPE_POSITION != "position":
        raise ValueError(f"SHAPE_POSITION must be 'position' or 'none', got {SHAPE_POSITION!r}")
    n = c.shape[0]
    pos = _indicators(position) if n else np.zeros((0, 1))
    tested = c if metric is None else c @ np.asarray(metric, dtype=float)
    if pos.shape[1] < 2 or position_test(tested, position, instrument)[0] >= POSITION_ALPHA:
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
