"""Equations of the quasi-static curving of a two-axle bogie: the residual of its equilibrium.

Model (Wickens / Elkins-Gostling style steady curving, solved as a nonlinear equilibrium):

* Track: curvature kappa = +1/R for a curve to the vehicle's left (``direction="left"``), -1/R
  for a right curve, 0 for tangent track; cant raises the outer rail. Track frame: x in the
  running direction, y to the LEFT, z up. Axle 1 leads at x = +a, axle 2 at x = -a.
* Unknowns (12): per wheelset i the lateral shift y_i [mm] of its contact frame (rail level),
  its yaw psi_i [rad] relative to the local track tangent, the rolling-speed ratio
  Omega r0 / V = 1 + e_i and the elastic approaches d_left, d_right of its wheels [mm]; the
  bogie frame's lateral shift y_b [mm] and yaw psi_b [rad] (track tangent at the bogie centre).
* Equations (12): per wheelset lateral force, yaw moment, axle pitch moment (traction torque)
  and the vertical load of each wheel; bogie lateral force and yaw moment.
* Roll: each wheel rises by its rigid-contact lift (contact table) less its approach; the roll
  theta turns the contact points, a wheel radius below the axle, so the wheelset centre (where
  the primary suspension acts) is at y_i - r0 theta. This lets the flange contact climb onto
  the flank as in the rigid geometry with roll (``contact.geometry``).
* Wheel loads: static Q plus the load transfer -+Q (a_unb/g)(h/b0) of the cant deficiency
  (unbalanced lateral acceleration a_unb = V^2 kappa - g cant/1500 mm), larger on the outer
  wheel. Prescribing each wheel's vertical load stands for the heave and roll equilibrium; the
  gravitational stiffness comes through the lateral components N sin(delta) of the normal
  forces.
* Contacts: up to three patches per wheel from the local minima of a tabulated, smoothed
  wheel-rail gap (:class:`ContactTable`, built from the rigid multi-point geometry of
  ``contact.geometry`` with its solved roll), elastic (Hertz: N = (approach / delta_1)^1.5,
  ``contact.hertz``), attributed to the flange when wheel y < -30 mm.
* Creepages in each wheel's local frame (lateral axis towards that wheel's field side, the
  right wheel's frame mirrored so both wheels are described alike): xi = 1 - kappa y_c - (1+e)
  r/r0, eta = -s psi / cos(delta), phi = (-(1+e) sin(delta)/r0 + s kappa cos(delta)) [1/m];
  s = +1 left, -1 right; y_c the contact's distance from the track centre line. The lateral
  creepage carries the contact point's lead: the contact of a wheel yawed by psi lies about
  r tan(delta) psi ahead of or behind the axle (the rigid geometry with yaw,
  ``contact.geometry``), where the wheel's rotation moves the surface normal to the axle at
  V psi tan(delta); with the lateral slip -V psi this is -psi / cos(delta) in the contact plane
  (Wickens 2003; equal within 5 % to the exact kinematics of ``contact.creepages`` at the
  geometry's contact points, tests/physics/test_curving_creepages.py). Before stop 30 it was
  -s psi cos(delta), the lead left out: 3x too small at 55 deg, 9x at 70 deg (the flank).
  Creep forces of the equilibrium: FASTSIM (``contact.fastsim``, CONTACT's flexibilities,
  16 x 16) on each patch; the continuation runs with Kalker's linear theory saturated by
  Shen-Hedrick-Elkins (``contact.creep``, smooth, spin included) and its equilibrium starts
  Newton with FASTSIM; tau_max from FASTSIM on the final state.
* Primary suspension per axle box (longitudinal k_px at +-b1, lateral k_py); the secondary
  suspension carries the body share's unbalanced force and a yaw stiffness to the body chord
  (front bogie: body yaw -kappa L/2 relative to the bogie's tangent).

The unknowns are scaled (mm, mrad, 1e-3, mm) and the residual (forces [N] and moments [N m])
is divided by the static wheel load [N]; ``curving`` solves it (``equilibrium_solvers``).
Linear-theory check: Boocock (1969), Wickens (2003).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.bogie_residual_kernel import (
    N_CONSTS,
    bogie_jacobian_flat,
    bogie_residual_flat,
)
from wearcast.physics.contact.creep import creep_forces
from wearcast.physics.contact.fastsim import SPIN_OFFSET_FRACTION, fastsim_forces
from wearcast.physics.contact.hertz import STEEL_SHEAR_MODULUS_MPA
from wearcast.physics.contact.kalker import KALKER_ROW_SHAPE, KALKER_TABLE
from wearcast.physics.contact_candidates_kernel import N_SLOTS
from wearcast.physics.curving_table import (
    _NO_CONTACT_GAP_MM,
    MAX_CURVATURE_B_PER_MM,
    MIN_CURVATURE_B_PER_MM,
    PROMINENCE_MM,
    SEPARATION_MM,
    SHARE_GAP_MM,
    SLOT_FADE_MM,
    TAPE_CIRCLE_HALF_SPACING_MM,
    ContactTable,
)
from wearcast.physics.vehicles import GRAVITY_M_S2, BogieVehicle

#: Shear modulus of wheel and rail steel [MPa] (``contact.hertz``).
SHEAR_MODULUS_MPA = STEEL_SHEAR_MODULUS_MPA
#: Poisson's ratio of the creep laws (``contact.creep``'s and ``contact.fastsim``'s default).
CREEP_POISSON = 0.28
#: Sign of each side's lateral axis: left wheel at +y (vocabulary.SIDES order).
SIDE_SIGN = np.array([1.0, -1.0])

# state layout: [y1, psi1, e1, dL1, dR1, y2, psi2, e2, dL2, dR2, yb, psib]
# scaled units: y [mm], psi [mrad], e [1e-3], d [mm]
N_STATE = 12
#: Unknowns per wheelset in the state (y, psi, e, dL, dR) and the columns of the two
#: wheelsets' lateral shifts y.
N_WHEELSET_UNKNOWNS = 5
WHEELSET_SHIFT_COLUMNS = (0, N_WHEELSET_UNKNOWNS)


def wheelset_unknowns(q: NDArray) -> NDArray:
    """The two wheelsets' unknowns of bogie states q (..., N_STATE) as (..., 2,
    N_WHEELSET_UNKNOWNS): per wheelset y [mm], psi [mrad], e [1e-3], dL, dR [mm] (a view)."""
    q = np.asarray(q)
    return q[..., :2 * N_WHEELSET_UNKNOWNS].reshape(q.shape[:-1] + (2, N_WHEELSET_UNKNOWNS))


@dataclass(frozen=True)
class BogieContacts:
    """Per-contact quantities, shape (..., 2 wheelsets, 2 sides, ``N_SLOTS`` patch slots)."""

    normal_force_n: NDArray
    contact_angle_rad: NDArray
    xi: NDArray
    eta: NDArray
    phi_per_mm: NDArray
    fx_n: NDArray
    fy_n: NDArray
    mz_nmm: NDArray
    a_mm: NDArray
    b_mm: NDArray
    rolling_radius_m: NDArray
    wheel_y_mm: NDArray
    rail_y_mm: NDArray
    lateral_position_mm: NDArray


def bogie_contacts(table: ContactTable, y_mm, psi, e, d_mm, kappa, r0, mu,
              creep_grid: int | None = None) -> BogieContacts:
    """Contact forces of wheelsets; y, psi, e: (..., W); d: (..., W, 2).

    ``creep_grid`` None: creep forces from the smooth saturation law (``contact.creep``);
    an integer n: from FASTSIM on an n x n grid (``contact.fastsim.fastsim_forces``).

    Returns per-contact arrays of shape (..., W, 2, slots)."""
    s = SIDE_SIGN  # (2,)
    shift = s * y_mm[..., None]  # (..., W, 2)
    # the geometry depends on the shift only: evaluate it once per distinct shift (finite
    # difference Jacobians perturb the other unknowns with the shifts unchanged)
    if table.right is None:  # one rail profile: both wheels from the one (mirrored) table
        unique, inverse = np.unique(shift.reshape(-1), return_inverse=True)
        col = {k: v[inverse].reshape(shift.shape + v.shape[-1:])
               for k, v in table.candidates(unique).items()}  # (..., W, 2, slots)
    else:  # a rail per side: each wheel's candidates from its own rail's table
        per_side = []
        for i in range(2):
            sh = shift[..., i]
            unique, inverse = np.unique(sh.reshape(-1), return_inverse=True)
            per_side.append({k: v[inverse].reshape(sh.shape + v.shape[-1:])
                             for k, v in table.side(i).candidates(unique).items()})
        col = {k: np.stack([per_side[0][k], per_side[1][k]], axis=-2) for k in per_side[0]}
    ang = col["angle_rad"]
    cos, sin = np.cos(ang), np.sin(ang)
    approach = (d_mm[..., None] - col["gap_mm"]) * cos
    normal = col["weight"] * np.clip(approach, 0.0, None) ** 1.5 / col["approach1_mm"] ** 1.5
    n13 = np.cbrt(normal)
    a = col["a1_mm"] * n13
    b = col["b1_mm"] * n13
    k = kappa[..., None, None, None]
    ratio = (1.0 + e)[..., None, None]
    ss = s[:, None]
    xi = 1.0 - k * ss * col["lateral_mm"] / 1000.0 - ratio * col["radius_m"] / r0
    # the contact point of a yawed wheel leads the axle by about -r tan(delta) psi, so the
    # wheel's rotation adds a normal slip V psi tan(delta) to the lateral -V psi: in the contact
    # plane -psi (cos(delta) + sin(delta) tan(delta)) = -psi / cos(delta) (module docstring)
    eta = -ss * psi[..., None, None] / cos
    phi = (-ratio * sin / r0 + ss * k * cos) / 1000.0
    loaded = normal > 0
    a_safe, b_safe = np.where(loaded, a, 1.0), np.where(loaded, b, 1.0)
    if creep_grid is None:
        cf = creep_forces(xi, eta, phi, a_safe, b_safe, normal, mu, SHEAR_MODULUS_MPA)
        fx, fy, mz = cf.fx_n, cf.fy_n, cf.mz_nmm
    else:
        ff = fastsim_forces(xi, eta, phi, a_safe, b_safe, normal, mu, SHEAR_MODULUS_MPA,
                            n_x=creep_grid, n_y=creep_grid)
        fx, fy, mz = ff.fx_n, ff.fy_n, ff.mz_nmm
    return BogieContacts(normal_force_n=normal, contact_angle_rad=ang, xi=xi, eta=eta,
                         phi_per_mm=phi, fx_n=fx, fy_n=fy, mz_nmm=mz, a_mm=a, b_mm=b,
                         rolling_radius_m=col["radius_m"], wheel_y_mm=col["wheel_y_mm"],
                         rail_y_mm=col["rail_y_mm"], lateral_position_mm=col["lateral_mm"])


def wheelset_loads(c: BogieContacts):
    """Track-frame loads of the contacts on each wheelset: lateral [N], vertical per wheel [N],
    yaw moment [N m], axle moment sum r Fx [N m]. Inputs (..., W, 2, slots)."""
    s = SIDE_SIGN[:, None]
    cos, sin = np.cos(c.contact_angle_rad), np.sin(c.contact_angle_rad)
    lateral = np.sum(s * (-c.normal_force_n * sin + c.fy_n * cos), axis=(-2, -1))
    vertical = np.sum(c.normal_force_n * cos + c.fy_n * sin, axis=-1)  # (..., W, 2)
    yaw = np.sum(-(s * c.lateral_position_mm / 1000.0) * c.fx_n + s * c.mz_nmm * cos / 1000.0,
                 axis=(-2, -1))
    pitch = np.sum(c.rolling_radius_m * c.fx_n, axis=(-2, -1))
    return lateral, vertical, yaw, pitch


def wheelset_roll(table: ContactTable, y_mm, d_mm):
    """Wheelset roll [rad] (+ = left wheel up) from the wheels' rigid rise at the contact shift
    y (+ left) less their elastic approaches d (..., 2); each wheel's rise from its own
    rail's table (``ContactTable.side``)."""
    rise_left = table.rigid_rise(y_mm) - d_mm[..., 0]
    rise_right = table.side(1).rigid_rise(-y_mm) - d_mm[..., 1]
    return (rise_left - rise_right) / (2.0 * TAPE_CIRCLE_HALF_SPACING_MM)


def centre_shift(table: ContactTable, y_mm, d_mm):
    """Lateral shift of the wheelset centre [mm] for a contact (rail-level) shift y: the roll
    theta turns the contact points, a wheel radius below the axle, by r0 theta towards +y."""
    return y_mm - 1000.0 * table.nominal_radius_m * wheelset_roll(table, y_mm, d_mm)


def wheel_loads(vehicle: BogieVehicle, a_unb) -> NDArray:
    """Vertical wheel loads (..., 2 sides) [N] with the load transfer of the cant deficiency."""
    q = vehicle.wheel_load_n
    dq = q * (np.asarray(a_unb) / GRAVITY_M_S2) * vehicle.cog_height_m / (
        TAPE_CIRCLE_HALF_SPACING_MM / 1000.0)
    return q - SIDE_SIGN * np.asarray(dq)[..., None]


def bogie_residual(q, vehicle: BogieVehicle, table: ContactTable, kappa, a_unb, torque,
                    return_contacts: bool = False, creep_grid: int | None = None,
                    contacts: BogieContacts | None = None):
    """Scaled equilibrium residual of the bogie; q (..., 12), parameters (...).

    ``contacts``: the contacts of the state q from elsewhere (the pipeline's,
    ``curving_contacts``) instead of the table's."""
    kappa = np.asarray(kappa, dtype=float)
    a_unb = np.asarray(a_unb, dtype=float)
    ws = wheelset_unknowns(q)
    y = ws[..., 0]
    psi = ws[..., 1] * 1e-3
    e = ws[..., 2] * 1e-3
    d = ws[..., 3:5]
    yb = q[..., 10]
    psib = q[..., 11] * 1e-3
    r0 = table.nominal_radius_m
    c = (bogie_contacts(table, y, psi, e, d, kappa, r0, vehicle.friction, creep_grid)
         if contacts is None else contacts)
    lat, vert, yaw, pitch = wheelset_loads(c)
    am = vehicle.semi_wheelbase_m
    x = np.array([am, -am])
    k = kappa[..., None]
    y_centre = centre_shift(table, y, d)
    dy = (y_centre + 1000.0 * k * x**2 / 2.0 - yb[..., None] - 1000.0 * psib[..., None] * x
          ) / 1000.0
    dpsi = psi + k * x - psib[..., None]
    kpy = 2.0 * vehicle.primary_lateral_stiffness_n_per_m
    kpsi = 2.0 * vehicle.primary_longitudinal_stiffness_n_per_m * vehicle.primary_semi_spacing_m**2
    f_prim = -kpy * dy
    m_prim = -kpsi * dpsi
    q_wheel = vehicle.wheel_load_n
    res_lat = (lat + f_prim - vehicle.wheelset_mass_kg * a_unb[..., None]) / q_wheel
    res_yaw = (yaw + m_prim) / q_wheel
    res_pitch = (np.asarray(torque)[..., None] - pitch) / q_wheel
    loads = wheel_loads(vehicle, a_unb)[..., None, :]
    res_vert = (vert - loads) / q_wheel
    body_yaw = -kappa * vehicle.bogie_centre_distance_m / 2.0
    bogie_lat = (np.sum(-f_prim, axis=-1)
                 - (vehicle.bogie_mass_kg + vehicle.body_mass_kg) * a_unb) / q_wheel
    bogie_yaw = (np.sum(-m_prim - x * f_prim, axis=-1)
                 - vehicle.secondary_yaw_stiffness_nm_per_rad * (psib - body_yaw)) / q_wheel
    res = np.concatenate([
        np.stack([res_lat, res_yaw, res_pitch, res_vert[..., 0], res_vert[..., 1]],
                 axis=-1).reshape(q.shape[:-1] + (10,)),
        bogie_lat[..., None], bogie_yaw[..., None]], axis=-1)
    if return_contacts:
        return res, c
    return res


class CompiledBogie:
    """:func:`bogie_residual` of one vehicle on one contact table by the compiled kernels of
    ``bogie_residual_kernel`` (the same numbers to rounding; ``bogie_residual`` is their numpy
    reference), for the equilibrium solvers' many small batches: the table's arrays (each
    wheel's table, ``ContactTable.side``) and the vehicle's constants are gathered once.

    creep_grid : None for the saturation law, n for FASTSIM on an n x n grid
    """

    def __init__(self, vehicle: BogieVehicle, table: ContactTable,
                 creep_grid: int | None = None):
        self.tab = _kernel_tab(table)
        self.tab_right = self.tab if table.right is None else _kernel_tab(table.right)
        self.consts = np.array([
            table.nominal_radius_m, vehicle.friction, SHEAR_MODULUS_MPA, CREEP_POISSON,
            vehicle.wheel_load_n, vehicle.semi_wheelbase_m,
            2.0 * vehicle.primary_lateral_stiffness_n_per_m,
            2.0 * vehicle.primary_longitudinal_stiffness_n_per_m
            * vehicle.primary_semi_spacing_m**2,
            vehicle.wheelset_mass_kg, vehicle.bogie_mass_kg + vehicle.body_mass_kg,
            vehicle.secondary_yaw_stiffness_nm_per_rad, vehicle.bogie_centre_distance_m,
            GRAVITY_M_S2, vehicle.cog_height_m, TAPE_CIRCLE_HALF_SPACING_MM,
            MIN_CURVATURE_B_PER_MM, MAX_CURVATURE_B_PER_MM, PROMINENCE_MM, SEPARATION_MM,
            SHARE_GAP_MM, _NO_CONTACT_GAP_MM, SPIN_OFFSET_FRACTION, float(table.shift_mm[0]),
            float(table.shift_mm[1] - table.shift_mm[0]), SLOT_FADE_MM, float(N_SLOTS)])
        assert self.consts.size == N_CONSTS
        self.creep_grid = 0 if creep_grid is None else int(creep_grid)
        if self.creep_grid < 0:
            raise ValueError("creep_grid must be None or a positive grid size")

    def residual(self, q: NDArray, params: NDArray) -> NDArray[np.float64]:
        """Scaled residual (N, 12) of the states q (N, 12) at params (N, 3): curvature
        [1/m], unbalanced acceleration [m/s^2], torque [N m] (``bogie_residual``)."""
        return bogie_residual_flat(np.ascontiguousarray(q, dtype=float),
                                   np.ascontiguousarray(params, dtype=float), self.tab,
                                   self.tab_right, self.consts, self.creep_grid)

    def jacobian(self, q: NDArray, params: NDArray, steps: NDArray
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The residual at q (N, 12) and its forward-difference Jacobian (N, 12, 12) with the
        steps (N, 12): column c is (r(q + steps[:, c] e_c) - r(q)) / steps[:, c], the numbers
        the solvers' finite differences of :meth:`residual` give
        (``bogie_residual_kernel.bogie_jacobian_flat``: a perturbed state recomputes only
        the perturbed wheelset's contacts)."""
        return bogie_jacobian_flat(np.ascontiguousarray(q, dtype=float),
                                   np.ascontiguousarray(steps, dtype=float),
                                   np.ascontiguousarray(params, dtype=float), self.tab,
                                   self.tab_right, self.consts, self.creep_grid)


def _kernel_tab(table: ContactTable) -> tuple:
    """One wheel's table arrays in the kernel's order (``bogie_residual_flat``)."""
    return (table.gap_mm, table.gap2_per_mm, table.smoothing_mm, table.wheel_y_mm,
            table.wheel_z_mm, table.contact_slope, table.shift_mm, table.rigid_rise_mm,
            table.hertz_log_ratio, table.hertz_approach1, table.hertz_a1, table.hertz_b1,
            KALKER_TABLE, KALKER_ROW_SHAPE)


def compiled_residual(q, vehicle: BogieVehicle, table: ContactTable, kappa, a_unb, torque,
                      creep_grid: int | None = None) -> NDArray[np.float64]:
    """:func:`bogie_residual` (same arguments and numbers, to rounding) by the compiled kernel
    (:class:`CompiledBogie`). q (..., 12); kappa, a_unb, torque broadcast to q's leading
    shape. Returns (..., 12)."""
    q = np.asarray(q, dtype=float)
    lead = q.shape[:-1]
    params = np.stack([np.broadcast_to(np.asarray(v, dtype=float), lead).reshape(-1)
                       for v in (kappa, a_unb, torque)], axis=-1)
    out = CompiledBogie(vehicle, table, creep_grid).residual(q.reshape(-1, N_STATE), params)
    return out.reshape(lead + (N_STATE,))


def initial_state(vehicle: BogieVehicle, table: ContactTable) -> NDArray:
    """Centred wheelsets on tangent track, wheels loaded on the tread (each wheel's approach
    from its own rail's table)."""
    q = np.zeros(N_STATE)
    for i in range(2):
        centre = table.side(i).candidates(0.0)
        tread = int(np.argmin(centre["gap_mm"]))
        d0 = (centre["approach1_mm"][tread] * vehicle.wheel_load_n ** (2.0 / 3.0)
              / np.cos(centre["angle_rad"][tread]))
        q[[3 + i, 8 + i]] = d0
    return q

