"""Head wear of a measured rail against a reference head (60E1/UIC60, 60E2 or given points).

The reference is PLACED on the measurement; the measurement is never moved.

Placement (``Placement``): the reference's top-of-head centre is put at the instrument's own
origin (the measured rail frame of ``profiles.measured_rail``), its top at z = 0. That datum
is checked on the field-side flank 12-30 mm below the reference top, which wheels do not
touch: the mean horizontal distance of the measured flank from the reference flank there.
Within ``DATUM_TOLERANCE_MM`` the datum is kept as is; beyond, the reference is shifted
LATERALLY by that mean (the only fitted quantity, reported with its RMS). The vertical datum is
always the instrument's zero: a head holds no unworn horizontal surface to fit it to.

Measures [mm], positive where metal is lost (the reference lies outside the measurement):

* ``vertical`` (W1): at the reference's centre line, reference top minus measured height;
* ``lateral`` (W2, gauge-face wear): 14 mm below the reference top (the gauge-point depth,
  EN 13848-1), measured gauge face minus reference gauge face, horizontally;
* ``corner_45`` (W3): along the reference's outward normal at the gauge-corner point where
  the reference surface is inclined at 45 deg, the distance from the reference surface to the
  measured one.

The reference heads are the EN 13674-1 profiles of ``profiles.rails``; the W1/W2/W3 positions
follow common rail-profile practice (e.g. the MiniProf W1/W2/W3 fields) and are stated in every
answer. A measurement that does not fit its reference (field flank off the reference shape,
gauge face well outside the reference, top above it) is flagged, never reported silently as
negative wear.

A head worn by the wear loop (:class:`WornRail`, :func:`wear_rail`): the normal depth the loop
computes on the inclined rail frame is removed along the head's normal (seed 003 §4.3) and
the head kept in the frame of the new rail (its foot does not move); it enters the contact
table like a rail name and is measured here against the head it was worn from.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.profiles.measured import ContentIdentity
from wearcast.physics.profiles.measured_rail import (
    GAUGE_POINT_DEPTH_MM,
    crossings_at_height,
    heights_at_y,
    polyline_crossings,
    rail_points,
    shape_facts,
    upper_envelope,
)
from wearcast.physics.profiles.rails import (
    RAIL_NAMES,
    incline,
    rail_profile,
    resample_by_arc_length,
)

#: A lateral datum offset up to this is accepted unfitted [mm].
DATUM_TOLERANCE_MM = 1.0
#: Depth window below the reference top of the field-side flank used to check the datum [mm].
FIELD_FLANK_WINDOW_MM = (12.0, 30.0)
#: Fewest field-flank points that make a datum check.
MIN_FLANK_POINTS = 5
#: RMS of the field flank about the placed reference above which the shapes differ [mm].
FLANK_RMS_LIMIT_MM = 0.75
#: Negative wear beyond these is a reference mismatch, not wear [mm].
NEGATIVE_LATERAL_LIMIT_MM = -1.0
NEGATIVE_VERTICAL_LIMIT_MM = -0.5
#: Farthest a 45-degree crossing is looked for from the reference point [mm].
CORNER_SEARCH_MM = 15.0

#: The reference heads known by name: the named rails of ``profiles.rails``.
REFERENCE_NAMES = RAIL_NAMES


@dataclass(frozen=True)
class RailReference:
    """A reference head, upright, top-of-head centre at (0, 0), gauge side at y < 0 [mm];
    ``source`` says what it is (a standard, or which stored rail)."""

    name: str
    y_mm: NDArray[np.float64] = field(repr=False)
    z_mm: NDArray[np.float64] = field(repr=False)
    source: str = ""


def reference_rail(name: str) -> RailReference:
    """The EN 13674-1 reference head ``60E1`` (alias ``UIC60``) or ``60E2``."""
    from wearcast.physics.profiles.rails import rail_profile

    key = name.strip().upper()
    if key not in REFERENCE_NAMES:
        raise ValueError(f"reference: unknown rail profile {name!r}; known: "
                         f"{', '.join(REFERENCE_NAMES)} (or a stored rail as reference)")
    y, z = rail_profile(key, step_mm=0.05, inclination=0.0)
    canonical = "60E2" if key == "60E2" else "60E1"
    label = f"{key} (= 60E1)" if key == "UIC60" else key
    return RailReference(name=key, y_mm=y, z_mm=z,
                         source=f"EN 13674-1 {canonical} head, arcs as in profiles.rails"
                         + (f"; {label}" if key == "UIC60" else ""))


def reference_from_points(name: str, y_mm: ArrayLike, z_mm: ArrayLike,
                          source: str = "") -> RailReference:
    """A reference given by points in its own rail frame (e.g. a stored measured new rail or a
    drawing), taken as it is: its frame's origin is its top-of-head centre."""
    y = np.asarray(y_mm, float)
    z = np.asarray(z_mm, float)
    facts = shape_facts(y, z)
    if facts.gauge_point_mm is None:
        raise ValueError("reference: its gauge side does not reach the gauge point "
                         f"({GAUGE_POINT_DEPTH_MM:g} mm below its top)")
    return RailReference(name=name, y_mm=y, z_mm=z, source=source or "given points")


@dataclass(frozen=True)
class Placement:
    """Where the reference's top-of-head centre sits in the measured rail frame [mm].

    ``lateral_mm``/``vertical_mm`` its position; ``fitted`` whether ``lateral_mm`` was fitted
    (to the field-side flank) rather than taken from the instrument's datum; the check:
    ``flank_points``, ``flank_offset_mm`` (mean measured minus reference, horizontal, before
    any fit) and ``flank_rms_mm`` (about the placed reference); ``method`` in words.
    """

    lateral_mm: float
    vertical_mm: float
    fitted: bool
    flank_points: int
    flank_offset_mm: float | None
    flank_rms_mm: float | None
    method: str


#: What a head wear measure is (``WearMeasure.status``).
WearStatus = Literal["ok", "reference_mismatch", "not_measured"]


@dataclass(frozen=True)
class WearMeasure:
    """One head wear measure [mm] (None when not measurable, see ``status`` and ``note``).

    ``status``: ``ok``; ``reference_mismatch`` (a value exists but the measurement does not fit
    the reference, so it is not wear); ``not_measured`` (the points do not reach it).
    ``reference_point_mm`` (y, z) where on the placed reference it is taken.
    """

    value_mm: float | None
    status: WearStatus
    reference_point_mm: tuple[float, float] | None
    definition: str
    note: str = ""


@dataclass(frozen=True)
class RailHeadWear:
    """Head wear of one measured rail against one reference (module docstring)."""

    reference: str
    reference_source: str
    placement: Placement
    vertical: WearMeasure
    lateral: WearMeasure
    corner_45: WearMeasure
    reference_fits: bool
    mismatch: list[str]
    reference_head_width_mm: float | None
    measured_head_width_mm: float | None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _reference_gauge_y(ref: RailReference, z_level: float) -> float | None:
    gauge = ref.y_mm <= 0.0
    ys = crossings_at_height(ref.y_mm[gauge], ref.z_mm[gauge], z_level)
    return float(ys.min()) if ys.size else None


def _reference_field_y(ref: RailReference, z_level: NDArray) -> NDArray:
    """Field-side y of the reference at each height (NaN outside its depth) [mm]."""
    field_side = ref.y_mm >= 0.0
    fy, fz = ref.y_mm[field_side], ref.z_mm[field_side]
    k = int(np.argmax(fy))  # outermost point; below it the flank, taken single-valued in z
    fy, fz = fy[:k + 1], fz[:k + 1]
    order = np.argsort(fz)
    return np.interp(z_level, fz[order], fy[order], left=np.nan, right=np.nan)


def _corner_point(ref: RailReference) -> tuple[float, float] | None:
    """Gauge-side point of the reference where its surface is inclined at 45 deg."""
    k = int(np.argmax(ref.z_mm))
    y = ref.y_mm[:k + 1][::-1]  # from the top outwards to the gauge side
    z = ref.z_mm[:k + 1][::-1]
    dy = -np.diff(y)
    dz = -np.diff(z)
    angle = np.degrees(np.arctan2(dz, np.where(dy == 0, 1e-12, dy)))
    above = np.nonzero(angle >= 45.0)[0]
    if above.size == 0 or above[0] == 0:
        return None
    i = int(above[0])
    a0, a1 = angle[i - 1], angle[i]
    t = (45.0 - a0) / (a1 - a0) if a1 != a0 else 0.0
    # the midpoints of segments i-1 and i carry the angles a0, a1
    m0 = 0.5 * np.array([y[i - 1] + y[i], z[i - 1] + z[i]])
    m1 = 0.5 * np.array([y[i] + y[i + 1], z[i] + z[i + 1]])
    p = m0 + t * (m1 - m0)
    return float(p[0]), float(p[1])


def _distance_along(y: NDArray, z: NDArray, point: NDArray, inward: NDArray) -> float | None:
    """Signed distance [mm] along ``inward`` from ``point`` to the polyline (y, z) where it
    crosses the line through ``point``; the crossing nearest ``point`` within the search."""
    tangent = np.array([inward[1], -inward[0]])
    rel = np.stack([y - point[0], z - point[1]], axis=1)
    along = rel @ tangent
    depth = rel @ inward
    hits = polyline_crossings(along, depth)
    hits = hits[np.abs(hits) <= CORNER_SEARCH_MM]
    return float(hits[np.argmin(np.abs(hits))]) if hits.size else None


def place_reference(y_mm: NDArray, z_mm: NDArray, ref: RailReference,
                    tolerance_mm: float = DATUM_TOLERANCE_MM) -> Placement:
    """Place the reference at the instrument's datum, checked (and if need be laterally
    fitted) on the field-side flank (module docstring)."""
    lo, hi = FIELD_FLANK_WINDOW_MM
    y_top = y_mm[int(np.argmax(z_mm))]  # the field side lies beyond the measured top
    window = (y_mm > max(0.0, y_top)) & (z_mm <= -lo) & (z_mm >= -hi)
    ref_y = _reference_field_y(ref, z_mm[window])
    offsets = (y_mm[window] - ref_y)[np.isfinite(ref_y)]
    n = int(offsets.size)
    if n < MIN_FLANK_POINTS:
        field = y_mm > max(0.0, y_top)
        depth = float(max(0.0, -z_mm[field].min())) if field.any() else 0.0
        return Placement(0.0, 0.0, False, n, None, None,
                         "instrument datum, unchecked: the field side is measured only "
                         f"{depth:.1f} mm below the reference top (the check needs its flank "
                         f"{lo:g}-{hi:g} mm below)")
    mean = float(np.mean(offsets))
    if abs(mean) <= tolerance_mm:
        rms = float(np.sqrt(np.mean(offsets**2)))
        return Placement(0.0, 0.0, False, n, mean, rms,
                         f"instrument datum, checked on the field-side flank ({n} points "
                         f"{lo:g}-{hi:g} mm below the top: mean offset {mean:+.2f} mm)")
    rms = float(np.sqrt(np.mean((offsets - mean) ** 2)))
    return Placement(mean, 0.0, True, n, mean, rms,
                     f"lateral datum FITTED: the field-side flank ({n} points {lo:g}-{hi:g} mm "
                     f"below the top) lies {mean:+.2f} mm from the reference placed at the "
                     "instrument's origin, beyond the "
                     f"{tolerance_mm:g} mm tolerance; the reference is shifted by that much "
                     "(the measurement is not moved); vertical datum: the instrument's zero")


def rail_head_wear(y_mm: ArrayLike, z_mm: ArrayLike, reference: RailReference | str = "60E1"
                   ) -> RailHeadWear:
    """Head wear measures of a measured rail (rail frame, ordered gauge side first) [mm].

    Parameters
    ----------
    y_mm, z_mm : measured points in the rail frame of ``profiles.measured_rail`` (gauge side
        at y < 0, z up, the instrument's origin kept)
    reference : ``"60E1"``, ``"UIC60"``, ``"60E2"`` or a :class:`RailReference`

    Returns
    -------
    RailHeadWear: the placement (and anything fitted), W1/W2/W3 with where they were taken,
    and whether the measurement fits the reference (reasons when not).
    """
    ref = reference_rail(reference) if isinstance(reference, str) else reference
    y = np.asarray(y_mm, float)
    z = np.asarray(z_mm, float)
    placement = place_reference(y, z, ref)
    yc, zc = placement.lateral_mm, placement.vertical_mm
    mismatch: list[str] = []
    if placement.flank_rms_mm is not None and placement.flank_rms_mm > FLANK_RMS_LIMIT_MM:
        mismatch.append(f"the field-side flank departs from the {ref.name} flank by "
                        f"{placement.flank_rms_mm:.2f} mm RMS (limit {FLANK_RMS_LIMIT_MM:g})")

    # W1: vertical at the centre line
    hz = heights_at_y(y, z, yc)
    w1_def = f"reference top minus measured height at the reference centre line (y = {yc:.2f})"
    if hz.size:
        w1 = float(zc - hz.max())
        vertical = WearMeasure(w1, "ok", (yc, zc), w1_def)
    else:
        vertical = WearMeasure(None, "not_measured", (yc, zc), w1_def,
                               "the points do not cross the centre line")

    # W2: lateral 14 mm below the reference top
    level = zc - GAUGE_POINT_DEPTH_MM
    ref_g = _reference_gauge_y(ref, -GAUGE_POINT_DEPTH_MM)
    w2_def = (f"measured minus reference gauge face, horizontally, {GAUGE_POINT_DEPTH_MM:g} mm "
              "below the reference top")
    gauge = y <= yc
    my = crossings_at_height(y[gauge], z[gauge], level)
    if ref_g is None:
        lateral = WearMeasure(None, "not_measured", None, w2_def,
                              "the reference has no gauge face at that depth")
    elif my.size == 0:
        lateral = WearMeasure(None, "not_measured", (yc + ref_g, level), w2_def,
                              "the gauge side is not measured that deep")
    else:
        lateral = WearMeasure(float(my.min() - (yc + ref_g)), "ok", (yc + ref_g, level), w2_def)

    # W3: 45 degrees at the gauge corner
    corner = _corner_point(ref)
    w3_def = ("distance from the reference to the measured surface along the reference's "
              "outward normal where the reference gauge corner is inclined at 45 deg")
    if corner is None:
        corner_45 = WearMeasure(None, "not_measured", None, w3_def,
                                "the reference has no 45-degree gauge corner")
    else:
        p = np.array([corner[0] + yc, corner[1] + zc])
        inward = np.array([1.0, -1.0]) / math.sqrt(2.0)
        d = _distance_along(y, z, p, inward)
        point = (float(p[0]), float(p[1]))
        corner_45 = (WearMeasure(d, "ok", point, w3_def) if d is not None else
                     WearMeasure(None, "not_measured", point, w3_def,
                                 "the measured points do not cross the 45-degree line"))

    if lateral.value_mm is not None and lateral.value_mm < NEGATIVE_LATERAL_LIMIT_MM:
        mismatch.append(f"the gauge face lies {-lateral.value_mm:.2f} mm OUTSIDE the {ref.name} "
                        "gauge face: the head is wider than the reference (another rail "
                        "section, plastic flow, or a datum the file does not give)")
    if vertical.value_mm is not None and vertical.value_mm < NEGATIVE_VERTICAL_LIMIT_MM:
        mismatch.append(f"the measured top lies {-vertical.value_mm:.2f} mm ABOVE the "
                        f"{ref.name} top at the instrument's zero: the vertical datum or the "
                        "reference does not fit")
    fits = not mismatch
    if not fits:
        vertical, lateral, corner_45 = (
            m if m.value_mm is None else WearMeasure(
                m.value_mm, "reference_mismatch", m.reference_point_mm, m.definition,
                "not wear: the measurement does not fit the reference")
            for m in (vertical, lateral, corner_45))
    ref_facts = shape_facts(ref.y_mm, ref.z_mm)
    # measured head width at the reference's gauge depth (both sides needed)
    field_y = crossings_at_height(y[y >= yc], z[y >= yc], level)
    width = (float(field_y.max() - my.min()) if field_y.size and my.size else None)
    return RailHeadWear(reference=ref.name, reference_source=ref.source, placement=placement,
                        vertical=vertical, lateral=lateral, corner_45=corner_45,
                        reference_fits=fits, mismatch=mismatch,
                        reference_head_width_mm=ref_facts.head_width_mm,
                        measured_head_width_mm=width)


# --------------------------------------------------------------------------------------------
# A rail head worn by the wear loop (fed back into the contact, seed 003 §4.3)
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class WornRail(ContentIdentity):
    """A rail head worn by the wear loop, as points [mm] in the UPRIGHT rail frame of
    ``profiles.rails`` (gauge side at y < 0, the new head's top at (0, 0)), ordered from the
    gauge side.

    Unlike a measured rail (``profiles.measured_rail.MeasuredRail``, placed by its own top
    and gauge point), a worn rail keeps the frame of the head it was worn from: the rail's
    foot does not move when its head wears, so its points are never shifted. It is a
    ``profiles.rails.RailShape``: :meth:`contact_points` gives the contact model its inclined
    upper envelope (``build_contact_table(wheel, rail, ...)`` accepts it like a rail name).
    ``base`` is the reference head it was worn from (``60E1``/``UIC60``/``60E2``), against
    which :meth:`head_wear` measures W1/W2/W3 (:func:`rail_head_wear`, placement exact: same
    frame). Equality and hashing go by content (``digest``), so it keys contact-table caches.
    """

    name: str
    y_mm: NDArray[np.float64] = field(repr=False)
    z_mm: NDArray[np.float64] = field(repr=False)
    base: str = "60E1"

    def __post_init__(self) -> None:
        y, z = rail_points(self.y_mm, self.z_mm, "worn rail")
        if self.base.strip().upper() not in REFERENCE_NAMES:
            raise ValueError(f"base: unknown rail profile {self.base!r}")
        object.__setattr__(self, "y_mm", y)
        object.__setattr__(self, "z_mm", z)

    def identity_text(self) -> str:
        """The base head (hashed into ``digest`` after the points)."""
        return self.base

    def __str__(self) -> str:
        return f"worn rail {self.name} ({self.base})"

    def contact_points(self, step_mm: float = 0.2, inclination: float = 0.0
                       ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The head as the contact model takes a rail (``profiles.rails.rail_profile``): turned
        by the inclination about the new head's top, reduced to its upper envelope (what a
        wheel can touch) and resampled by arc length; (y, z) [mm], gauge side first."""
        y, z = incline(self.y_mm, self.z_mm, inclination)
        y, z = upper_envelope(y, z)
        return resample_by_arc_length(y, z, step_mm)

    def head_wear(self) -> RailHeadWear:
        """W1/W2/W3 of this head against its base (:func:`rail_head_wear`) [mm]."""
        return rail_head_wear(self.y_mm, self.z_mm, self.base)

    def area_loss_mm2(self) -> float:
        """Cross-section area lost against the new ``base`` head [mm^2] (vertical integral of
        the height difference over the head)."""
        y0, z0 = rail_profile(self.base, step_mm=0.05, inclination=0.0)
        return head_area_between_mm2(y0, z0, self.y_mm, self.z_mm)


def head_area_between_mm2(y_new_mm: ArrayLike, z_new_mm: ArrayLike, y_worn_mm: ArrayLike,
                          z_worn_mm: ArrayLike) -> float:
    """Area between two heads given as outlines in the same frame [mm^2]: the integral over
    height of the width lost, i.e. the area of the new head above the worn outline. Both
    outlines are reduced to their upper envelopes and compared as z(y) on a 0.01 mm grid over
    the new head's span (the worn head beyond its own points counts as absent)."""
    y0, z0 = upper_envelope(np.asarray(y_new_mm, float), np.asarray(z_new_mm, float))
    y1, z1 = upper_envelope(np.asarray(y_worn_mm, float), np.asarray(z_worn_mm, float))
    grid = np.arange(y0[0], y0[-1], 0.01)
    top0 = np.interp(grid, y0, z0)
    bottom = float(min(z0.min(), z1.min()))
    top1 = np.interp(grid, y1, z1, left=bottom, right=bottom)
    return float(np.trapezoid(np.clip(top0 - np.maximum(top1, bottom), 0.0, None), grid))


def wear_rail(rail: str | Any, rail_y_mm: ArrayLike, normal_depth_mm: ArrayLike,
              inclination: float, name: str = "worn") -> WornRail:
    """Remove a normal wear depth from a rail head (seed 003 §4.3: "in the normal direction to
    the ... rail profile").

    Parameters
    ----------
    rail : a rail name (``60E1``/``UIC60``/``60E2``) or a :class:`WornRail`
    rail_y_mm, normal_depth_mm : the depth [mm] over the lateral coordinate of the INCLINED
        rail frame the contact model uses (``ContactTable``: ``rail_y_mm`` of the contacts,
        e.g. ``rail_wear_per_vehicle.rail_depth_per_vehicle``), gauge side at y < 0
    inclination : rail inclination as a slope (the vehicle's), used to turn the head into
        that frame and back

    Returns
    -------
    WornRail: every point of the inclined head moved along its inward normal by the depth at
    its y (zero outside the given range), turned back upright, reduced to its upper envelope.
    """
    if isinstance(rail, str):
        base = rail.strip().upper()
        if base not in REFERENCE_NAMES:
            raise ValueError(f"rail: unknown rail profile {rail!r}")
    elif isinstance(rail, WornRail):
        base = rail.base
    else:
        raise ValueError("rail: a rail name or a WornRail")
    y, z = rail_profile(rail, step_mm=0.05, inclination=inclination)
    ry = np.asarray(rail_y_mm, float)
    d = np.asarray(normal_depth_mm, float)
    if ry.shape != d.shape or ry.ndim != 1 or np.any(np.diff(ry) <= 0):
        raise ValueError("rail_y_mm must be ascending and match normal_depth_mm")
    if not np.all(np.isfinite(d)):
        raise ValueError("normal_depth_mm must be finite")
    dy = np.gradient(y)
    dz = np.gradient(z)
    norm = np.hypot(dy, dz)
    out_y, out_z = -dz / norm, dy / norm               # outward normal (up on the crown)
    depth = np.interp(y, ry, d, left=0.0, right=0.0)
    yw, zw = y - depth * out_y, z - depth * out_z
    yu, zu = incline(yw, zw, -inclination)              # back to upright
    yu, zu = upper_envelope(yu, zu)
    return WornRail(name=name, y_mm=yu, z_mm=zu, base=base)
