"""The weighted wear measure of a route, P = sum_i c_i P_i (seed 001 eq. 2), written once.

c_i is the share of the route's length in curve class i and P_i the curve-radius table value
(:mod:`wearcast.statistics.wear_tables`) for the wheel's bogie type, wheelset position, rail and
region, interpolated linearly in curvature 1/R. The rail of a class follows the rail rule of
:func:`wearcast.physics.vocabulary.rail_for` (tangent on straight track; in a left curve the
right wheels run on the high rail); the wheelset position follows the running mode
(:func:`wearcast.physics.vocabulary.leading_share`: axle 1 always leads in ``lead`` mode, each
axle leads half the distance in ``mixed`` mode, seed 001 §4).

Everything that needs P — the hybrid model's calibration and prediction
(:mod:`wearcast.statistics.hybrid`), the residuals and the discrepancy finder's route causes
(:mod:`wearcast.statistics.residuals`, :mod:`wearcast.statistics.causes_route`) and the fleet
twin (:mod:`wearcast.statistics.generators.fleet_twin`) — calls these functions.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.vocabulary import (
    DIRECTIONS,
    RAILS,
    REGIONS,
    SIDES,
    WEAR_MEASURES,
    WHEELSETS,
    Rail,
    leading_share,
)
from wearcast.statistics.routes import Route, RouteClass, rail_for
from wearcast.statistics.wear_tables import (
    RADIUS_RTOL,
    WearTable,
    compile_wear_table,
    table_value,
)

#: Curve-direction parts of a route: tangent track, curves bending left, curves bending right.
PARTS = ("tangent", "left", "right")


class UnknownBogieTypeError(ValueError):
    """The model (its wear table) does not cover the requested bogie type."""


def check_choice(value: object, allowed: Sequence[object], name: str) -> None:
    if value not in allowed:
        raise ValueError(f"{name}: must be one of {tuple(allowed)}, got {value!r}")


def wheelset_weights(axle: int, running_mode: str) -> dict[str, float]:
    """Share of the distance a wheelset runs leading/trailing [-] (seed 001 §4).

    ``lead``: axle 1 always leads, axle 2 always trails; ``mixed``: each leads half the time.
    Positions with no distance are left out (their table rows are not needed).
    """
    p = leading_share(axle, running_mode)  # type: ignore[arg-type]
    return {ws: w for ws, w in zip(WHEELSETS, (p, 1.0 - p), strict=True) if w > 0.0}


def _class_values(classes: Sequence[RouteClass], wt: WearTable, bogie_type: str,
                  wheelset: str, side: str, region: str,
                  measure: str) -> NDArray[np.float64] | None:
    """P_i of each class for one wheelset, one interpolation per rail (same arithmetic as
    :func:`wear_tables.table_value`); None when the table does not cover a class."""
    rails = np.array([rail_for(c, side) for c in classes])
    curvature = np.array([0.0 if c.radius_m is None else 1.0 / c.radius_m for c in classes])
    values = np.empty(len(classes))
    for rail in RAILS:
        sel = rails == rail
        if not sel.any():
            continue
        if rail == "tangent":
            tangent = wt.tangent.get((bogie_type, wheelset, region, measure))
            if tangent is None:
                return None
            values[sel] = tangent
            continue
        table_k = wt.curves.get((bogie_type, wheelset, rail, region, measure))
        if table_k is None:
            return None
        k_table, v_table = table_k
        k = curvature[sel]
        if np.any(k > k_table[-1] * (1.0 + RADIUS_RTOL)):
            return None
        values[sel] = np.interp(np.minimum(k, k_table[-1]), k_table, v_table)
    return values


def class_measures(route: Route, table: pd.DataFrame | WearTable, *, bogie_type: str,
                   wheelsets: Sequence[str], side: str, region: str,
                   measure: str) -> tuple[tuple[RouteClass, ...], dict[str, NDArray[np.float64]]]:
    """The route's classes with a share and their table values P_i per wheelset position.

    Returns (classes, {wheelset: (n_classes,) P_i}) in the table's unit. Raises the error of
    :func:`wear_tables.table_value` for the first class (in route order) the table does not
    cover: RadiusOutOfTableError for a class tighter than the table's smallest radius,
    UnknownTableEntryError for a key without rows.
    """
    wt = compile_wear_table(table)
    classes = tuple(c for c in route.classes if c.share != 0.0)
    out: dict[str, NDArray[np.float64]] = {}
    for ws in wheelsets:
        values = _class_values(classes, wt, bogie_type, ws, side, region, measure)
        if values is None:
            for c in classes:  # raises the error of the first class not covered
                for w in wheelsets:
                    table_value(wt, bogie_type, w, rail_for(c, side), c.radius_m, region,
                                measure)
            raise AssertionError("unreachable: a class was not covered")  # pragma: no cover
        out[ws] = values
    return classes, out


def weighted_wear_measure(
    route: Route,
    table: pd.DataFrame | WearTable,
    *,
    bogie_type: str,
    axle: int,
    side: str,
    running_mode: str,
    region: str,
    measure: str,
) -> float:
    """Weighted wear measure P = sum_i c_i P_i of a wheel on a route (seed 001 eq. 2).

    Parameters
    ----------
    route : curve classes with their shares c_i
    table : curve-radius table (long DataFrame or compiled)
    bogie_type : bogie type in the table
    axle : 1 or 2, the wheelset's position in its bogie (docs/conventions.md "Sides and curves")
    side : 'left' or 'right' side of the vehicle
    running_mode : 'lead' (axle 1 always leads) or 'mixed' (half leading, half trailing)
    region : 'flange' or 'tread'
    measure : 'tau_max' or 't_gamma'

    Returns
    -------
    P in the unit of the table's measure. The rail of each class is tangent on tangent
    track; in a curve bending towards the wheel's side the wheel runs on the low rail,
    otherwise on the high rail (in a left curve the right wheels run on the high rail).

    Raises UnknownBogieTypeError for a bogie type the table lacks and RadiusOutOfTableError
    for a class tighter than the table covers.
    """
    check_choice(side, SIDES, "side")
    check_choice(region, REGIONS, "region")
    check_choice(measure, WEAR_MEASURES, "measure")
    wt = compile_wear_table(table)
    if bogie_type not in wt.bogie_types:
        raise UnknownBogieTypeError(
            f"bogie_type: {bogie_type!r} is not in the wear table (has {wt.bogie_types})"
        )
    weights = wheelset_weights(axle, running_mode)
    classes, values = class_measures(route, wt, bogie_type=bogie_type, wheelsets=tuple(weights),
                                     side=side, region=region, measure=measure)
    if not classes:
        return 0.0
    p = np.zeros(len(classes))
    for ws, w in weights.items():
        p = p + w * values[ws]
    shares = np.array([c.share for c in classes])
    return float(sum((shares * p).tolist()))


def curve_direction_shares(route: Route, left_share: float | None) -> list[float]:
    """Class shares c_i [-] with the route's curved length re-split so that a share
    ``left_share`` of it bends left (the curve-asymmetry effect of the generators); tangent
    shares unchanged. None, or a route without curves, keeps the route's own shares."""
    curved: dict[str, float] = {
        d: sum(c.share for c in route.classes if c.direction == d) for d in DIRECTIONS}
    total = curved["left"] + curved["right"]
    if left_share is None or total <= 0:
        return [c.share for c in route.classes]
    out = []
    for c in route.classes:
        if c.direction is None:
            out.append(c.share)
            continue
        want = left_share if c.direction == "left" else 1.0 - left_share
        out.append(c.share * want * total / curved[c.direction])
    return out


def analytic_wear_measure(route: Route, side: str,
                          value: Callable[[str, Rail, float | None], float],
                          shares: Sequence[float] | None = None) -> dict[str, float]:
    """P = sum_i c_i P_i (seed 001 eq. 2) per wheelset position for an analytic wear measure.

    value : P_i as a function of (wheelset, rail, radius_m), radius_m None on tangent track
    shares : the classes' c_i (default the route's own; see :func:`curve_direction_shares`)

    Returns {'leading': P, 'trailing': P}; the rail of each class follows the rail rule.
    """
    c_i = [c.share for c in route.classes] if shares is None else list(shares)
    out: dict[str, float] = {}
    for ws in WHEELSETS:
        acc = 0.0
        for c, share in zip(route.classes, c_i, strict=True):
            acc += share * value(ws, rail_for(c, side), c.radius_m)
        out[ws] = acc
    return out


def route_parts(route: Route, table: pd.DataFrame | WearTable, *, bogie_type: str, side: str,
                region: str, measure: str) -> NDArray[np.float64]:
    """Route's wear measure split by wheelset and curve direction (seed 001 eq. 2 by parts).

    Returns (2, 3): rows leading/trailing, columns tangent/left/right (:data:`PARTS`), each
    sum_i c_i P_i over the route's classes of that direction; their sum over columns is the P
    of a wheel that always leads (row 0) or always trails (row 1).
    """
    classes, values = class_measures(route, table, bogie_type=bogie_type, wheelsets=WHEELSETS,
                                     side=side, region=region, measure=measure)
    out = np.zeros((2, 3))
    for i, c in enumerate(classes):
        part = 0 if c.radius_m is None else PARTS.index(str(c.direction))
        for w, ws in enumerate(WHEELSETS):
            out[w, part] += c.share * float(values[ws][i])
    return out


def weighted_measure(parts: NDArray[np.float64], lead_share: ArrayLike, measure_index: int,
                     left_right: ArrayLike | None = None) -> NDArray[np.float64]:
    """P per measurement and region (n, 2) from the route parts (seed 001 eq. 2).

    parts : (n, measure, region, wheelset, part) route parts (:func:`route_parts` stacked)
    lead_share : (n,) share of distance the wheelset leads (P = p P_lead + (1 - p) P_trail)
    measure_index : index of the measure in ``vocabulary.WEAR_MEASURES``
    left_right : optional (n, 2) weights multiplying the left and right curve parts
    """
    block = parts[:, measure_index]                      # (n, region, wheelset, part)
    lw = np.ones((block.shape[0], 3))
    if left_right is not None:
        lw[:, 1:] = np.asarray(left_right, dtype=float)
    per_ws = np.einsum("nrwp,np->nrw", block, lw)
    p = np.asarray(lead_share, dtype=float)
    return per_ws[:, :, 0] * p[:, None] + per_ws[:, :, 1] * (1.0 - p[:, None])


def leading_shares(axle: ArrayLike, running_mode: ArrayLike) -> NDArray[np.float64]:
    """Share of distance each wheelset runs leading [-]: elementwise
    :func:`wearcast.physics.vocabulary.leading_share` (lead: axle 1 → 1, axle 2 → 0; mixed 0.5).

    Raises ValueError naming ``axle`` or ``running_mode`` for a value outside the vocabulary.
    """
    a, mode = np.broadcast_arrays(np.asarray(axle), np.asarray(running_mode))
    out = np.empty(a.shape, dtype=float)
    for x, m in set(zip(a.ravel().tolist(), mode.ravel().tolist(), strict=True)):
        out[(a == x) & (mode == m)] = leading_share(int(x), m)
    return out


__all__ = ["PARTS", "UnknownBogieTypeError", "analytic_wear_measure", "class_measures",
           "curve_direction_shares", "leading_shares", "route_parts", "weighted_measure",
           "weighted_wear_measure", "wheelset_weights"]
