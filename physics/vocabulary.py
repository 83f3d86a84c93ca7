"""The shared words of wearcast: regions, bogie types, wheelset positions, sides, rails,
running modes, wear measures and the curve class, defined once for every layer.

Conventions (docs/conventions.md, "Sides and curves" and "Wear curve and regions"):

- ``side`` is the side of the vehicle seen in its reference running direction; a curve's
  ``direction`` is the side towards which the track bends. In a left curve the right wheels run
  on the **high** (outer) rail and the left wheels on the **low** rail; on tangent track both
  run on the ``tangent`` rail (:func:`rail_for`).
- ``axle`` 1 is the wheelset nearer the vehicle's reference end; it leads in the reference
  direction. ``running_mode`` ``lead``: axle 1 always leads; ``mixed``: each axle leads half
  the distance (seed 001 §4).
- Regions of the wheel frame: ``flange`` y < split, ``tread`` y >= split (default split −30 mm).

The HTTP schemas (``service/*_schemas.py``) and the readers build their enums from these types.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, cast, get_args

Region = Literal["flange", "tread"]
BogieType = Literal["motor", "trailer"]
Axle = Literal[1, 2]
Wheelset = Literal["leading", "trailing"]
Side = Literal["left", "right"]
Direction = Literal["left", "right"]
Rail = Literal["high", "low", "tangent"]
RunningMode = Literal["lead", "mixed"]
WearMeasure = Literal["tau_max", "t_gamma"]

#: Every value of each word, in the one order used everywhere (flange before tread).
REGIONS: tuple[Region, ...] = get_args(Region)
BOGIE_TYPES: tuple[BogieType, ...] = get_args(BogieType)
WHEELSETS: tuple[Wheelset, ...] = get_args(Wheelset)
SIDES: tuple[Side, ...] = get_args(Side)
DIRECTIONS: tuple[Direction, ...] = get_args(Direction)
RAILS: tuple[Rail, ...] = get_args(Rail)
RUNNING_MODES: tuple[RunningMode, ...] = get_args(RunningMode)
WEAR_MEASURES: tuple[WearMeasure, ...] = get_args(WearMeasure)
#: Columns of the curve-radius table (docs/conventions.md "Curve-radius table CSV"): the wear
#: measure of each bogie type, wheelset, rail, radius and region; built by
#: ``physics.wear_tables``, read by ``statistics.wear_tables``.
WEAR_TABLE_COLUMNS: tuple[str, ...] = ("bogie_type", "wheelset", "rail", "radius_m", "region",
                                       "measure", "value")
AXLES: tuple[Axle, ...] = get_args(Axle)

#: Wheel-frame lateral position separating flange (y < split) from tread [mm].
REGION_SPLIT_Y_MM = -30.0


def region_of(y_mm: float, split_y_mm: float = REGION_SPLIT_Y_MM) -> Region:
    """Region of a wheel-frame lateral position ``y_mm`` [mm]: flange below the split."""
    return "flange" if y_mm < split_y_mm else "tread"


def check_side(side: object) -> Side:
    """``side`` itself when it is ``'left'`` or ``'right'``; a ValueError naming it otherwise."""
    if side not in SIDES:
        raise ValueError(f"side: must be 'left' or 'right', got {side!r}")
    return cast(Side, side)


def rail_for(direction: Direction | None, side: Side) -> Rail:
    """Rail a wheel on ``side`` runs on in a curve bending towards ``direction``.

    ``direction`` None (or a tangent class) gives ``tangent``. In a left curve the right wheels
    run on the high (outer) rail and the left wheels on the low rail; mirrored in a right curve.
    """
    check_side(side)
    if direction is None:
        return "tangent"
    if direction not in DIRECTIONS:
        raise ValueError(f"direction: must be 'left' or 'right', got {direction!r}")
    return "low" if direction == side else "high"


def leading_share(axle: int, running_mode: RunningMode) -> float:
    """Share of the distance on which wheelset ``axle`` leads its bogie [-] (seed 001 §4)."""
    if axle not in AXLES:
        raise ValueError(f"axle: must be 1 or 2, got {axle!r}")
    if running_mode not in RUNNING_MODES:
        raise ValueError(f"running_mode: must be 'lead' or 'mixed', got {running_mode!r}")
    if running_mode == "mixed":
        return 0.5
    return 1.0 if axle == 1 else 0.0


@dataclass(frozen=True)
class CurveClass:
    """One class of a route's curves (seed 003 §5.3).

    radius_m : curve radius [m]; None (or +inf) is tangent track
    cant_mm : cant (superelevation) [mm], >= 0
    speed_kmh : running speed [km/h]; None = from the route's unbalanced lateral acceleration
    direction : side towards which the track bends ('left' or 'right'; ignored on tangent)
    share : share of the route's distance in this class [-], >= 0

    A route's stored class, :class:`wearcast.statistics.routes.RouteClass`, differs: its speed
    is always given, a tangent has direction None, its cant may be negative and its share is a
    fraction of the route length; ``RouteClass.curve_class()`` builds this class from it.
    """

    radius_m: float | None
    cant_mm: float = 0.0
    speed_kmh: float | None = None
    direction: Direction = "left"
    share: float = 1.0

    def __post_init__(self) -> None:
        if self.radius_m is not None and not (self.radius_m > 0 and not math.isnan(self.radius_m)):
            raise ValueError(f"radius_m: must be positive or None, got {self.radius_m}")
        if not (math.isfinite(self.cant_mm) and self.cant_mm >= 0):
            raise ValueError(f"cant_mm: must be >= 0, got {self.cant_mm}")
        if self.speed_kmh is not None and not (math.isfinite(self.speed_kmh)
                                               and self.speed_kmh > 0):
            raise ValueError(f"speed_kmh: must be positive, got {self.speed_kmh}")
        if self.direction not in DIRECTIONS:
            raise ValueError(f"direction: must be 'left' or 'right', got {self.direction!r}")
        if not (math.isfinite(self.share) and self.share >= 0):
            raise ValueError(f"share: must be >= 0, got {self.share}")

    @property
    def is_tangent(self) -> bool:
        """True on tangent track (no radius, or an infinite one)."""
        return self.radius_m is None or math.isinf(self.radius_m)

    def rail_for(self, side: Side) -> Rail:
        """Rail a wheel on ``side`` runs on in this class (:func:`rail_for`)."""
        return rail_for(None if self.is_tangent else self.direction, side)
