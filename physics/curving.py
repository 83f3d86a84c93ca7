"""Quasi-static curving of a two-axle bogie: wheelset shifts and yaws, contact forces.

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
  r/r0, eta = -s psi cos(delta), phi = (-(1+e) sin(delta)/r0 + s kappa cos(delta)) [1/m]; s = +1
  left, -1 right; y_c the contact's distance from the track centre line. Creep forces of the
  equilibrium: FASTSIM (``contact.fastsim``, CONTACT's flexibilities, 16 x 16) on each patch;
  the continuation runs with Kalker's linear theory saturated by Shen-Hedrick-Elkins
  (``contact.creep``, smooth, spin included) and its equilibrium starts Newton with FASTSIM;
  tau_max from FASTSIM on the final state.
* Primary suspension per axle box (longitudinal k_px at +-b1, lateral k_py); the secondary
  suspension carries the body share's unbalanced force and a yaw stiffness to the body chord
  (front bogie: body yaw -kappa L/2 relative to the bogie's tangent).

Solution from straight track with continuation in the load parameter (curvature, unbalanced
acceleration and torque scaled together from 0), a batched damped Newton method with
``scipy.optimize.root`` (hybr) as fallback; failure raises :class:`CurvingConvergenceError`.
Seeds 001 §4 and 003 §5.3 (speed from an unbalanced lateral acceleration / cant deficiency);
linear-theory check: Boocock (1969), Wickens (2003).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.creep import creep_forces
from wearcast.physics.contact.fastsim import Bound, fastsim, fastsim_forces
from wearcast.physics.contact.hertz import STEEL_SHEAR_MODULUS_MPA

# the contact table lives in curving_table; its names are re-exported for the table's users
from wearcast.physics.curving_contacts import pipeline_contacts
from wearcast.physics.curving_table import GAUGE_MM as GAUGE_MM
from wearcast.physics.curving_table import TAPE_CIRCLE_HALF_SPACING_MM, vehicle_contact_table
from wearcast.physics.curving_table import ContactTable as ContactTable
from wearcast.physics.curving_table import build_contact_table as build_contact_table
from wearcast.physics.curving_table import conformal_half_width_mm as conformal_half_width_mm
from wearcast.physics.curving_table import conical_wheel as conical_wheel
from wearcast.physics.curving_table import contact_table_for as contact_table_for
from wearcast.physics.curving_table import measured_wheel_table_for as measured_wheel_table_for
from wearcast.physics.equilibrium_solvers import continuation_batch, newton_batch, scipy_polish
from wearcast.physics.vehicles import GRAVITY_M_S2, BogieVehicle
from wearcast.physics.vocabulary import REGION_SPLIT_Y_MM, SIDES, rail_for
from wearcast.physics.wear_measures import t_gamma as wear_t_gamma
from wearcast.physics.wear_measures import tau_max as wear_tau_max

#: Lateral distance used for the cant angle (rail-centre spacing) [mm].
CANT_BASE_MM = 1500.0
#: Wheel-frame lateral position separating flange (y < split) from tread [mm]: the vocabulary's.
FLANGE_SPLIT_Y_MM = REGION_SPLIT_Y_MM
#: Shear modulus of wheel and rail steel [MPa] (``contact.hertz``).
SHEAR_MODULUS_MPA = STEEL_SHEAR_MODULUS_MPA
#: Default tolerance on the scaled equilibrium residual (see ``solve_curving``).
DEFAULT_TOLERANCE = 1e-6
#: Traction bound of the FASTSIM solution tau_max is read from: the elliptic bound mu p(x, y) has
#: the Hertz pressure's shape, so in the slip zone tau_max <= mu p0 as in the exact (variational)
#: solution; the parabolic bound (FASTSIM's default for forces) peaks at 4/3 mu p0 and overstates
#: tau_max by up to 33 % (tests/physics/test_curving.py, full slip).
TAU_MAX_BOUND: Bound = "elliptic"
#: FASTSIM grid (n x n) of the creep forces in the curving equilibrium; 16 x 16 keeps the forces
#: within 0.03 mu Fn of a 40 x 40 grid at the equilibria of ``benchmarks/curving_creep_law.py``.
DEFAULT_CREEP_GRID = 16
#: Tolerance of the equilibrium with FASTSIM's forces (scaled residual, as DEFAULT_TOLERANCE):
#: FASTSIM's totals are only piecewise smooth in the creepages (grid elements switch between
#: adhesion and slip), so Newton can stall near 1e-5 of the wheel load: a solve that stalls
#: below 1e-4 (5 N on a 50 kN wheel) counts as converged. ``CurvingResult.residual_norm``
#: reports what was reached.
FASTSIM_TOLERANCE = 1e-4
_SIDE_SIGN = np.array([1.0, -1.0])  # left wheel at +y (vocabulary.SIDES order)


class CurvingConvergenceError(RuntimeError):
    """The curving equilibrium was not found.

    Attributes: ``radius_m`` (signed by direction, inf for tangent), ``residual_norm``.
    """

    def __init__(self, message: str, radius_m: float, residual_norm: float):
        super().__init__(f"{message} (radius {radius_m:g} m, residual norm {residual_norm:.3g})")
        self.radius_m = radius_m
        self.residual_norm = residual_norm


# --------------------------------------------------------------------------------------------
# Loads, operating point
# --------------------------------------------------------------------------------------------

def speed_from_cant_deficiency(radius_m: ArrayLike, cant_mm: ArrayLike,
                               unbalanced_acceleration_m_s2: float = 0.58,
                               max_speed_m_s: float | None = None) -> NDArray[np.float64]:
    """Curving speed that gives a prescribed unbalanced lateral acceleration.

    V = sqrt(R (a_nc + g cant / 1500 mm)); tangent track (R = inf/NaN) gives ``max_speed_m_s``
    (or inf). Seed 001 §4 uses a_nc = 0.58 m/s^2, seed 003 §5.3 a_nc = 0.8 m/s^2 capped by the
    line speed. A cant deficiency limit D [mm] is the same as a_nc = g D / 1500.

    Parameters
    ----------
    radius_m : curve radius [m]; cant_mm : cant [mm]
    unbalanced_acceleration_m_s2 : a_nc [m/s^2]
    max_speed_m_s : optional cap [m/s]

    Returns
    -------
    speed [m/s]
    """
    r = np.asarray(radius_m, dtype=float)
    c = np.asarray(cant_mm, dtype=float)
    finite = np.isfinite(r) & (r > 0)
    base = unbalanced_acceleration_m_s2 + GRAVITY_M_S2 * c / CANT_BASE_MM
    v = np.where(finite, np.sqrt(np.clip(np.where(finite, r, 1.0) * base, 0.0, None)), np.inf)
    if max_speed_m_s is not None:
        v = np.minimum(v, max_speed_m_s)
    return v


@dataclass(frozen=True)
class CurveCase:
    """One operating point: signed curvature kappa [1/m] (+ left), unbalanced lateral
    acceleration [m/s^2] (+y), speed [m/s], traction torque per axle [N m]."""

    curvature_per_m: float
    unbalanced_acceleration_m_s2: float
    speed_m_s: float
    torque_nm: float

    def scaled(self, t: float) -> CurveCase:
        return CurveCase(t * self.curvature_per_m, t * self.unbalanced_acceleration_m_s2,
                         self.speed_m_s, t * self.torque_nm)


def curve_case(radius_m: float | None, cant_mm: float = 0.0, speed_m_s: float | None = None,
               direction: str = "left", unbalanced_acceleration_m_s2: float = 0.58,
               torque_nm: float = 0.0, tangent_speed_m_s: float = 30.0) -> CurveCase:
    """Build a :class:`CurveCase` from radius [m] (None/inf = tangent), cant [mm], speed [m/s]
    (None: from the unbalanced acceleration, :func:`speed_from_cant_deficiency`), direction."""
    if direction not in SIDES:
        raise ValueError(f"direction must be 'left' or 'right', got {direction!r}")
    if radius_m is not None and np.isfinite(radius_m) and radius_m <= 0:
        raise ValueError(f"radius_m must be positive, got {radius_m}")
    if cant_mm < 0:
        raise ValueError(f"cant_mm must be >= 0, got {cant_mm}")
    if radius_m is None or not np.isfinite(radius_m):  # tangent track
        v = tangent_speed_m_s if speed_m_s is None else speed_m_s
        return CurveCase(0.0, 0.0, float(v), torque_nm)
    if speed_m_s is None:
        speed_m_s = float(speed_from_cant_deficiency(radius_m, cant_mm,
                                                     unbalanced_acceleration_m_s2))
    if speed_m_s <= 0:
        raise ValueError(f"speed must be positive, got {speed_m_s}")
    sign = 1.0 if direction == "left" else -1.0
    kappa = sign / radius_m
    a_unb = speed_m_s**2 * kappa - sign * GRAVITY_M_S2 * cant_mm / CANT_BASE_MM
    return CurveCase(kappa, a_unb, float(speed_m_s), torque_nm)


# --------------------------------------------------------------------------------------------
# Equilibrium
# --------------------------------------------------------------------------------------------

# state layout: [y1, psi1, e1, dL1, dR1, y2, psi2, e2, dL2, dR2, yb, psib]
# scaled units: y [mm], psi [mrad], e [1e-3], d [mm]
_N_STATE = 12


@dataclass(frozen=True)
class _Contacts:
    """Per-contact quantities, shape (..., 2 wheelsets, 2 sides, 3 patch slots)."""

    normal_n: NDArray
    angle_rad: NDArray
    xi: NDArray
    eta: NDArray
    phi_per_mm: NDArray
    fx_n: NDArray
    fy_n: NDArray
    mz_nmm: NDArray
    a_mm: NDArray
    b_mm: NDArray
    radius_m: NDArray
    wheel_y_mm: NDArray
    rail_y_mm: NDArray
    lateral_mm: NDArray


def _contacts(table: ContactTable, y_mm, psi, e, d_mm, kappa, r0, mu,
              creep_grid: int | None = None) -> _Contacts:
    """Contact forces of wheelsets; y, psi, e: (..., W); d: (..., W, 2).

    ``creep_grid`` None: creep forces from the smooth saturation law (``contact.creep``);
    an integer n: from FASTSIM on an n x n grid (``contact.fastsim.fastsim_forces``).

    Returns per-contact arrays of shape (..., W, 2, slots)."""
    s = _SIDE_SIGN  # (2,)
    shift = s * y_mm[..., None]  # (..., W, 2)
    # the geometry depends on the shift only: evaluate it once per distinct shift (finite
    # difference Jacobians perturb the other unknowns with the shifts unchanged)
    unique, inverse = np.unique(shift.reshape(-1), return_inverse=True)
    col = {k: v[inverse].reshape(shift.shape + v.shape[-1:])
           for k, v in table.candidates(unique).items()}  # (..., W, 2, slots)
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
    eta = -ss * psi[..., None, None] * cos
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
    return _Contacts(normal, ang, xi, eta, phi, fx, fy, mz, a, b, col["radius_m"],
                     col["wheel_y_mm"], col["rail_y_mm"], col["lateral_mm"])


def _wheelset_loads(c: _Contacts):
    """Track-frame loads of the contacts on each wheelset: lateral [N], vertical per wheel [N],
    yaw moment [N m], axle moment sum r Fx [N m]. Inputs (..., W, 2, slots)."""
    s = _SIDE_SIGN[:, None]
    cos, sin = np.cos(c.angle_rad), np.sin(c.angle_rad)
    lateral = np.sum(s * (-c.normal_n * sin + c.fy_n * cos), axis=(-2, -1))
    vertical = np.sum(c.normal_n * cos + c.fy_n * sin, axis=-1)  # (..., W, 2)
    yaw = np.sum(-(s * c.lateral_mm / 1000.0) * c.fx_n + s * c.mz_nmm * cos / 1000.0,
                 axis=(-2, -1))
    pitch = np.sum(c.radius_m * c.fx_n, axis=(-2, -1))
    return lateral, vertical, yaw, pitch


def _roll(table: ContactTable, y_mm, d_mm):
    """Wheelset roll [rad] (+ = left wheel up) from the wheels' rigid rise at the contact shift
    y (+ left) less their elastic approaches d (..., 2)."""
    rise_left = table.rigid_rise(y_mm) - d_mm[..., 0]
    rise_right = table.rigid_rise(-y_mm) - d_mm[..., 1]
    return (rise_left - rise_right) / (2.0 * TAPE_CIRCLE_HALF_SPACING_MM)


def _centre_shift(table: ContactTable, y_mm, d_mm):
    """Lateral shift of the wheelset centre [mm] for a contact (rail-level) shift y: the roll
    theta turns the contact points, a wheel radius below the axle, by r0 theta towards +y."""
    return y_mm - 1000.0 * table.nominal_radius_m * _roll(table, y_mm, d_mm)


def _wheel_loads(vehicle: BogieVehicle, a_unb) -> NDArray:
    """Vertical wheel loads (..., 2 sides) [N] with the load transfer of the cant deficiency."""
    q = vehicle.wheel_load_n
    dq = q * (np.asarray(a_unb) / GRAVITY_M_S2) * vehicle.cog_height_m / (
        TAPE_CIRCLE_HALF_SPACING_MM / 1000.0)
    return q - _SIDE_SIGN * np.asarray(dq)[..., None]


def _bogie_residual(q, vehicle: BogieVehicle, table: ContactTable, kappa, a_unb, torque,
                    return_contacts: bool = False, creep_grid: int | None = None,
                    contacts: _Contacts | None = None):
    """Scaled equilibrium residual of the bogie; q (..., 12), parameters (...).

    ``contacts``: the contacts of the state q from elsewhere (the pipeline's,
    ``curving_contacts``) instead of the table's."""
    kappa = np.asarray(kappa, dtype=float)
    a_unb = np.asarray(a_unb, dtype=float)
    ws = q[..., :10].reshape(q.shape[:-1] + (2, 5))
    y = ws[..., 0]
    psi = ws[..., 1] * 1e-3
    e = ws[..., 2] * 1e-3
    d = ws[..., 3:5]
    yb = q[..., 10]
    psib = q[..., 11] * 1e-3
    r0 = table.nominal_radius_m
    c = (_contacts(table, y, psi, e, d, kappa, r0, vehicle.friction, creep_grid)
         if contacts is None else contacts)
    lat, vert, yaw, pitch = _wheelset_loads(c)
    am = vehicle.semi_wheelbase_m
    x = np.array([am, -am])
    k = kappa[..., None]
    y_centre = _centre_shift(table, y, d)
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
    loads = _wheel_loads(vehicle, a_unb)[..., None, :]
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


def _initial_state(vehicle: BogieVehicle, table: ContactTable) -> NDArray:
    """Centred wheelsets on tangent track, wheels loaded on the tread."""
    centre = table.candidates(0.0)
    tread = int(np.argmin(centre["gap_mm"]))
    d0 = (centre["approach1_mm"][tread] * vehicle.wheel_load_n ** (2.0 / 3.0)
          / np.cos(centre["angle_rad"][tread]))
    q = np.zeros(_N_STATE)
    q[[3, 4, 8, 9]] = d0
    return q


# --------------------------------------------------------------------------------------------
# Contacts from the contact pipeline at the equilibrium pose
# --------------------------------------------------------------------------------------------

def _pipeline_at(q, vehicle: BogieVehicle, table: ContactTable, params, creep_grid: int
                 ) -> tuple[_Contacts, NDArray, NDArray, dict[int, str]]:
    """The pipeline's contacts (``curving_contacts``) at the states q (m, 12) with parameters
    (m, >= 2): (contacts, peak pressures [MPa], ok (m,), errors per row)."""
    m = q.shape[0]
    ws = q[:, :10].reshape(m, 2, 5)
    y, d = ws[..., 0], ws[..., 3:5]
    loads = np.broadcast_to(_wheel_loads(vehicle, params[:, 1])[:, None, :], (m, 2, 2))
    pc = pipeline_contacts(table.track, TAPE_CIRCLE_HALF_SPACING_MM - table.rail_offset_mm,
                           _centre_shift(table, y, d), ws[..., 1] * 1e-3, _roll(table, y, d),
                           1.0 + ws[..., 2] * 1e-3, loads, params[:, 0], vehicle.friction,
                           SHEAR_MODULUS_MPA, creep_grid)
    c = _Contacts(pc.normal_n, pc.angle_rad, pc.xi, pc.eta, pc.phi_per_mm, pc.fx_n, pc.fy_n,
                  pc.mz_nmm, pc.a_mm, pc.b_mm, pc.radius_m, pc.wheel_y_mm, pc.rail_y_mm,
                  pc.lateral_mm)
    return c, pc.peak_pressure_mpa, pc.ok, pc.errors


#: Scaled residual (as DEFAULT_TOLERANCE) at which the equilibrium with the pipeline's forces
#: counts as found (``_pipeline_equilibrium``): 1e-3 of the static wheel load, 50 N on a 50 kN
#: wheel. The pipeline's forces are only piecewise smooth in the pose (patches merge and split,
#: Hertz and the coarse BEM take turns, its normal / tangential coupling settles to 1e-4 of the
#: load), so a tighter tolerance is not reached.
PIPELINE_TOLERANCE = 1e-3
#: Most Broyden iterations of ``_pipeline_equilibrium``.
PIPELINE_MAX_ITERATIONS = 40
#: Largest Broyden step in any scaled unknown of ``_pipeline_equilibrium`` (mm, mrad, 1e-3).
PIPELINE_MAX_STEP = 1.0
#: Residual rows of the wheels' vertical loads (state layout above).
_VERTICAL_ROWS = [3, 4, 8, 9]


def _pipeline_residual(q, vehicle: BogieVehicle, table: ContactTable, params, grid: int,
                       creep_grid: int | None):
    """The bogie residual with the pipeline's contact forces at the states q (m, 12).

    The pipeline carries each wheel's prescribed vertical load by construction, so the vertical
    rows keep the table's equations: they fix the approaches d, which only set the roll.
    Returns (contacts, peak pressures, ok, errors, residual (m, 12))."""
    c, peak, ok, errors = _pipeline_at(q, vehicle, table, params, grid)
    res = _bogie_residual(q, vehicle, table, params[:, 0], params[:, 1], params[:, 2],
                          contacts=c)
    res_t = _bogie_residual(q, vehicle, table, params[:, 0], params[:, 1], params[:, 2],
                            creep_grid=creep_grid)
    res[:, _VERTICAL_ROWS] = res_t[:, _VERTICAL_ROWS]
    return c, peak, ok, errors, res


def _pipeline_equilibrium(q, vehicle: BogieVehicle, table: ContactTable, params, grid: int,
                          creep_grid: int | None) -> NDArray:
    """Equilibrium states (m, 12) of the bogie with the pipeline's contact forces.

    Broyden's ("good") method on ``_pipeline_residual`` from the table's equilibria q, the
    initial Jacobian the table's (forward differences): each iteration is one pipeline
    evaluation of the rows not yet converged; a step that raises the residual is cut to 0.3.
    A plain defect correction with the table's Jacobian oscillates: the pipeline's forces
    respond 2-4 times as stiffly to the state (its conformal patches are larger than the
    table's Hertz ellipses). Returns per row the state of the smallest residual found (rows
    where the pipeline fails keep theirs; the caller reports them).
    """
    q = np.array(q, dtype=float)
    m, n = q.shape

    def table_res(qq, pp):
        return _bogie_residual(qq, vehicle, table, pp[:, 0], pp[:, 1], pp[:, 2],
                               creep_grid=creep_grid)

    steps = 1e-6 * np.maximum(1.0, np.abs(q))
    states = q[:, None, :] + np.concatenate([np.zeros((m, 1, n)),
                                             steps[:, :, None] * np.eye(n)], axis=1)
    r_all = table_res(states.reshape(-1, n), np.repeat(params, n + 1, axis=0)).reshape(
        m, n + 1, n)
    jac = np.swapaxes((r_all[:, 1:] - r_all[:, :1]) / steps[:, :, None], 1, 2)
    _, _, ok, _, f = _pipeline_residual(q, vehicle, table, params, grid, creep_grid)
    norm = np.linalg.norm(f, axis=-1)
    best_q, best_norm = q.copy(), norm.copy()
    for _ in range(PIPELINE_MAX_ITERATIONS):
        act = np.nonzero(ok & ~(best_norm < PIPELINE_TOLERANCE))[0]
        if act.size == 0:
            break
        try:
            dx = np.linalg.solve(jac[act], -f[act][..., None])[..., 0]
        except np.linalg.LinAlgError:
            break
        # a step of at most PIPELINE_MAX_STEP in every scaled unknown (mm, mrad, 1e-3): far
        # from the table's equilibrium Broyden's Jacobian is not to be trusted
        dx *= np.minimum(1.0, PIPELINE_MAX_STEP / np.max(np.abs(dx), axis=-1))[:, None]
        x_new = q[act] + dx
        _, _, ok_n, _, f_new = _pipeline_residual(x_new, vehicle, table, params[act], grid,
                                                  creep_grid)
        worse = ok_n & (np.linalg.norm(f_new, axis=-1) > norm[act])
        if np.any(worse):
            w = np.nonzero(worse)[0]
            x_new[w] = q[act[w]] + 0.3 * dx[w]
            _, _, ok_w, _, f_w = _pipeline_residual(x_new[w], vehicle, table, params[act[w]],
                                                    grid, creep_grid)
            ok_n[w], f_new[w] = ok_w, f_w
        ok[act] = ok_n
        s_step = x_new - q[act]
        y_step = f_new - f[act]
        denom = np.maximum(np.sum(s_step * s_step, axis=-1), 1e-300)
        jac[act] += (np.einsum("ki,kj->kij", y_step - np.einsum("kij,kj->ki", jac[act], s_step),
                               s_step) / denom[:, None, None])
        q[act], f[act] = x_new, f_new
        norm[act] = np.linalg.norm(f_new, axis=-1)
        better = act[ok_n & (norm[act] < best_norm[act])]
        best_q[better], best_norm[better] = q[better], norm[better]
    return best_q


# --------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class CurvingResult:
    """Quasi-static curving solution of one bogie.

    State: ``wheelset_shift_mm`` (2,) of the wheelset centres (+ = left), ``contact_shift_mm``
    (2,) the same at rail level (the contact frame; differs by r0 times the roll),
    ``wheelset_roll_rad`` (2,) (+ = left wheel up), ``wheelset_yaw_rad`` (2,) (relative to the
    local track tangent, + = nose left), ``rolling_ratio`` (2,) Omega r0/V, ``bogie_shift_mm``,
    ``bogie_yaw_rad``. Per contact, arrays of shape (2 axles, 2 sides (left, right), 3 patch
    slots, field side first; the region follows from ``wheel_y_mm``): normal force [N],
    contact angle [rad], position on the wheel (wheel frame)
    and rail (rail frame) [mm], lateral distance from the track centre [mm], rolling radius
    [m], creepages xi, eta [-], phi [1/mm] and creep forces Fx, Fy [N], spin moment Mz [N mm]
    (each wheel in its own frame, lateral towards its field side), Hertz semi-axes a, b [mm] and
    p0 [MPa], and from FASTSIM on this state tau_max [MPa] and T_gamma [N]; ``in_contact`` marks
    loaded patches. Also: the operating point, ``high_rail_side`` (None on tangent track) and the
    residual norm of the scaled equilibrium and the solver ``state`` (scaled unknowns, used to
    continue from this solution); ``saturation_state`` the equilibrium of the smooth saturation
    law the solve went through (the start of the Newton solution with FASTSIM's forces; equal
    to ``state`` without them), the warm start of a later solve (``initial_states``), which
    runs the saturation law first; ``creep_grid`` the FASTSIM grid of the equilibrium's creep
    forces (None: the saturation law, ``contact.creep``).

    ``pipeline`` (with ``contact_pipeline=True``, else None): the contacts of the one contact
    pipeline (``curving_contacts``) at this equilibrium's pose of every wheel, same shape and
    signs as above, keyed ``normal_n``, ``angle_rad``, ``wheel_y_mm``, ``rail_y_mm``,
    ``lateral_mm``, ``radius_m``, ``xi``, ``eta``, ``phi_per_mm``, ``fx_n``, ``fy_n``,
    ``mz_nmm``, ``a_mm``, ``b_mm``, ``peak_pressure_mpa``, ``tau_max_mpa``, ``t_gamma_n``,
    ``in_contact``, and the pose it was evaluated at: ``state`` (as ``state``),
    ``wheelset_shift_mm``, ``wheelset_roll_rad``, ``wheelset_yaw_rad`` (2,) (the table's, or
    with ``pipeline_equilibrium`` the equilibrium of the pipeline's forces);
    ``pipeline_residual_norm`` the scaled bogie equilibrium residual there with the pipeline's
    forces in place of the table's (the vertical rows the table's).
    """

    radius_m: float
    direction: str
    cant_mm: float
    speed_m_s: float
    unbalanced_acceleration_m_s2: float
    wheelset_shift_mm: NDArray
    contact_shift_mm: NDArray
    wheelset_roll_rad: NDArray
    wheelset_yaw_rad: NDArray
    rolling_ratio: NDArray
    bogie_shift_mm: float
    bogie_yaw_rad: float
    normal_force_n: NDArray
    contact_angle_rad: NDArray
    wheel_y_mm: NDArray
    rail_y_mm: NDArray
    lateral_position_mm: NDArray
    rolling_radius_m: NDArray
    xi: NDArray
    eta: NDArray
    phi_per_mm: NDArray
    fx_n: NDArray
    fy_n: NDArray
    mz_nmm: NDArray
    a_mm: NDArray
    b_mm: NDArray
    p0_mpa: NDArray
    tau_max_mpa: NDArray
    t_gamma_n: NDArray
    in_contact: NDArray
    residual_norm: float
    state: NDArray
    saturation_state: NDArray | None = None
    creep_grid: int | None = None
    pipeline: dict[str, NDArray] | None = None
    pipeline_residual_norm: float = float("nan")

    @property
    def high_rail_side(self) -> str | None:
        """Side of the wheels on the high rail: right in a left curve (docs/conventions.md)."""
        if not np.isfinite(self.radius_m):
            return None
        return "right" if self.direction == "left" else "left"

    def rail_of(self, side: str) -> str:
        """``high``, ``low`` or ``tangent`` for the wheels on ``side`` (vocabulary.rail_for)."""
        return rail_for(None if not np.isfinite(self.radius_m) else self.direction,  # type: ignore[arg-type]
                        side)  # type: ignore[arg-type]

    @property
    def flange_contact(self) -> NDArray:
        """(2 axles, 2 sides): the wheel has a loaded patch on its flange (y < -30 mm)."""
        return np.any(self.in_contact & (self.wheel_y_mm < FLANGE_SPLIT_Y_MM), axis=-1)


def contact_wear_measures(xi, eta, phi_per_mm, a_mm, b_mm, normal_force_n, fx_n, fy_n, mz_nmm,
                          mu, fastsim_grid: int = 20) -> dict[str, NDArray]:
    """Tγ, τmax and p0 per contact; FASTSIM batched over the loaded contacts.

    Parameters
    ----------
    xi, eta [-], phi_per_mm [1/mm], a_mm, b_mm [mm], normal_force_n [N], creep forces
    fx_n, fy_n [N] and spin moment mz_nmm [N mm] of the equilibrium: any common shape
    mu : friction coefficient; fastsim_grid : n for the n x n FASTSIM grid

    Returns
    -------
    dict with ``t_gamma_n`` = |Fx xi| + |Fy eta| + |Mz phi| [N] (seed 004 eq. 1),
    ``tau_max_mpa`` the largest surface shear traction of the FASTSIM solution [MPa]
    (elliptic traction bound ``TAU_MAX_BOUND``, CONTACT's flexibilities; seed 001 §2.2,
    Al-Maliki), ``p0_mpa`` the Hertz
    peak pressure 3N/(2 pi a b), ``in_contact`` (loaded with at least 1 N). Unloaded contacts
    get zeros.
    """
    shape = np.shape(normal_force_n)
    fn = np.asarray(normal_force_n, dtype=float).reshape(-1)
    loaded = fn >= 1.0
    flat = [np.broadcast_to(np.asarray(v, dtype=float), shape).reshape(-1)
            for v in (xi, eta, phi_per_mm, a_mm, b_mm, fx_n, fy_n, mz_nmm)]
    t_gamma = np.where(loaded, wear_t_gamma(flat[5], flat[6], flat[7], flat[0], flat[1],
                                            flat[2]), 0.0)
    tau = np.zeros(fn.size)
    p0 = np.zeros(fn.size)
    if np.any(loaded):
        sel = [v[loaded] for v in flat[:5]]
        fs = fastsim(sel[0], sel[1], sel[2], sel[3], sel[4], fn[loaded], mu,
                     SHEAR_MODULUS_MPA, n_x=fastsim_grid, n_y=fastsim_grid,
                     bound=TAU_MAX_BOUND)
        tau[loaded] = wear_tau_max(fs)
        p0[loaded] = 1.5 * fn[loaded] / (np.pi * sel[3] * sel[4])
    return {"t_gamma_n": t_gamma.reshape(shape), "tau_max_mpa": tau.reshape(shape),
            "p0_mpa": p0.reshape(shape), "in_contact": loaded.reshape(shape)}


# --------------------------------------------------------------------------------------------
# Public solvers
# --------------------------------------------------------------------------------------------

def solve_curving(vehicle: BogieVehicle, radius_m: float | None, cant_mm: float = 0.0,
                  speed_m_s: float | None = None, direction: str = "left",
                  unbalanced_acceleration_m_s2: float = 0.58, tangent_speed_m_s: float = 30.0,
                  table: ContactTable | None = None, tol: float = DEFAULT_TOLERANCE,
                  fastsim_grid: int = 20, creep_grid: int | None = DEFAULT_CREEP_GRID,
                  contact_pipeline: bool = False, pipeline_equilibrium: bool = False
                  ) -> CurvingResult:
    """Quasi-static curving of a two-axle bogie (module docstring).

    Parameters
    ----------
    vehicle : BogieVehicle (``vehicles.vehicle_preset``)
    radius_m : curve radius [m]; None or inf for tangent track
    cant_mm : cant (superelevation) [mm]
    speed_m_s : speed [m/s]; None: from the unbalanced lateral acceleration
        (:func:`speed_from_cant_deficiency`; seed 001 uses 0.58 m/s^2)
    direction : ``left`` or ``right`` (side towards which the track bends)
    unbalanced_acceleration_m_s2 : a_nc used when the speed is not given [m/s^2]
    tangent_speed_m_s : speed on tangent track when not given [m/s]
    table : contact table (default: the vehicle's profile pair, cached)
    tol : tolerance on the norm of the scaled residual (forces [N] and moments [N m] divided by
        the static wheel load [N]); the default 1e-6 is 0.05 N on a 50 kN wheel
    fastsim_grid : FASTSIM grid n (n x n) for tau_max on the final state
    creep_grid : FASTSIM grid of the equilibrium's creep forces, None for the saturation law
        (:func:`solve_curving_cases_or_none`)
    contact_pipeline, pipeline_equilibrium : contacts from the contact pipeline, at the
        table's equilibrium or at the pipeline's own (:func:`solve_curving_cases_or_none`)

    Returns
    -------
    CurvingResult

    Raises
    ------
    CurvingConvergenceError if the continuation from tangent track fails.
    """
    case = curve_case(radius_m, cant_mm, speed_m_s, direction, unbalanced_acceleration_m_s2,
                      vehicle.traction_torque_nm, tangent_speed_m_s)
    return solve_curving_cases(vehicle, [case], [(radius_m, direction, cant_mm)], table, tol,
                               fastsim_grid, creep_grid, contact_pipeline,
                               pipeline_equilibrium)[0]


def solve_curving_cases(vehicle: BogieVehicle, cases: list[CurveCase],
                        labels: list[tuple[float | None, str, float]] | None = None,
                        table: ContactTable | None = None, tol: float = DEFAULT_TOLERANCE,
                        fastsim_grid: int = 20, creep_grid: int | None = DEFAULT_CREEP_GRID,
                        contact_pipeline: bool = False, pipeline_equilibrium: bool = False
                        ) -> list[CurvingResult]:
    """:func:`solve_curving_cases_or_none` that raises CurvingConvergenceError naming the
    first case that did not converge."""
    results = solve_curving_cases_or_none(vehicle, cases, labels, table, tol, fastsim_grid,
                                          skip_failed=False, creep_grid=creep_grid,
                                          contact_pipeline=contact_pipeline,
                                          pipeline_equilibrium=pipeline_equilibrium)
    return [r for r in results if r is not None]


def solve_curving_cases_or_none(vehicle: BogieVehicle, cases: list[CurveCase],
                                labels: list[tuple[float | None, str, float]] | None = None,
                                table: ContactTable | None = None,
                                tol: float = DEFAULT_TOLERANCE, fastsim_grid: int = 20,
                                skip_failed: bool = True,
                                initial_states: list[NDArray | None] | None = None,
                                creep_grid: int | None = DEFAULT_CREEP_GRID,
                                contact_pipeline: bool = False,
                                pipeline_equilibrium: bool = False
                                ) -> list[CurvingResult | None]:
    """Solve many operating points of one vehicle at once (batched continuation).

    Every case is continued from centred wheelsets on tangent track (curvature, unbalanced
    acceleration and torque scaled from 0 to their values; the step of each case is doubled on
    success and halved on failure) by a batched damped Newton method with forward-difference
    Jacobians; a case whose steps become small is also tried with ``scipy.optimize.root``
    (Powell hybrid). FASTSIM runs once, batched, on all final contacts.

    Parameters
    ----------
    vehicle : BogieVehicle
    cases : operating points (:func:`curve_case`)
    labels : per case (radius_m or None, direction, cant_mm) for the results (default from
        the curvature)
    table, tol, fastsim_grid : as :func:`solve_curving`
    skip_failed : return None for the cases that did not converge instead of raising (one
        batch for any number of failures; the wear loop's fallback)
    initial_states : per case an equilibrium state (``CurvingResult.saturation_state``: the
        first Newton solution uses the saturation law) to start Newton from at the case's own
        load parameters instead of the continuation from centred
        wheelsets (None: continuation); the wear loop's warm retry after a profile update
    creep_grid : creep forces of the equilibrium from FASTSIM on an n x n grid (default
        ``DEFAULT_CREEP_GRID``): the continuation runs with the smooth saturation law
        (``contact.creep``) and its equilibrium starts a Newton solution with FASTSIM's forces
        (Powell hybrid as fallback); a case that does not converge with FASTSIM fails like one
        that does not converge at all. None: the saturation law's equilibrium (faster; its
        forces are up to ~0.5 mu Fn off under large spin, ``contact.creep``)
    contact_pipeline : also evaluate the one contact pipeline at each equilibrium's pose
        (``CurvingResult.pipeline``, ``curving_contacts``; 0.1-0.5 s per wheel); a case at which
        the pipeline fails fails like one that does not converge. The equilibrium and the
        contacts that feed wear stay the table's: at the table's pose the pipeline's forces
        leave up to 1.7 wheel loads unbalanced on a flange (``pipeline_residual_norm``;
        ``benchmarks/curving_flange_vs_geometry.py``)
    pipeline_equilibrium : with ``contact_pipeline``, evaluate the pipeline at the equilibrium
        of ITS forces instead of the table's (``_pipeline_equilibrium``: Broyden's method from
        the table's equilibrium; 20-40 pipeline evaluations, ~20 s per operating point);
        ``CurvingResult.pipeline`` then also holds that equilibrium's pose. A point that does
        not reach ``PIPELINE_TOLERANCE`` keeps its best state and reports its residual
        (``pipeline_residual_norm``); the table's results are unchanged either way

    Returns
    -------
    list of CurvingResult (None for failed cases with ``skip_failed``), in the order of
    ``cases``

    Raises
    ------
    CurvingConvergenceError naming the first case that did not converge (not with
    ``skip_failed``).
    """
    table = vehicle_contact_table(vehicle) if table is None else table
    n = len(cases)
    if labels is None:
        labels = [(None if c.curvature_per_m == 0 else 1.0 / abs(c.curvature_per_m),
                   "left" if c.curvature_per_m >= 0 else "right", 0.0) for c in cases]
    p_end = np.array([[c.curvature_per_m, c.unbalanced_acceleration_m_s2, c.torque_nm]
                      for c in cases], dtype=float).reshape(n, 3)
    p_start = np.zeros_like(p_end)
    q0 = np.repeat(_initial_state(vehicle, table)[None, :], n, axis=0)
    for k, state in enumerate(initial_states or []):
        if state is not None:
            q0[k] = state
            p_start[k] = p_end[k]

    def fun(q, params):
        return _bogie_residual(q, vehicle, table, params[:, 0], params[:, 1], params[:, 2])

    q, norm, ok = continuation_batch(fun, q0, p_start, p_end, tol)
    q_saturation = q.copy()
    if creep_grid is not None and np.any(ok):
        # the saturation law's equilibrium is the start of Newton with FASTSIM's forces
        def fun_fastsim(q, params):
            return _bogie_residual(q, vehicle, table, params[:, 0], params[:, 1],
                                   params[:, 2], creep_grid=creep_grid)

        rows = np.nonzero(ok)[0]
        q_f, norm_f, ok_f = newton_batch(fun_fastsim, q[rows], p_end[rows], tol,
                                          max_iter=30)
        for m in np.nonzero(~ok_f)[0]:
            q_s, n_s, ok_s = scipy_polish(fun_fastsim, q_f[m], p_end[rows[m]], tol)
            if n_s < norm_f[m]:
                q_f[m], norm_f[m], ok_f[m] = q_s, n_s, ok_s
        # a solve that stalled below FASTSIM_TOLERANCE has found the equilibrium as far as
        # FASTSIM's piecewise-smooth forces allow (the residual is reported)
        ok_f = ok_f | (norm_f < max(tol, FASTSIM_TOLERANCE))
        q[rows], norm[rows], ok[rows] = q_f, norm_f, ok_f
    if not np.all(ok) and not skip_failed:
        k = int(np.nonzero(~ok)[0][0])
        kappa = cases[k].curvature_per_m
        raise CurvingConvergenceError("quasi-static curving did not converge",
                                      np.inf if kappa == 0 else 1.0 / kappa, float(norm[k]))
    res, c = _bogie_residual(q, vehicle, table, p_end[:, 0], p_end[:, 1], p_end[:, 2],
                             return_contacts=True, creep_grid=creep_grid)
    norm = np.linalg.norm(res, axis=-1)
    wear = contact_wear_measures(c.xi, c.eta, c.phi_per_mm, c.a_mm, c.b_mm, c.normal_n,
                                 c.fx_n, c.fy_n, c.mz_nmm, vehicle.friction, fastsim_grid)
    pipeline: list[dict[str, NDArray] | None] = [None] * n
    pipeline_norm = np.full(n, np.nan)
    if contact_pipeline and np.any(ok):
        rows = np.nonzero(ok)[0]
        grid = DEFAULT_CREEP_GRID if creep_grid is None else creep_grid
        q_p = q[rows]
        if pipeline_equilibrium:
            q_p = _pipeline_equilibrium(q_p, vehicle, table, p_end[rows], grid, creep_grid)
        cp, peak, ok_p, errors, res_p = _pipeline_residual(q_p, vehicle, table, p_end[rows],
                                                           grid, creep_grid)
        wear_p = contact_wear_measures(cp.xi, cp.eta, cp.phi_per_mm, cp.a_mm, cp.b_mm,
                                       cp.normal_n, cp.fx_n, cp.fy_n, cp.mz_nmm,
                                       vehicle.friction, fastsim_grid)
        ws_p = q_p[:, :10].reshape(-1, 2, 5)
        pose = {"state": q_p,
                "wheelset_shift_mm": _centre_shift(table, ws_p[..., 0], ws_p[..., 3:5]),
                "wheelset_roll_rad": _roll(table, ws_p[..., 0], ws_p[..., 3:5]),
                "wheelset_yaw_rad": ws_p[..., 1] * 1e-3}
        for j, row in enumerate(rows.tolist()):
            if not ok_p[j]:
                if not skip_failed:
                    kappa = cases[row].curvature_per_m
                    raise CurvingConvergenceError(
                        f"contact pipeline failed at the equilibrium pose: {errors[j]}",
                        np.inf if kappa == 0 else 1.0 / kappa, float(norm[row]))
                ok[row] = False
                continue
            pipeline[row] = {**{f.name: getattr(cp, f.name)[j] for f in fields(_Contacts)},
                             "peak_pressure_mpa": peak[j],
                             "tau_max_mpa": wear_p["tau_max_mpa"][j],
                             "t_gamma_n": wear_p["t_gamma_n"][j],
                             "in_contact": wear_p["in_contact"][j],
                             **{name: v[j] for name, v in pose.items()}}
            pipeline_norm[row] = float(np.linalg.norm(res_p[j]))
    results: list[CurvingResult | None] = []
    for k, (case, (radius_m, direction, cant_mm)) in enumerate(zip(cases, labels, strict=True)):
        if not ok[k]:
            results.append(None)
            continue
        ws = q[k, :10].reshape(2, 5)
        shown_r = np.inf if radius_m is None else float(radius_m)
        results.append(CurvingResult(
            radius_m=shown_r, direction=direction, cant_mm=float(cant_mm),
            speed_m_s=case.speed_m_s,
            unbalanced_acceleration_m_s2=case.unbalanced_acceleration_m_s2,
            wheelset_shift_mm=_centre_shift(table, ws[:, 0], ws[:, 3:5]),
            contact_shift_mm=ws[:, 0].copy(), wheelset_roll_rad=_roll(table, ws[:, 0], ws[:, 3:5]),
            wheelset_yaw_rad=ws[:, 1] * 1e-3,
            rolling_ratio=1.0 + ws[:, 2] * 1e-3, bogie_shift_mm=float(q[k, 10]),
            bogie_yaw_rad=float(q[k, 11]) * 1e-3, normal_force_n=c.normal_n[k],
            contact_angle_rad=c.angle_rad[k], wheel_y_mm=c.wheel_y_mm[k],
            rail_y_mm=c.rail_y_mm[k], lateral_position_mm=c.lateral_mm[k],
            rolling_radius_m=c.radius_m[k], xi=c.xi[k], eta=c.eta[k],
            phi_per_mm=c.phi_per_mm[k], fx_n=c.fx_n[k], fy_n=c.fy_n[k], mz_nmm=c.mz_nmm[k],
            a_mm=c.a_mm[k], b_mm=c.b_mm[k], p0_mpa=wear["p0_mpa"][k],
            tau_max_mpa=wear["tau_max_mpa"][k], t_gamma_n=wear["t_gamma_n"][k],
            in_contact=wear["in_contact"][k], residual_norm=float(norm[k]),
            state=q[k].copy(), saturation_state=q_saturation[k].copy(),
            creep_grid=creep_grid, pipeline=pipeline[k],
            pipeline_residual_norm=float(pipeline_norm[k])))
    return results


def solve_free_wheelset(table: ContactTable, radius_m: float, wheel_load_n: float = 50_000.0,
                        friction: float = 0.35, direction: str = "left",
                        tol: float = DEFAULT_TOLERANCE) -> tuple[float, float, NDArray]:
    """Steady curving of a single wheelset without suspension at balanced speed.

    No unbalanced lateral force and no torque: the wheelset finds the lateral shift and yaw at
    which the creep forces balance (in linear theory, pure rolling at y = r0 b0 / (lambda R),
    Boocock 1969, Wickens 2003 §4). Unknowns: shift, yaw, rolling ratio and the two wheels'
    approaches; the same contact and creep model as :func:`solve_curving`.

    Parameters
    ----------
    table : contact table of the wheel-rail pair (e.g. ``build_contact_table(conical_wheel(l))``)
    radius_m : curve radius [m]; direction : ``left`` or ``right``
    wheel_load_n : vertical load of each wheel [N]; friction : mu
    tol : tolerance on the scaled residual

    Returns
    -------
    (shift [mm] (+ = left), yaw [rad], longitudinal creepages of the loaded patches (2 sides))
    """
    sign = 1.0 if direction == "left" else -1.0
    kappa = sign / radius_m
    r0 = table.nominal_radius_m
    centre = table.candidates(0.0)
    slot = int(np.argmin(centre["gap_mm"]))
    d0 = centre["approach1_mm"][slot] * wheel_load_n ** (2.0 / 3.0) / np.cos(
        centre["angle_rad"][slot])

    def fun(q, params):
        k = params[:, 0]
        c = _contacts(table, q[:, 0:1], q[:, 1:2] * 1e-3, q[:, 2:3] * 1e-3,
                      q[:, None, 3:5], k, r0, friction)
        lat, vert, yaw, pitch = _wheelset_loads(c)
        return np.concatenate([lat, yaw, -pitch, vert[:, 0] - wheel_load_n], axis=-1
                              ) / wheel_load_n

    q0 = np.array([[0.0, 0.0, 0.0, d0, d0]])
    q, norm, ok = continuation_batch(fun, q0, np.zeros((1, 1)), np.array([[kappa]]), tol)
    if not ok[0]:
        raise CurvingConvergenceError("free wheelset did not converge", sign * radius_m,
                                      float(norm[0]))
    c = _contacts(table, q[:, 0:1], q[:, 1:2] * 1e-3, q[:, 2:3] * 1e-3, q[:, None, 3:5],
                  np.array([kappa]), r0, friction)
    loaded = c.normal_n[0, 0] > 0
    xi = np.array([np.sum(np.where(loaded[s], c.xi[0, 0, s], 0.0) * c.normal_n[0, 0, s])
                   / np.sum(c.normal_n[0, 0, s]) for s in range(2)])
    return float(q[0, 0]), float(q[0, 1]) * 1e-3, xi


def flange_contact_radius_m(vehicle: BogieVehicle, cant_mm: float = 0.0,
                            speed_m_s: float | None = None,
                            unbalanced_acceleration_m_s2: float = 0.58,
                            radius_range_m: tuple[float, float] = (100.0, 5000.0),
                            threshold_n: float | None = None, rtol: float = 0.005) -> float:
    """Largest curve radius at which the leading wheelset's high-rail wheel touches with its
    flange (a loaded patch at wheel y < -30 mm).

    Parameters
    ----------
    vehicle : BogieVehicle
    cant_mm : cant [mm]
    speed_m_s : fixed speed [m/s]; None: from ``unbalanced_acceleration_m_s2`` at each radius
        (default 0.58 m/s^2 as seed 001 §4)
    radius_range_m : search interval (R_min, R_max) [m]
    threshold_n : flange normal force that counts as contact [N] (default 1 % of the static
        wheel load)
    rtol : relative accuracy of the radius

    Returns
    -------
    radius [m]; ``inf`` if the flange already touches at R_max, NaN if it never touches down
    to R_min. Found on a geometric grid of radii solved together, refined by nested grids.
    """
    threshold = 0.01 * vehicle.wheel_load_n if threshold_n is None else threshold_n
    table = vehicle_contact_table(vehicle)

    def touches(radii: NDArray) -> NDArray:
        cases = [curve_case(float(r), cant_mm, speed_m_s, "left", unbalanced_acceleration_m_s2)
                 for r in radii]
        results = solve_curving_cases(vehicle, cases, table=table, fastsim_grid=4)
        out = []
        for res in results:
            high = SIDES.index(res.high_rail_side)
            flange = res.wheel_y_mm[0, high] < FLANGE_SPLIT_Y_MM
            out.append(bool(np.any(flange & (res.normal_force_n[0, high] > threshold))))
        return np.array(out)

    lo, hi = float(radius_range_m[0]), float(radius_range_m[1])
    ends = touches(np.array([lo, hi]))
    if ends[1]:
        return float("inf")
    if not ends[0]:
        return float("nan")
    while hi / lo - 1.0 > rtol:
        radii = np.geomspace(lo, hi, 10)[1:-1]
        t = touches(radii)
        # largest touching radius and the next larger non-touching one
        touching = np.nonzero(t)[0]
        k = touching[-1] if touching.size else -1
        new_lo = radii[k] if k >= 0 else lo
        new_hi = radii[k + 1] if k + 1 < len(radii) else hi
        lo, hi = new_lo, new_hi
    return float(np.sqrt(lo * hi))
