"""Loaded wheel-rail contact of a wheelset on a straight track: normal and creep forces.

For prescribed lateral shifts and yaw angles of a wheelset rolling at a speed V with an axle
angular velocity omega, this module turns the rigid contact geometry of ``geometry`` into
loaded contacts per wheel, vectorised over the shifts (the Manchester contact benchmark case
A-2.2, ``reference/contact-benchmark/mbench_a22_*.inp``, poses exactly this problem):

1. Geometry (``geometry.contact_table``): per wheel a primary and possibly a secondary
   (two-point) contact point with contact angle delta, rolling radius, Hertz curvatures A, B
   and undeformed vertical gap g.
2. Kinematics: the wheel material velocity at the contact point p is
   v_w = V e_x + omega a x (p - c), with c the axle centre and a the unit axle vector (turned
   by the yaw psi and the roll); the rail is at rest.  Creepages follow CONTACT's wheel-rail
   convention (body 1 = rail): rail minus wheel velocity over V, in the contact frame
   (e_x along the track, e_s lateral in the contact plane towards the wheel's field side,
   e_n the rail's outward normal):
       xi = -v_w.e_x / V,   eta = -v_w.e_s / V,   phi = -omega (a_out . e_n) / V  [1/mm],
   a_out the axle direction pointing out of the track through that wheel.  For small angles
   xi = (omega r - V)/V, eta = psi / cos(delta) and phi = -sin(delta +/- roll)/r (the
   contact angle relative to the axle; + for the left wheel) (seed 000 §III,
   seed 002 §2; Kalker 1967).
3. Normal contact: the wheel load W (vertical force on the rail) is carried by the patches
   with one common vertical penetration d: patch i has the normal approach
   (d - g_i) cos(delta_i) and the Hertz normal force F_i = ((d - g_i) cos delta_i / delta_1,i)^1.5
   (``hertz.hertz_contact``, delta_1 the approach under 1 N).  Vertical equilibrium of the
   rail includes the lateral creep force in the contact plane, which on a flange is large:
       sum_i F_n,i cos(delta_i) + F_s,i sin(delta_i) = W.
   It is solved by bisection in d for the current ratios F_s/F_n, alternated with FASTSIM
   until the normal forces settle (a fixed point; 3-6 rounds to 1e-6 relative).
4. Tangential contact: FASTSIM (``fastsim.fastsim``, CONTACT's discretisation and combined
   flexibility rule, 40 x 40 grid, parabolic bound by default) on each Hertz ellipse gives the
   creep forces F_x, F_s and the spin moment M_z on the rail.

Signs of the results (per wheel, in that wheel's local frame; the right wheel's frame is the
mirror image of the left one so that both wheels are described alike): y_wheel and delta as
``geometry`` (delta < 0 on tread and flange), forces ON THE RAIL, F_s positive towards the
wheel's field side; the lateral track force on the rail ``lateral_force_n`` =
sum (F_s cos delta - F_n sin delta) is positive outwards (a flanging wheel pushes its rail
out).  With these signs the left wheel at shift +y and yaw +psi is CONTACT's (unmirrored)
right wheel at y_ws = y, yaw psi, quantity by quantity; CONTACT prints its left wheel in the
track frame, i.e. our right wheel with y_wheel, delta, eta, phi and F_s negated.

Model differences from CONTACT's exact solution (to read the benchmark): CONTACT solves the
non-Hertzian, conformal normal problem on the real surfaces and the exact tangential
problem; here each patch is a Hertz ellipse from the curvatures at one rigid contact point,
so on the nearly conformal S1002/60E1 tread the contact position (and with it the rolling
radius, i.e. xi) differs by up to ~2 mm and the peak pressure differs most.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.creepages import rigid_creepages
from wearcast.physics.contact.fastsim import Bound, fastsim
from wearcast.physics.contact.geometry import (
    ContactPatches,
    ContactTable,
    WheelsetTrack,
    contact_table,
)
from wearcast.physics.contact.hertz import hertz_contact

_FloatArray = NDArray[np.float64]

#: Shear modulus of wheel and rail steel in the Manchester benchmark [MPa] (CONTACT's GG).
BENCHMARK_SHEAR_MODULUS_MPA = 82_000.0


@dataclass(frozen=True)
class WheelLoadedContact:
    """Loaded contact of one wheel for N shifts; patch arrays have shape (N, 2).

    Column 0 is the primary contact point, column 1 the secondary (two-point contact); fields
    are NaN where a patch does not exist (``valid`` False) and 0 for forces of a patch that
    exists geometrically but carries no load.

    valid : patch exists geometrically
    y_wheel_mm : contact position in the wheel frame [mm] (negative towards the flange)
    contact_angle_rad : delta [rad] (negative on tread and flange)
    rolling_radius_mm : wheel radius at the contact point [mm]
    normal_force_n : F_n [N]
    xi, eta : longitudinal and lateral creepage [-] (rail minus wheel, over V)
    phi_per_mm : spin creepage [1/mm]
    fx_n, fs_n : longitudinal and lateral (in the contact plane) creep force on the rail [N]
    mz_nmm : spin moment on the rail about the patch normal [N mm]
    a_mm, b_mm : Hertz semi-axes, a along the track [mm]
    p0_mpa : Hertz peak pressure [MPa]
    approach_mm : vertical penetration of the wheel into its rail [mm], shape (N,)
    """

    valid: NDArray[np.bool_]
    y_wheel_mm: _FloatArray
    contact_angle_rad: _FloatArray
    rolling_radius_mm: _FloatArray
    normal_force_n: _FloatArray
    xi: _FloatArray
    eta: _FloatArray
    phi_per_mm: _FloatArray
    fx_n: _FloatArray
    fs_n: _FloatArray
    mz_nmm: _FloatArray
    a_mm: _FloatArray
    b_mm: _FloatArray
    p0_mpa: _FloatArray
    approach_mm: _FloatArray

    @property
    def vertical_force_n(self) -> _FloatArray:
        """Vertical force on the rail, sum F_n cos(delta) + F_s sin(delta) [N], shape (N,)."""
        return np.nansum(self.normal_force_n * np.cos(self.contact_angle_rad)
                         + self.fs_n * np.sin(self.contact_angle_rad), axis=1)

    @property
    def lateral_force_n(self) -> _FloatArray:
        """Lateral track force on the rail, positive towards the wheel's field side [N], (N,):
        sum F_s cos(delta) - F_n sin(delta)."""
        return np.nansum(self.fs_n * np.cos(self.contact_angle_rad)
                         - self.normal_force_n * np.sin(self.contact_angle_rad), axis=1)

    @property
    def longitudinal_force_n(self) -> _FloatArray:
        """Total longitudinal creep force on the rail [N], shape (N,)."""
        return np.nansum(self.fx_n, axis=1)

    @property
    def dominant(self) -> NDArray[np.intp]:
        """Index (0 or 1) of the patch carrying the larger normal force, shape (N,)."""
        fn = np.where(self.valid, self.normal_force_n, -1.0)
        return np.argmax(fn, axis=1)

    def pick(self, name: str, patch: ArrayLike | None = None) -> _FloatArray:
        """Field ``name`` of one patch per shift (default: the dominant patch), shape (N,)."""
        idx = self.dominant if patch is None else np.broadcast_to(
            np.asarray(patch, dtype=np.intp), self.dominant.shape)
        values = getattr(self, name)
        return np.take_along_axis(values, idx[:, None], axis=1)[:, 0]


@dataclass(frozen=True)
class LoadedWheelsetContact:
    """Loaded contact of a wheelset for N shifts (signs: module docstring).

    shift_mm : lateral shift [mm], positive towards the left rail
    yaw_rad : yaw [rad], positive turning the front to the left
    roll_rad, height_mm : rigid pose from ``geometry`` [rad], [mm]
    angular_velocity_rad_s : axle angular velocity omega [rad/s], (N,)
    speed_m_s : rolling speed V [m/s]
    left, right : per-wheel loaded contacts
    iterations : FASTSIM / normal-force rounds used
    """

    shift_mm: _FloatArray
    yaw_rad: _FloatArray
    roll_rad: _FloatArray
    height_mm: _FloatArray
    angular_velocity_rad_s: _FloatArray
    speed_m_s: float
    left: WheelLoadedContact
    right: WheelLoadedContact
    iterations: int


def contact_creepages(table: ContactTable, side: str, speed_m_s: float,
                      angular_velocity_rad_s: ArrayLike, nominal_radius_mm: float,
                      patch: str = "primary") -> tuple[_FloatArray, _FloatArray, _FloatArray]:
    """Rigid-body creepages (xi, eta, phi [1/mm]) at one wheel's contact points, shape (N,).

    Parameters
    ----------
    table : contact geometry (``geometry.contact_table``) with shifts, yaw and solved roll
    side : ``"left"`` or ``"right"``
    speed_m_s : forward speed V of the wheelset centre [m/s]
    angular_velocity_rad_s : axle angular velocity omega [rad/s], scalar or (N,)
    nominal_radius_mm : r0 of the wheelset the table was built for [mm] (axle height)
    patch : ``"primary"`` or ``"secondary"``

    Returns
    -------
    xi, eta, phi in the wheel's local contact frame (module docstring): rail minus wheel
    material velocity over V (CONTACT's convention), phi = -omega (a_out . e_n) / V.
    Kalker 1967 / seed 000 §III; exact 3D rigid-body kinematics, no small-angle expansion.
    """
    if side not in ("left", "right"):
        raise ValueError(f"side must be 'left' or 'right', not {side!r}")
    wheel = table.left if side == "left" else table.right
    p: ContactPatches = getattr(wheel, patch)
    point = np.stack([p.x_track_mm, p.y_track_mm, p.z_track_mm])
    return rigid_creepages(side, speed_m_s, angular_velocity_rad_s, table.shift_mm,
                           table.yaw_rad, table.roll_rad, table.height_mm, nominal_radius_mm,
                           point, p.contact_angle_rad)


def _stack(table: ContactTable, side: str, name: str) -> _FloatArray:
    wheel = table.left if side == "left" else table.right
    return np.stack([getattr(wheel.primary, name), getattr(wheel.secondary, name)], axis=1)


def _share_vertical_load(load_n: _FloatArray, gap: _FloatArray, cos_d: _FloatArray,
                         support: _FloatArray, approach_1n: _FloatArray, valid: NDArray[np.bool_]
                         ) -> tuple[_FloatArray, _FloatArray]:
    """Common vertical penetration d (N,) and normal forces (N, 2) carrying the load.

    Patch i: F_i = ((d - g_i) cos(delta_i) / delta_1,i)^1.5, vertical support per unit normal
    force ``support`` = cos(delta_i) + (F_s/F_n)_i sin(delta_i) > 0; sum F_i support_i = W,
    monotone in d, solved by bisection."""
    g = np.where(valid, gap, np.inf)

    def forces(d: _FloatArray) -> _FloatArray:
        pen = np.clip(d[:, None] - g, 0.0, None) * cos_d
        return np.where(valid, (pen / approach_1n) ** 1.5, 0.0)

    # the primary alone carrying everything bounds d from above
    hi = approach_1n[:, 0] * (load_n / support[:, 0]) ** (2.0 / 3.0) / cos_d[:, 0]
    lo = np.zeros_like(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        short = np.nansum(forces(mid) * support, axis=1) < load_n
        lo = np.where(short, mid, lo)
        hi = np.where(short, hi, mid)
    d = 0.5 * (lo + hi)
    return d, forces(d)


def wheelset_contact(wt: WheelsetTrack, shifts_mm: ArrayLike, yaw_rad: ArrayLike = 0.0,
                     wheel_load_n: ArrayLike = 10_000.0, speed_m_s: float = 2.0,
                     angular_velocity_rad_s: ArrayLike | None = None, mu: float = 0.3,
                     shear_modulus_mpa: float = BENCHMARK_SHEAR_MODULUS_MPA,
                     poisson: float = 0.28, n_grid: int = 40, bound: Bound = "parabolic",
                     two_point_gap_mm: float = 0.05, rtol: float = 1e-6, max_iter: int = 30
                     ) -> LoadedWheelsetContact:
    """Normal and creep forces of both wheels of a wheelset for many shifts at once.

    Parameters
    ----------
    wt : wheelset and track (``geometry.s1002_60e1()`` is the Manchester geometry)
    shifts_mm : lateral shifts [mm] (N,), positive towards the left rail
    yaw_rad : yaw [rad], scalar or (N,), positive turning the front to the left
    wheel_load_n : vertical force of each wheel on its rail W [N], scalar or (N,)
        (10 kN in Manchester A-2.2)
    speed_m_s : forward speed V [m/s] (A-2.2: 2 m/s)
    angular_velocity_rad_s : axle angular velocity omega [rad/s], scalar or (N,); default
        V / r0 (pure rolling at the nominal radius).  A-2.2 prescribes |VPITCH| per case.
    mu : coefficient of friction (A-2.2: 0.3)
    shear_modulus_mpa, poisson : G [MPa] and nu of both bodies (A-2.2: 82 GPa, 0.28);
        Hertz uses E = 2 G (1 + nu)
    n_grid : FASTSIM grid n x n per patch
    bound : FASTSIM traction bound, ``"parabolic"`` or ``"elliptic"``
    two_point_gap_mm : largest undeformed gap of a secondary patch (``geometry``)
    rtol, max_iter : convergence of the normal-force / creep-force fixed point

    Returns
    -------
    LoadedWheelsetContact; see the module docstring for the method and the signs.
    Raises RuntimeError if the fixed point does not converge (never silently).
    """
    table = contact_table(wt, shifts_mm, yaw_rad=yaw_rad, two_point_gap_mm=two_point_gap_mm)
    n = table.shift_mm.size
    r0 = wt.nominal_radius_mm
    if angular_velocity_rad_s is None:
        omega = np.full(n, speed_m_s * 1000.0 / r0)
    else:
        omega = np.broadcast_to(np.asarray(angular_velocity_rad_s, dtype=float), (n,)).copy()
    load = np.broadcast_to(np.asarray(wheel_load_n, dtype=float), (n,)).copy()
    if np.any(load <= 0):
        raise ValueError("wheel_load_n must be positive")
    young = 2.0 * shear_modulus_mpa * (1.0 + poisson)

    sides = {}
    iterations = 0
    for side in ("left", "right"):
        valid = _stack(table, side, "valid").astype(bool)
        delta = _stack(table, side, "contact_angle_rad")
        gap = np.where(valid, np.nan_to_num(_stack(table, side, "gap_mm")), np.inf)
        curv_a = np.where(valid, _stack(table, side, "curvature_a_per_mm"), 1.0)
        curv_b = np.where(valid, _stack(table, side, "curvature_b_per_mm"), 1.0)
        cos_d = np.where(valid, np.cos(delta), 1.0)
        sin_d = np.where(valid, np.sin(delta), 0.0)
        creep = [contact_creepages(table, side, speed_m_s, omega, r0, patch)
                 for patch in ("primary", "secondary")]
        xi, eta, phi = (np.nan_to_num(np.stack([c[k] for c in creep], axis=1))
                        for k in range(3))
        approach_1n = hertz_contact(1.0, curv_a, curv_b, young, poisson).approach_mm
        ratio = np.zeros((n, 2))  # F_s / F_n per patch
        fn_old = np.zeros((n, 2))
        rounds = 0
        while True:
            rounds += 1
            support = np.clip(cos_d + ratio * sin_d, 0.05, None)
            d, fn = _share_vertical_load(load, gap, cos_d, support, approach_1n, valid)
            hz = hertz_contact(fn, curv_a, curv_b, young, poisson)
            loaded = fn > 0
            res = fastsim(xi, eta, phi, np.where(loaded, hz.a_mm, 1.0),
                          np.where(loaded, hz.b_mm, 1.0), fn, mu,
                          shear_modulus_mpa=shear_modulus_mpa, poisson=poisson,
                          n_x=n_grid, n_y=n_grid, bound=bound)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.where(loaded, res.fy_n / np.where(loaded, fn, 1.0), 0.0)
            change = np.max(np.abs(fn - fn_old) / load[:, None])
            fn_old = fn
            if change < rtol:
                break
            if rounds >= max_iter:
                raise RuntimeError(f"normal/creep force iteration did not converge on the "
                                   f"{side} wheel in {max_iter} rounds (last change "
                                   f"{change:.2e} of W)")
        iterations = max(iterations, rounds)

        def masked(a: ArrayLike, valid: NDArray[np.bool_] = valid) -> _FloatArray:
            return np.where(valid, np.asarray(a, dtype=float), np.nan)

        def loaded_only(a: ArrayLike, loaded: NDArray[np.bool_] = loaded) -> _FloatArray:
            return masked(np.where(loaded, a, 0.0))

        sides[side] = WheelLoadedContact(
            valid=valid, y_wheel_mm=_stack(table, side, "y_wheel_mm"),
            contact_angle_rad=delta, rolling_radius_mm=_stack(table, side, "rolling_radius_mm"),
            normal_force_n=masked(fn), xi=masked(xi), eta=masked(eta), phi_per_mm=masked(phi),
            fx_n=loaded_only(res.fx_n), fs_n=loaded_only(res.fy_n),
            mz_nmm=loaded_only(res.mz_nmm), a_mm=loaded_only(hz.a_mm),
            b_mm=loaded_only(hz.b_mm), p0_mpa=loaded_only(hz.p0_mpa), approach_mm=d,
        )
    return LoadedWheelsetContact(table.shift_mm, table.yaw_rad, table.roll_rad,
                                 table.height_mm, omega, float(speed_m_s), sides["left"],
                                 sides["right"], iterations)


#: Columns of ``in_contact_convention`` (names as the A-2.2 reference CSVs).
CONTACT_COLUMNS = ("ycp_w_mm", "delta_rad", "cksi", "ceta", "cphi_per_mm", "Fn_N", "Fx_N",
                   "Fs_N", "pmax_Nmm2", "FY_rail_N", "FZ_rail_N")


def in_contact_convention(result: LoadedWheelsetContact, contact_wheel: str
                          ) -> dict[str, _FloatArray]:
    """Results of one wheel as CONTACT prints them for a wheelset at y_ws = shift, yaw = yaw.

    CONTACT's (unmirrored) right wheel is our left wheel, unchanged; its left wheel is printed
    in CONTACT's track frame, i.e. our right wheel with the lateral quantities (y_w, delta,
    eta, phi, F_s, F_Y) negated (module docstring).  Patch quantities are those of the patch
    carrying the larger normal force (CONTACT reports one patch per wheel in A-2.2), track
    forces F_Y, F_Z are sums over the patches.  Returns arrays (N,) keyed by
    ``CONTACT_COLUMNS``.
    """
    if contact_wheel not in ("left", "right"):
        raise ValueError(f"contact_wheel must be 'left' or 'right', not {contact_wheel!r}")
    wheel = result.left if contact_wheel == "right" else result.right
    sign = 1.0 if contact_wheel == "right" else -1.0
    return {
        "ycp_w_mm": sign * wheel.pick("y_wheel_mm"),
        "delta_rad": sign * wheel.pick("contact_angle_rad"),
        "cksi": wheel.pick("xi"),
        "ceta": sign * wheel.pick("eta"),
        "cphi_per_mm": sign * wheel.pick("phi_per_mm"),
        "Fn_N": wheel.pick("normal_force_n"),
        "Fx_N": wheel.pick("fx_n"),
        "Fs_N": sign * wheel.pick("fs_n"),
        "pmax_Nmm2": wheel.pick("p0_mpa"),
        "FY_rail_N": sign * wheel.lateral_force_n,
        "FZ_rail_N": wheel.vertical_force_n,
    }
