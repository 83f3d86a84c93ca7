"""Rigid-body creepages of one wheel at given contact points (exact 3D kinematics).

The wheel material velocity at the contact point p is
v_w = V e_x + omega a x (p - c) + Omega e_z x p, with c the axle centre, a the unit axle vector
(turned by the yaw psi and the roll) and Omega = V kappa the rate at which the track frame
turns on a curve of curvature kappa (+ to the left; 0 on tangent track: a quasi-statically
curving wheelset is at rest in that frame, which follows the track at V along its centre
line); the rail is at rest. Creepages follow CONTACT's wheel-rail convention (body 1 = rail):
rail minus wheel velocity over V, in the contact frame (e_x along the track, e_s lateral in the
contact plane towards the wheel's field side, e_n the rail's outward normal):

    xi = -v_w.e_x / V,   eta = -v_w.e_s / V,   phi = -(omega a_out + s Omega e_z) . e_n / V  [1/mm],

a_out the axle direction pointing out of the track through that wheel, s = +1 for the left and
-1 for the right wheel (each wheel in its own mirrored frame). For small angles
xi = omega r / V - (1 - kappa y) (y the contact's track y, + left: the inner wheel of a curve
travels less than V, the outer more), eta = psi cos(delta) for a contact point under the axle
(x = 0) and psi / cos(delta) at the contact point of a yawed wheel, which leads the axle by
about -r tan(delta) psi (``geometry``), and
phi = -sin(delta +/- roll)/r - s kappa cos(delta) (the contact angle relative to the axle;
+ for the left wheel) (seed 000 §III, seed 002 §2; Kalker 1967; the curve terms as in the
quasi-static curving of ``curving``, Wickens 2003).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.vocabulary import check_side

_FloatArray = NDArray[np.float64]


def rigid_creepages(side: str, speed_m_s: float, angular_velocity_rad_s: ArrayLike,
                    shift_mm: ArrayLike, yaw_rad: ArrayLike, roll_rad: ArrayLike,
                    height_mm: ArrayLike, nominal_radius_mm: float, point_mm: ArrayLike,
                    contact_angle_rad: ArrayLike, track_curvature_per_m: ArrayLike = 0.0
                    ) -> tuple[_FloatArray, _FloatArray, _FloatArray]:
    """Rigid-body creepages (xi, eta, phi [1/mm]) of one wheel at given contact points.

    Parameters
    ----------
    side : ``"left"`` or ``"right"``
    speed_m_s : forward speed V of the track frame along the centre line [m/s]
    angular_velocity_rad_s : axle angular velocity omega [rad/s], scalar or (N,)
    shift_mm, yaw_rad, roll_rad, height_mm : wheelset pose (N,) or scalars [mm], [rad], [rad],
        [mm] (``geometry``: shift of the axle centre, + to the left; yaw + nose left; roll +
        left wheel up)
    nominal_radius_mm : r0 [mm] (axle height above rail level at zero height)
    point_mm : (3, N) the contact point (x, y, z) in the track frame [mm] (origin on the track
        centre line at rail level) with the axle centre at (0, shift, r0 + height)
    contact_angle_rad : (N,) delta there (``geometry``'s sign)
    track_curvature_per_m : kappa [1/m] of the curve, + to the left, scalar or (N,)

    Returns
    -------
    xi, eta, phi in the wheel's local contact frame (module docstring).
    """
    check_side(side)
    if speed_m_s <= 0:
        raise ValueError("speed_m_s must be positive")
    sign = 1.0 if side == "left" else -1.0
    point = np.asarray(point_mm, dtype=float)
    shape = point.shape[1:]
    psi = np.broadcast_to(np.asarray(yaw_rad, dtype=float), shape)
    roll = np.broadcast_to(np.asarray(roll_rad, dtype=float), shape)
    omega = np.broadcast_to(np.asarray(angular_velocity_rad_s, dtype=float), shape)
    kappa_per_mm = np.broadcast_to(np.asarray(track_curvature_per_m, dtype=float),
                                   shape) / 1000.0
    speed = speed_m_s * 1000.0  # mm/s
    turn = speed * kappa_per_mm  # Omega [rad/s]
    # unit axle vector (track frame, x forward, y left, z up), as geometry._points
    axle = np.stack([-np.sin(psi), np.cos(psi) * np.cos(roll), np.cos(psi) * np.sin(roll)])
    centre = np.stack([np.zeros(shape), np.broadcast_to(np.asarray(shift_mm, dtype=float), shape),
                       nominal_radius_mm + np.broadcast_to(np.asarray(height_mm, dtype=float),
                                                           shape)])
    v_wheel = omega * np.cross(axle, point - centre, axis=0)
    v_wheel[0] += speed - turn * point[1]  # Omega e_z x p
    v_wheel[1] += turn * point[0]
    delta = np.broadcast_to(np.asarray(contact_angle_rad, dtype=float), shape)
    e_s = np.stack([np.zeros(shape), sign * np.cos(delta), -np.sin(delta)])
    e_n = np.stack([np.zeros(shape), sign * np.sin(delta), np.cos(delta)])
    xi = -v_wheel[0] / speed
    eta = -np.sum(v_wheel * e_s, axis=0) / speed
    phi = -(omega * np.sum(sign * axle * e_n, axis=0) + sign * turn * e_n[2]) / speed
    return xi, eta, phi
