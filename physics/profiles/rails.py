"""60E1 and 60E2 rail heads (EN 13674-1) from their arcs, and rail inclination.

Rail frame: ``y`` [mm] lateral, ``z`` [mm] up, the top of the (un-inclined) rail at (0, 0).
The head is symmetric; ``y < 0`` is the half that faces the track centre when the rail is
laid (the gauge side), matching the wheel frame of docs/conventions.md where the flange is at ``y <
0``.

Geometry (EN 13674-1, docs/references.md; 60E1 and 60E2): a chain of tangent arcs from the
crown outwards, then the 1:20 flank (dy/dz = 1/20).  The arc centres are recomputed here from
the radii and the lateral positions of the tangent points between arcs (60E1: 10.228 and
26.0265 mm; 60E2: 11.889, 24.4565 and 35.387 mm), which reproduces the README's centres to
1e-4 mm and its test vectors to 1e-6 mm.  The flank is extended to ``RAIL_FLANK_DEPTH_MM``
below the top, deeper than any 28 mm flange (S1002) can reach; the rest of the rail (web,
foot) is not modelled.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, lru_cache
from typing import Literal, Protocol, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Depth below the rail top down to which the 1:20 flank is modelled [mm].
RAIL_FLANK_DEPTH_MM = 35.0
#: The named rail heads (EN 13674-1): 60E1, its alias UIC60, and 60E2.
RailName = Literal["60E1", "UIC60", "60E2"]
RAIL_NAMES: tuple[RailName, ...] = get_args(RailName)
#: Flank slope dy/dz of both rails (1:20), EN 13674-1.
_FLANK_DY_DZ = 1.0 / 20.0


class RailShape(Protocol):
    """A rail given by its points (``profiles.measured_rail.MeasuredRail``): it samples itself
    for the contact model, upright points turned by ``inclination``, top at z = 0 and the gauge
    point where the 60E1 head has it, ordered by increasing y."""

    def contact_points(self, step_mm: float, inclination: float
                       ) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...


@dataclass(frozen=True)
class RailHead:
    """Arc chain of one rail head half (the gauge half, y <= 0), all lengths in [mm].

    ``radii_mm`` from the crown outwards; ``centres_mm`` the arc centres (y, z);
    ``breaks_y_mm`` the lateral positions where arc k ends (the last is the arc/flank
    tangent point); ``flank_start_mm`` the (y, z) where the 1:20 flank begins.
    """

    name: str
    radii_mm: tuple[float, ...]
    centres_mm: tuple[tuple[float, float], ...]
    breaks_y_mm: tuple[float, ...]
    flank_start_mm: tuple[float, float]

    @property
    def half_width_mm(self) -> float:
        """Half width of the modelled head at its deepest modelled point [mm]."""
        y0, z0 = self.flank_start_mm
        return -(y0 - _FLANK_DY_DZ * (RAIL_FLANK_DEPTH_MM + z0))


def _arc_chain(name: str, radii: tuple[float, ...], tangent_y: tuple[float, ...]) -> RailHead:
    """Build the gauge half of a rail head from tangent arcs and a 1:20 flank.

    The first arc (crown) is centred on y = 0 below the top; each following arc is internally
    tangent to the previous one at the given lateral position; the flank is the line of slope
    dy/dz = 1/20 tangent to the last arc.
    """
    centre = np.array([0.0, -radii[0]])
    centres = [tuple(centre)]
    for k in range(1, len(radii)):
        y_t = tangent_y[k - 1]
        r_prev = radii[k - 1]
        z_t = centre[1] + np.sqrt(r_prev**2 - (y_t - centre[0]) ** 2)
        point = np.array([y_t, z_t])
        centre = centre + (r_prev - radii[k]) / r_prev * (point - centre)
        centres.append(tuple(centre))
    # outward normal of the flank line (direction (dy, dz) = (1, 20)) on the gauge side
    normal = np.array([-20.0, 1.0]) / np.sqrt(401.0)
    flank = centre + radii[-1] * normal
    return RailHead(
        name=name,
        radii_mm=tuple(float(r) for r in radii),
        centres_mm=tuple((float(c[0]), float(c[1])) for c in centres),
        breaks_y_mm=tuple(float(y) for y in tangent_y) + (float(flank[0]),),
        flank_start_mm=(float(flank[0]), float(flank[1])),
    )


@cache
def rail_head(name: str) -> RailHead:
    """Arc chain of a named rail head: ``"60E1"`` (R300, R80, R13) or ``"60E2"``
    (R200, R70, R16, R8); EN 13674-1 (docs/references.md)."""
    key = name.upper()
    if key in ("60E1", "UIC60"):
        return _arc_chain("60E1", (300.0, 80.0, 13.0), (-10.228, -26.0265))
    if key == "60E2":
        return _arc_chain("60E2", (200.0, 70.0, 16.0, 8.0), (-11.889, -24.4565, -35.387))
    raise ValueError(f"unknown rail profile {name!r}; known: 60E1, 60E2")


def rail_height_mm(name: str, y_mm: ArrayLike) -> NDArray[np.float64]:
    """Height z(y) of a rail head [mm] (0 at the top, negative below).

    Parameters
    ----------
    name : ``"60E1"`` or ``"60E2"``
    y_mm : lateral position(s) in the rail frame [mm]; the head is symmetric in y

    Returns
    -------
    z [mm]; NaN beyond the modelled head (flank deeper than ``RAIL_FLANK_DEPTH_MM``).
    """
    head = rail_head(name)
    u = -np.abs(np.asarray(y_mm, dtype=float))  # evaluate on the gauge half (y <= 0)
    z = np.full(u.shape, np.nan)
    lower = 0.0
    for radius, (cy, cz), y_end in zip(head.radii_mm, head.centres_mm, head.breaks_y_mm,
                                       strict=True):
        on_arc = (u <= lower) & (u >= y_end) & np.isnan(z)
        z = np.where(on_arc, cz + np.sqrt(np.clip(radius**2 - (u - cy) ** 2, 0.0, None)), z)
        lower = y_end
    y0, z0 = head.flank_start_mm
    z_flank = z0 + (u - y0) / _FLANK_DY_DZ
    on_flank = np.isnan(z) & (u < y0) & (z_flank >= -RAIL_FLANK_DEPTH_MM)
    return np.where(on_flank, z_flank, z)


def rail_60e1_height_mm(y_mm: ArrayLike) -> NDArray[np.float64]:
    """Height z(y) [mm] of the 60E1 (UIC60) head, top at (0, 0); see ``rail_height_mm``."""
    return rail_height_mm("60E1", y_mm)


def rail_60e2_height_mm(y_mm: ArrayLike) -> NDArray[np.float64]:
    """Height z(y) [mm] of the 60E2 head, top at (0, 0); see ``rail_height_mm``."""
    return rail_height_mm("60E2", y_mm)


def rail_profile(name: str | RailShape = "60E1", step_mm: float = 0.2,
                 inclination: float = 0.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sampled rail head, evenly spaced in arc length, from gauge-side flank to field side.

    Parameters
    ----------
    name : ``"60E1"`` (alias ``"UIC60"``) or ``"60E2"``, or a rail given by its points (any
        object with ``contact_points(step_mm, inclination)``, e.g.
        ``profiles.measured_rail.MeasuredRail``), which answers for itself
    step_mm : arc-length spacing of the samples [mm]
    inclination : rail inclination as a slope (1/40, 1/20, 0 = upright); the rail is turned
        about its top so that its gauge side (y < 0) goes down, see ``incline``

    Returns
    -------
    (y [mm], z [mm]) in the rail frame, ordered from the gauge-side flank bottom (y < 0) over
    the crown to the field-side flank bottom.  Sampling in arc length resolves the steep flank.
    """
    if not isinstance(name, str):
        return name.contact_points(step_mm, inclination)
    y, z = _named_rail_profile(name, float(step_mm), float(inclination))
    return y.copy(), z.copy()


@lru_cache(maxsize=32)
def _named_rail_profile(name: str, step_mm: float, inclination: float
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`rail_profile` of a named rail, cached (every contact table of the wear loop
    samples the same rail)."""
    head = rail_head(name)
    half = head.half_width_mm
    # dense in y, then resampled by arc length (the flank is nearly vertical)
    y_dense = np.concatenate([
        np.linspace(-half, head.flank_start_mm[0], 2001),
        np.linspace(head.flank_start_mm[0], -head.flank_start_mm[0], 20001)[1:-1],
        np.linspace(-head.flank_start_mm[0], half, 2001),
    ])
    z_dense = rail_height_mm(name, y_dense)
    keep = np.isfinite(z_dense)
    y, z = resample_by_arc_length(y_dense[keep], z_dense[keep], step_mm)
    return incline(y, z, inclination)


def resample_by_arc_length(y_mm: ArrayLike, z_mm: ArrayLike,
                           step_mm: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Resample an ordered polyline at (nearly) even arc-length spacing [mm], ends kept."""
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(y), np.diff(z)))])
    n = max(int(np.ceil(s[-1] / step_mm)) + 1, 2)
    s_new = np.linspace(0.0, s[-1], n)
    return np.interp(s_new, s, y), np.interp(s_new, s, z)


def incline(y_mm: ArrayLike, z_mm: ArrayLike,
            inclination: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Turn a rail profile about its top (0, 0) by the rail inclination.

    Parameters
    ----------
    y_mm, z_mm : rail points in the upright rail frame [mm] (gauge side at y < 0)
    inclination : slope of the inclination, e.g. 1/40 or 1/20 (angle = arctan(inclination))

    Returns
    -------
    (y, z) [mm] of the inclined rail, in axes parallel to the track plane: the rail is turned
    towards the track centre, so gauge-side points (y < 0) go down and the surface matches the
    wheel's conicity.
    """
    angle = np.arctan(inclination)
    y = np.asarray(y_mm, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    cos, sin = np.cos(angle), np.sin(angle)
    return y * cos - z * sin, y * sin + z * cos
