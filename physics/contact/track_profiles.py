"""A wheelset on its track from the profiles a user has: a wheel height function or curve and
a rail (a name such as ``60E1``, or a measured head), placed as ``contact.geometry`` places
them (gauge 1435 mm at 14 mm below the top, tape circles 1500 mm apart).

One construction for the curving model's contact table (``curving_table``) and the contact
API (``contact.pose_contact``).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.contact.geometry import WheelsetTrack
from wearcast.physics.profiles.measured import ProfileCurve
from wearcast.physics.profiles.measured_rail import NOMINAL_GAUGE_POINT_Y_MM
from wearcast.physics.profiles.rails import RailShape, rail_profile

#: Depth of the gauge point below the rail top [mm] (EN 13674).
GAUGE_HEIGHT_MM = 14.0


def reaches_gauge_depth(y_mm: NDArray, z_mm: NDArray, inclination: float) -> bool:
    """Whether an upright rail curve (gauge side first) reaches GAUGE_HEIGHT_MM below its top
    on the gauge side once inclined (where ``contact.geometry`` looks for the gauge point)."""
    alpha = np.arctan(inclination)
    z_i = np.asarray(y_mm) * np.sin(alpha) + np.asarray(z_mm) * np.cos(alpha)
    top = int(np.argmax(z_i))
    return bool(np.any(z_i[: top + 1] < z_i[top] - GAUGE_HEIGHT_MM))


def wheel_curve_from_height(wheel_height_mm: Callable[[NDArray[np.float64]], NDArray[np.float64]],
                            y_range_mm: tuple[float, float], step_mm: float = 0.05
                            ) -> ProfileCurve:
    """The wheel curve through z(y) sampled every ``step_mm`` over ``y_range_mm`` [mm]."""
    y = np.arange(y_range_mm[0], y_range_mm[1] + 1e-9, step_mm)
    return ProfileCurve.from_points(y, wheel_height_mm(y))


def wheelset_track(wheel: ProfileCurve, rail: str | RailShape, inclination: float,
                   nominal_radius_mm: float, wheel_sample_mm: float = 0.2,
                   rail_right: str | RailShape | None = None) -> WheelsetTrack:
    """The wheelset on a track of ``rail`` inclined by ``inclination`` (a slope, 1/40);
    ``rail_right``: the right rail when it differs from the left one (None: ``rail`` on both
    sides, the mirrored track).

    The gauge point is found on the rail curve as for a named rail; a measured or worn head
    comes in the nominal rail frame with its gauge point at 60E1's
    (``MeasuredRail.contact_points``), which may lie under a lip the contact curve omits: then
    that known point places it (each rail by its own head).
    """
    def curve_and_gauge(r: str | RailShape) -> tuple[ProfileCurve, tuple[float, float] | None]:
        y_rail, z_rail = rail_profile(r, step_mm=0.1, inclination=0.0)
        gauge_point = None
        if not isinstance(r, str) and not reaches_gauge_depth(y_rail, z_rail, inclination):
            gauge_point = (NOMINAL_GAUGE_POINT_Y_MM, -GAUGE_HEIGHT_MM)
        return ProfileCurve.from_points(y_rail, z_rail), gauge_point

    left, gauge_left = curve_and_gauge(rail)
    right, gauge_right = (None, None) if rail_right is None else curve_and_gauge(rail_right)
    return WheelsetTrack(wheel=wheel, rail=left, rail_right=right,
                         nominal_radius_mm=nominal_radius_mm, rail_inclination=inclination,
                         wheel_sample_mm=wheel_sample_mm, rail_gauge_point_mm=gauge_left,
                         rail_right_gauge_point_mm=gauge_right)
