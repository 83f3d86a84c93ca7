"""Results of the rigid wheel-rail contact geometry (``geometry.contact_table``).

The arrays and scalars that the contact search reports per wheel and shift: the contact
points (wheel, rail and track frames), contact angle, rolling radius and the Hertz
curvatures, with the frames and signs defined in ``physics.contact.geometry``'s docstring.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

_FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ContactPatches:
    """One kind of contact patch (primary or secondary) on one wheel, for N shifts.

    Every field is an array of shape (N,); fields are NaN where ``valid`` is False.

    valid : the patch exists (always True for the primary)
    gap_mm : undeformed vertical gap at the patch [mm] (0 for the primary)
    y_wheel_mm, z_wheel_mm : contact point in the wheel frame [mm]
    y_rail_mm, z_rail_mm : contact point in the rail frame [mm]
    x_track_mm, y_track_mm, z_track_mm : contact point in the track frame [mm] (y positive to
        the left; x ahead of the wheelset centre, non-zero only with yaw: the wheel centres
        themselves sit at x = -/+ (d/2) sin(yaw) for the left/right wheel)
    contact_angle_rad : delta [rad], negative on tread and flange (module docstring)
    wheel_angle_rad : profile angle in the wheel frame atan(dz/dy) [rad] (roll excluded)
    rolling_radius_mm : r0 + z_wheel [mm]
    curvature_a_per_mm, curvature_b_per_mm : Hertz A (rolling) and B (lateral) [1/mm]
    wheel_curvature_per_mm, rail_curvature_per_mm : lateral profile curvatures [1/mm],
        positive where convex towards the other body
    """

    valid: NDArray[np.bool_]
    gap_mm: _FloatArray
    y_wheel_mm: _FloatArray
    z_wheel_mm: _FloatArray
    y_rail_mm: _FloatArray
    z_rail_mm: _FloatArray
    x_track_mm: _FloatArray
    y_track_mm: _FloatArray
    z_track_mm: _FloatArray
    contact_angle_rad: _FloatArray
    wheel_angle_rad: _FloatArray
    rolling_radius_mm: _FloatArray
    curvature_a_per_mm: _FloatArray
    curvature_b_per_mm: _FloatArray
    wheel_curvature_per_mm: _FloatArray
    rail_curvature_per_mm: _FloatArray

    def row(self, i: int) -> ContactPoint | None:
        """The patch of shift number ``i`` as a scalar ``ContactPoint`` (None if absent)."""
        if not self.valid[i]:
            return None
        values = {name: float(getattr(self, name)[i]) for name in _POINT_FIELDS}
        return ContactPoint(**values)


@dataclass(frozen=True)
class ContactPoint:
    """One contact point of one wheel (fields as ``ContactPatches``, scalars)."""

    gap_mm: float
    y_wheel_mm: float
    z_wheel_mm: float
    y_rail_mm: float
    z_rail_mm: float
    x_track_mm: float
    y_track_mm: float
    z_track_mm: float
    contact_angle_rad: float
    wheel_angle_rad: float
    rolling_radius_mm: float
    curvature_a_per_mm: float
    curvature_b_per_mm: float
    wheel_curvature_per_mm: float
    rail_curvature_per_mm: float


_POINT_FIELDS = tuple(ContactPoint.__dataclass_fields__)


@dataclass(frozen=True)
class WheelContacts:
    """Primary (gap 0) and secondary (two-point) patches of one wheel over N shifts."""

    primary: ContactPatches
    secondary: ContactPatches


@dataclass(frozen=True)
class ContactTable:
    """Contact geometry for an array of lateral shifts (see the module docstring for signs).

    shift_mm : wheelset lateral shift [mm], positive towards the left rail
    yaw_rad : wheelset yaw [rad] (input), positive turning the front to the left
    roll_rad : wheelset roll [rad], positive when the left wheel rises
    height_mm : vertical displacement of the axle from nominal [mm]
    left, right : contact patches of each wheel
    """

    shift_mm: _FloatArray
    yaw_rad: _FloatArray
    roll_rad: _FloatArray
    height_mm: _FloatArray
    left: WheelContacts
    right: WheelContacts

    @property
    def rolling_radius_difference_mm(self) -> _FloatArray:
        """Delta r = r_left - r_right at the primary patches [mm]; > 0 for a left shift."""
        return self.left.primary.rolling_radius_mm - self.right.primary.rolling_radius_mm



@dataclass(frozen=True)
class WheelsetContact:
    """Contact geometry at one shift: pose and all contact points per wheel."""

    shift_mm: float
    yaw_rad: float
    roll_rad: float
    height_mm: float
    left: tuple[ContactPoint, ...]
    right: tuple[ContactPoint, ...]

    @property
    def rolling_radius_difference_mm(self) -> float:
        """r_left - r_right at the primary patches [mm]."""
        return self.left[0].rolling_radius_mm - self.right[0].rolling_radius_mm
