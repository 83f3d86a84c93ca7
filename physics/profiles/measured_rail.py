"""A measured rail head in the rail frame, and what its shape says about it.

Rail frame (as ``profiles.rails``): ``y`` [mm] lateral, NEGATIVE on the gauge side (the side
that faces the track centre), ``z`` [mm] up, the rail upright (its own axes, not the track's:
the laying inclination is stated separately and applied only when the rail is placed in track).
A measured rail keeps the instrument's own origin: the points are only mirrored (when the
instrument's X runs towards the gauge side) and their height sign fixed (when its Y runs
down); they are never shifted, rotated or fitted.

Derived, never stored as points:

* the **top of the head**: the highest measured point;
* the **gauge point**: the outermost gauge-side point 14 mm below the top, where track gauge
  is measured (EN 13848-1; ``GAUGE_POINT_DEPTH_MM``);
* the **head width** 14 mm below the top, when both sides are measured that deep.

For the contact model (:meth:`MeasuredRail.contact_points`) the rail is inclined and reduced
to what a wheel can touch from above (its upper envelope: undercuts below an overhanging gauge
face or a field-side lip are hidden), then expressed with its top at z = 0 and its gauge point
where the nominal 60E1 head has it, so that track gauge is the distance between the measured
rails' gauge points, as a gauge measurement on track finds it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.measured import ContentIdentity
from wearcast.physics.profiles.rails import incline, resample_by_arc_length

#: Depth of the gauge point below the top of the head [mm] (EN 13848-1 track gauge).
GAUGE_POINT_DEPTH_MM = 14.0
#: Lateral position of the 60E1 gauge point in the upright rail frame [mm] (R13 arc).
NOMINAL_GAUGE_POINT_Y_MM = -35.981
#: Head width 14 mm below the top that a rail head has (60E1/60E2: 72 mm) [mm].
RAIL_HEAD_WIDTH_RANGE_MM = (55.0, 90.0)
#: A side measured less deep than this below the top is "short" [mm].
SHORT_SIDE_DEPTH_MM = 10.0
#: Two sides whose measured depths differ by less than this tell no gauge side [mm].
DEPTH_EVIDENCE_MM = 3.0


def polyline_crossings(a: NDArray, b: NDArray, level: float = 0.0) -> NDArray:
    """Values of ``b`` where the ordered polyline (a, b) crosses ``a = level``, linearly
    interpolated between the two vertices that bracket the level; a vertex exactly at the
    level (the last one included) counts once. The one crossing rule of the rail geometry."""
    d = a - level
    out = []
    for i in range(len(a) - 1):
        if d[i] == 0.0:
            out.append(b[i])
        elif d[i] * d[i + 1] < 0.0:
            t = d[i] / (d[i] - d[i + 1])
            out.append(b[i] + t * (b[i + 1] - b[i]))
    if len(a) and d[-1] == 0.0:
        out.append(b[-1])
    return np.asarray(out, dtype=float)


def crossings_at_height(y_mm: ArrayLike, z_mm: ArrayLike, z_level_mm: float) -> NDArray:
    """Lateral positions [mm] where an ordered polyline crosses the height ``z_level_mm``."""
    return polyline_crossings(np.asarray(z_mm, float), np.asarray(y_mm, float), z_level_mm)


def heights_at_y(y_mm: ArrayLike, z_mm: ArrayLike, y_level_mm: float) -> NDArray:
    """Heights [mm] where an ordered polyline crosses the vertical line ``y = y_level_mm``."""
    return polyline_crossings(np.asarray(y_mm, float), np.asarray(z_mm, float), y_level_mm)


def vertical_sense(x_mm: ArrayLike, y_mm: ArrayLike) -> tuple[bool, str]:
    """Whether the instrument's Y runs DOWN (a head's flanks lie below its crown).

    The crown is the middle third of the lateral span; the flanks are the points nearest the
    two lateral ends. Returns (y_down, evidence).
    """
    x = np.asarray(x_mm, float)
    y = np.asarray(y_mm, float)
    lo, hi = float(x.min()), float(x.max())
    third = (hi - lo) / 3.0
    middle = (x > lo + third) & (x < hi - third)
    ends = (x <= lo + 0.1 * (hi - lo)) | (x >= hi - 0.1 * (hi - lo))
    if not middle.any() or not ends.any():
        return False, "too few points to tell which way Y runs; taken as up"
    mid, end = float(np.median(y[middle])), float(np.median(y[ends]))
    if end > mid:
        return True, (f"Y runs down: the ends of the profile (median Y {end:.1f} mm) lie above "
                      f"its middle ({mid:.1f} mm) in the file's numbers")
    return False, f"Y runs up: the middle of the profile (median Y {mid:.1f} mm) is its top"


def side_depths(x_mm: ArrayLike, height_mm: ArrayLike) -> tuple[float, float, float, float]:
    """(x_top, z_top, depth reached at x < x_top, depth reached at x > x_top) [mm] of a head
    given with heights up (depths below the highest point, >= 0)."""
    x = np.asarray(x_mm, float)
    z = np.asarray(height_mm, float)
    k = int(np.argmax(z))
    top = float(z[k])
    left = z[x < x[k]]
    right = z[x > x[k]]
    d_left = float(top - left.min()) if left.size else 0.0
    d_right = float(top - right.min()) if right.size else 0.0
    return float(x[k]), top, d_left, d_right


def orient(x_mm: ArrayLike, y_mm: ArrayLike, gauge_at_positive_x: bool,
           y_down: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Instrument points (X, Y) [mm] in the rail frame: y = -X when the gauge side is at
    positive X (else X), z = -Y when Y runs down (else Y); ordered from the gauge side to the
    field side. No shift, no rotation."""
    y = -np.asarray(x_mm, float) if gauge_at_positive_x else np.asarray(x_mm, float).copy()
    z = -np.asarray(y_mm, float) if y_down else np.asarray(y_mm, float).copy()
    if y[0] > y[-1]:
        y, z = y[::-1].copy(), z[::-1].copy()
    return y, z


@dataclass(frozen=True)
class RailShapeFacts:
    """What the points of one head say, in the rail frame [mm].

    ``top_mm`` (y, z) the highest point; ``gauge_point_mm`` (y, z) the outermost gauge-side
    point 14 mm below it (None when the gauge side is not measured that deep);
    ``field_point_y_mm`` the outermost field-side point at that depth (None likewise);
    ``head_width_mm`` their distance; ``gauge_depth_mm``/``field_depth_mm`` how deep below the
    top each side is measured; ``lateral_span_mm`` the extent of the points.
    """

    top_mm: tuple[float, float]
    gauge_point_mm: tuple[float, float] | None
    field_point_y_mm: float | None
    head_width_mm: float | None
    gauge_depth_mm: float
    field_depth_mm: float
    lateral_span_mm: float

    def is_rail_head(self) -> tuple[bool, str]:
        """Whether this is the shape of a rail head (a crown, the gauge side measured down to
        the gauge point, a head 55-90 mm wide where both sides are measured), with the reason."""
        lo, hi = RAIL_HEAD_WIDTH_RANGE_MM
        if self.gauge_point_mm is None:
            return False, (f"the gauge side is measured only {self.gauge_depth_mm:.1f} mm below "
                           f"the top, not down to the gauge point ({GAUGE_POINT_DEPTH_MM:g} mm)")
        if self.head_width_mm is not None and not lo <= self.head_width_mm <= hi:
            return False, (f"head {self.head_width_mm:.1f} mm wide {GAUGE_POINT_DEPTH_MM:g} mm "
                           f"below its top; a rail head is {lo:g}-{hi:g} mm (60E1: 72 mm)")
        if self.head_width_mm is None:
            return True, (f"a crown with the gauge side measured down to the gauge point; the "
                          f"field side only {self.field_depth_mm:.1f} mm below the top")
        return True, (f"a crown, head {self.head_width_mm:.1f} mm wide "
                      f"{GAUGE_POINT_DEPTH_MM:g} mm below the top")


def shape_facts(y_mm: ArrayLike, z_mm: ArrayLike) -> RailShapeFacts:
    """:class:`RailShapeFacts` of oriented rail-frame points (gauge side at y < 0 of the top)."""
    y = np.asarray(y_mm, float)
    z = np.asarray(z_mm, float)
    y_top, z_top, d_gauge, d_field = side_depths(y, z)
    level = z_top - GAUGE_POINT_DEPTH_MM
    gauge_side = y <= y_top
    field_side = y >= y_top
    gy = crossings_at_height(y[gauge_side], z[gauge_side], level)
    fy = crossings_at_height(y[field_side], z[field_side], level)
    gauge = (float(gy.min()), level) if gy.size and d_gauge >= GAUGE_POINT_DEPTH_MM else None
    field_y = float(fy.max()) if fy.size and d_field >= GAUGE_POINT_DEPTH_MM else None
    width = field_y - gauge[0] if gauge is not None and field_y is not None else None
    return RailShapeFacts(top_mm=(y_top, z_top), gauge_point_mm=gauge, field_point_y_mm=field_y,
                          head_width_mm=width, gauge_depth_mm=d_gauge, field_depth_mm=d_field,
                          lateral_span_mm=float(y.max() - y.min()))


def upper_envelope(y_mm: ArrayLike, z_mm: ArrayLike) -> tuple[NDArray, NDArray]:
    """The part of an ordered head outline a wheel can reach from above [mm].

    From the highest point towards each end, a point is kept only when it lies further out
    than every point kept before it (running minimum of y towards the gauge side, maximum
    towards the field side): undercuts below an overhanging face and the underside of a lip
    are dropped. The result is single-valued in y, ordered by increasing y.
    """
    y = np.asarray(y_mm, float)
    z = np.asarray(z_mm, float)
    k = int(np.argmax(z))
    left_y, left_z = [y[k]], [z[k]]
    for i in range(k - 1, -1, -1):
        if y[i] < left_y[-1]:
            left_y.append(y[i])
            left_z.append(z[i])
    right_y, right_z = [], []
    last = y[k]
    for i in range(k + 1, len(y)):
        if y[i] > last:
            right_y.append(y[i])
            right_z.append(z[i])
            last = y[i]
    yy = np.concatenate([np.asarray(left_y[::-1]), np.asarray(right_y)])
    zz = np.concatenate([np.asarray(left_z[::-1]), np.asarray(right_z)])
    return yy, zz


#: Fewest points a rail head's polyline needs (its top, gauge side and corner are found on it).
MIN_RAIL_POINTS = 10


def rail_points(y_mm: ArrayLike, z_mm: ArrayLike, what: str
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A rail head's (y, z) points [mm] as float arrays, checked: one-dimensional, of equal
    count, at least :data:`MIN_RAIL_POINTS`, finite. ``what`` names the rail in the error
    (``measured rail``, ``worn rail``)."""
    y = np.asarray(y_mm, float)
    z = np.asarray(z_mm, float)
    if y.shape != z.shape or y.ndim != 1 or y.size < MIN_RAIL_POINTS:
        raise ValueError(f"a {what} needs at least {MIN_RAIL_POINTS} (y, z) points of equal "
                         "count")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(z))):
        raise ValueError(f"{what} points must be finite")
    return y, z


#: What a measured rail is (:class:`MeasuredRail`): a track rail or a roller of a roller rig.
RailKind = Literal["rail", "roller"]
RAIL_KINDS: tuple[RailKind, ...] = get_args(RailKind)


@dataclass(frozen=True, eq=False)
class MeasuredRail(ContentIdentity):
    """A measured rail head, points in the rail frame (see the module docstring) [mm].

    ``name`` says where it comes from (file, part); ``kind`` is ``rail`` or ``roller`` (a
    roller of a roller rig, rail-shaped, standing in for the rail: its curvature in the rolling
    direction is not modelled); ``inclination`` the laying inclination stated for it (a slope,
    e.g. 1/40) or None for the vehicle's. Equality and hashing go by content (``digest``), so
    a MeasuredRail can key the contact-table cache like a rail name.
    """

    name: str
    y_mm: NDArray[np.float64] = field(repr=False)
    z_mm: NDArray[np.float64] = field(repr=False)
    kind: str = "rail"
    inclination: float | None = None

    def __post_init__(self) -> None:
        y, z = rail_points(self.y_mm, self.z_mm, "measured rail")
        if self.kind not in RAIL_KINDS:
            raise ValueError(f"kind must be 'rail' or 'roller', got {self.kind!r}")
        if self.inclination is not None and not 0.0 <= self.inclination <= 0.2:
            raise ValueError(f"inclination must be a slope between 0 and 0.2 (1/5), got "
                             f"{self.inclination}")
        object.__setattr__(self, "y_mm", y)
        object.__setattr__(self, "z_mm", z)
        facts = shape_facts(y, z)
        if facts.gauge_point_mm is None:
            raise ValueError(f"{self.name}: no gauge point: {facts.is_rail_head()[1]}")

    def identity_text(self) -> str:
        """Kind and stated inclination (hashed into ``digest`` after the points)."""
        return f"{self.kind}|{self.inclination!r}"

    def __str__(self) -> str:  # how it reads in labels and errors
        return f"measured {self.kind} {self.name}"

    @cached_property
    def facts(self) -> RailShapeFacts:
        """Top, gauge point and head width of the points (:func:`shape_facts`)."""
        return shape_facts(self.y_mm, self.z_mm)

    def contact_points(self, step_mm: float = 0.2, inclination: float = 0.0
                       ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The head as the contact model takes a rail (``profiles.rails.rail_profile``).

        The upright points are shifted (a copy; the measurement is untouched) so that the top
        is at z = 0 and the gauge point at the 60E1 gauge point (y = -35.981 mm), turned by the
        inclination about that origin like a nominal rail (``rails.incline``), reduced to their
        upper envelope (what a wheel can touch) and resampled by arc length.

        Returns (y, z) [mm] ordered by increasing y (gauge side first).
        """
        gauge = self.facts.gauge_point_mm
        assert gauge is not None  # checked in __post_init__
        y = self.y_mm - gauge[0] + NOMINAL_GAUGE_POINT_Y_MM
        z = self.z_mm - self.facts.top_mm[1]
        y, z = incline(y, z, inclination)
        y, z = upper_envelope(y, z)
        return resample_by_arc_length(y, z, step_mm)


def nominal_rail_points(name: str, y_step_mm: float = 0.1) -> tuple[NDArray, NDArray]:
    """A nominal head (``"60E1"``, ``"UIC60"``, ``"60E2"``) as upright points ordered from the
    gauge side [mm], top at (0, 0); flanks down to ``rails.RAIL_FLANK_DEPTH_MM``."""
    from wearcast.physics.profiles.rails import rail_profile

    y, z = rail_profile(name, step_mm=y_step_mm, inclination=0.0)
    return y, z


__all__ = ["GAUGE_POINT_DEPTH_MM", "MeasuredRail", "RailShapeFacts", "crossings_at_height",
           "heights_at_y", "nominal_rail_points", "orient", "shape_facts", "side_depths",
           "upper_envelope", "vertical_sense"]
