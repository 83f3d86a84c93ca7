"""Contact locus of one wheel over its rail: the input of the non-Hertzian contact models.

For every wheel sample (a circle of the wheel surface, ``geometry``'s samples) the point
nearest the prismatic rail (``geometry`` module docstring, "Yaw"), its vertical gap over the
rail and the local geometry, for N poses with the roll solved (both wheels touching, as
``geometry.contact_table``) or prescribed (each wheel lowered onto its own rail, as CONTACT
treats the wheels of its wheel-rail cases one at a time).  Frames and signs: ``geometry``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.geometry import (
    WheelsetTrack,
    _gaps,
    _points,
    _pose_arrays,
    _prepare,
    _solve_roll,
)
from wearcast.physics.vocabulary import check_side

_FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class WheelLocus:
    """The contact locus of one wheel over its rail for N poses and the M wheel samples.

    For every wheel sample (a circle of the wheel surface) the point nearest the prismatic
    rail (module docstring, "Yaw"), its vertical gap over the rail and the local geometry.
    Arrays have shape (N, M) unless noted; entries where no rail lies below the wheel have
    ``valid`` False and an infinite gap.

    side : ``"left"`` or ``"right"``
    shift_mm, yaw_rad, roll_rad : pose (N,) [mm], [rad], [rad] (roll solved or prescribed)
    height_mm : vertical axle displacement (N,) [mm] at which this wheel first touches
    gap_mm : vertical undeformed gap at that height [mm] (min 0 over the samples)
    y_wheel_mm, z_wheel_mm : the sample in the wheel frame [mm], shape (M,)
    x_track_mm, y_track_mm, z_track_mm : the locus point on the wheel, track frame [mm]
        (at ``height_mm``; y positive to the left)
    z_rail_mm : rail height below it [mm]
    contact_angle_rad : delta of the rail at the locus point [rad] (sign as ``ContactPoint``)
    rolling_radius_mm : r0 + z_wheel [mm], shape (M,)
    curvature_a_per_mm : rolling-direction curvature A = cos(gamma) / (2 r) [1/mm], (M,)
    arc_length_mm : wheel arc length of the samples [mm], shape (M,)
    valid : a rail lies below the sample
    """

    side: str
    shift_mm: _FloatArray
    yaw_rad: _FloatArray
    roll_rad: _FloatArray
    height_mm: _FloatArray
    gap_mm: _FloatArray
    y_wheel_mm: _FloatArray
    z_wheel_mm: _FloatArray
    x_track_mm: _FloatArray
    y_track_mm: _FloatArray
    z_track_mm: _FloatArray
    z_rail_mm: _FloatArray
    contact_angle_rad: _FloatArray
    rolling_radius_mm: _FloatArray
    curvature_a_per_mm: _FloatArray
    arc_length_mm: _FloatArray
    valid: NDArray[np.bool_]

    @property
    def sign(self) -> float:
        """+1 for the left wheel, -1 for the right one (track y of the wheel's field side)."""
        return 1.0 if self.side == "left" else -1.0

    # Derived arrays the patch search and the planar patch problem read at every approach of
    # every round (``patches``, ``patch_plane``), computed once per locus.
    @cached_property
    def arc_step_mm(self) -> float:
        """Median spacing of the wheel samples along the wheel arc [mm]."""
        return float(np.median(np.diff(self.arc_length_mm)))

    @cached_property
    def track_width_mm(self) -> _FloatArray:
        """|d y_track / d sample| (N, M) [mm]: the lateral track width of each sample
        (``np.gradient`` along the samples)."""
        return np.abs(np.gradient(self.y_track_mm, axis=1))

    @cached_property
    def sqrt_curvature_a(self) -> _FloatArray:
        """sqrt(A) (M,) [mm^-1/2] of the rolling curvature ``curvature_a_per_mm``."""
        return np.sqrt(self.curvature_a_per_mm)


class NoContactError(ValueError):
    """A wheel that cannot touch its rail (no rail below it, or a profile that never comes
    near the rail); ``field`` names the input at fault (``"wheel"``, ``"rail"``, ``"shift"``)."""

    def __init__(self, field_name: str, reason: str) -> None:
        super().__init__(f"{field_name}: {reason}")
        self.field = field_name
        self.reason = reason


def wheel_locus(wt: WheelsetTrack, shifts_mm: ArrayLike, side: str = "left",
                yaw_rad: ArrayLike = 0.0, roll_rad: ArrayLike | None = None) -> WheelLocus:
    """Contact locus of one wheel for N poses (see ``WheelLocus``).

    Parameters
    ----------
    wt : wheelset and track
    shifts_mm : lateral shifts [mm] (N,), positive towards the left rail
    side : ``"left"`` or ``"right"``
    yaw_rad : yaw [rad], scalar or (N,), positive turning the front to the left
    roll_rad : wheelset roll [rad], scalar or (N,), positive when the left wheel rises;
        None solves it (both wheels touching, as ``contact_table``).  With a prescribed roll
        each wheel is lowered onto its own rail (``height_mm`` per wheel, as CONTACT treats
        the wheels of its wheel-rail cases one at a time).

    Raises ``NoContactError`` when no rail lies below the wheel at some pose.
    """
    check_side(side)
    shift, yaw = _pose_arrays(shifts_mm, yaw_rad)
    sides = _prepare(wt)
    r0 = wt.nominal_radius_mm
    if roll_rad is None:
        try:
            roll, _ = _solve_roll(sides, shift, yaw, r0)
        except ValueError as exc:
            raise NoContactError("shift", str(exc)) from exc
    else:
        roll = np.broadcast_to(np.asarray(roll_rad, dtype=float), shift.shape).copy()
        if np.any(np.abs(roll) > 0.1):
            raise ValueError("roll_rad beyond 0.1 rad")
    chosen = sides[0] if side == "left" else sides[1]
    gap, _ = _gaps(chosen, shift, roll, yaw, r0)
    finite = np.isfinite(gap)
    if not np.all(np.any(finite, axis=1)):
        raise NoContactError("shift", f"no rail below the {side} wheel for some shift")
    g0 = np.min(gap, axis=1)
    height = -g0
    axial = chosen.y_ws
    radius = -chosen.z_ws
    x_t, y_t, z_t = _points(chosen, shift, roll, yaw, r0, axial, radius, grid=True)
    z_t = z_t + height[:, None]
    s_r = np.interp(y_t, chosen.rail_y, chosen.rail_s)
    rail_angle = np.arctan(np.tan(chosen.rail.tangent_angle_at(s_r)))
    delta = -(rail_angle + chosen.inclination_rad)
    z_rail = np.interp(y_t, chosen.rail_y, chosen.rail_z, left=np.nan, right=np.nan)
    y_w, z_w = chosen.wheel.point(chosen.s_wheel)
    wheel_angle = np.arctan(np.tan(chosen.wheel.tangent_angle_at(chosen.s_wheel)))
    return WheelLocus(
        side=side, shift_mm=shift, yaw_rad=yaw, roll_rad=roll, height_mm=height,
        gap_mm=gap - g0[:, None], y_wheel_mm=y_w, z_wheel_mm=z_w, x_track_mm=x_t,
        y_track_mm=y_t, z_track_mm=z_t, z_rail_mm=z_rail, contact_angle_rad=delta,
        rolling_radius_mm=r0 + z_w, curvature_a_per_mm=np.cos(wheel_angle) / (2.0 * (r0 + z_w)),
        arc_length_mm=chosen.s_wheel, valid=finite,
    )
