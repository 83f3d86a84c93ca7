"""Loaded contact of one wheel on its rail: non-Hertzian patches + rigid creepages + FASTSIM.

The pipeline of CONTACT's wheel-rail module for one wheel at a time, pose by pose:

1. contact locus (``locus.wheel_locus``; roll solved or prescribed, yaw);
2. patches merged or split by the interpenetration region and the normal problem carrying
   the vertical wheel load W (``normal_contact.wheel_normal_contact``, BEM / Kik-Piotrowski /
   Hertz);
3. rigid creepages at each patch's reference point (``creepages.rigid_creepages``,
   CONTACT's convention: rail minus wheel velocity over V; on a curve with the track frame's
   turning rate V kappa);
4. creep forces from FASTSIM (``fastsim.fastsim``, CONTACT's discretisation and combined
   flexibility) on the patch's equivalent ellipse (a, b from the patch: b half its lateral
   extent, a = area / (pi b)) with its normal force;
5. vertical equilibrium sum F_n cos(delta) + F_s sin(delta) = W: steps 2-4 are repeated with
   the patches' F_s/F_n until the normal forces settle (CONTACT solves the same coupled
   problem; 2-4 rounds to 1e-4 W; the ratios are under-relaxed after 3 rounds, with a
   falling weight, and with
   method "auto" a pose still unsettled after 10 rounds finishes with the coarse BEM for
   every patch, since a patch at the Hertz criterion's threshold can flip between the two).
   The poses advance round by round together, each pose's rounds exactly as if alone: the
   normal problem pose by pose, steps 3-4 of every pose still iterating in one batched
   call per round (``_tangential``; the creepages and FASTSIM are per patch).

Signs of the results (per wheel, in that wheel's local frame; the right wheel's frame is the
mirror image of the left one so that both wheels are described alike): y_wheel and delta as
``geometry`` (delta < 0 on tread and flange), forces ON THE RAIL, F_s positive towards the
wheel's field side; the lateral track force on the rail ``lateral_force_n`` =
sum (F_s cos delta - F_n sin delta) is positive outwards (a flanging wheel pushes its rail
out). With these signs the left wheel at shift +y and yaw +psi is CONTACT's (unmirrored) right
wheel at y_ws = y, yaw psi, quantity by quantity; CONTACT prints its left wheel in the track
frame, i.e. our right wheel with y_wheel, delta, eta, phi and F_s negated
(``benchmarks/manchester_contact.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from wearcast.physics.contact.creepages import rigid_creepages
from wearcast.physics.contact.fastsim import Bound, fastsim_forces
from wearcast.physics.contact.hertz import STEEL_SHEAR_MODULUS_MPA
from wearcast.physics.contact.locus import WheelLocus
from wearcast.physics.contact.normal_contact import WheelNormalContact, wheel_normal_contact
from wearcast.physics.contact.patch_plane import NormalPatch

_FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class LoadedPatch:
    """One loaded patch: its normal solution and the tangential results.

    normal : the ``NormalPatch`` (reference location, pressure, equivalent ellipse)
    xi, eta, phi_per_mm : creepages at the reference point [-], [-], [1/mm]
    fx_n, fs_n : creep forces on the rail [N], F_s in the contact plane towards the field side
    mz_nmm : spin moment on the rail [N mm]
    """

    normal: NormalPatch
    xi: float
    eta: float
    phi_per_mm: float
    fx_n: float
    fs_n: float
    mz_nmm: float

    @property
    def normal_force_n(self) -> float:
        """F_n [N]."""
        return self.normal.normal_force_n

    @property
    def contact_angle_rad(self) -> float:
        """delta at the reference [rad]."""
        return self.normal.contact_angle_rad


@dataclass(frozen=True)
class LoadedWheel:
    """All loaded patches of one wheel at one pose (field side first)."""

    approach_mm: float
    patches: list[LoadedPatch]
    rounds: int

    @property
    def vertical_force_n(self) -> float:
        """sum F_n cos(delta) + F_s sin(delta) on the rail [N]."""
        return float(sum(p.normal_force_n * np.cos(p.contact_angle_rad)
                         + p.fs_n * np.sin(p.contact_angle_rad) for p in self.patches))

    @property
    def lateral_force_n(self) -> float:
        """sum F_s cos(delta) - F_n sin(delta), positive towards the field side [N]."""
        return float(sum(p.fs_n * np.cos(p.contact_angle_rad)
                         - p.normal_force_n * np.sin(p.contact_angle_rad)
                         for p in self.patches))

    @property
    def dominant(self) -> LoadedPatch:
        """The patch carrying the largest normal force."""
        return max(self.patches, key=lambda p: p.normal_force_n)


class _PoseRound(NamedTuple):
    """One pose's input to a round's tangential step (``_tangential``)."""

    locus: WheelLocus
    row: int
    patches: list[NormalPatch]
    approach_mm: float
    omega_rad_s: float
    curvature_per_m: float


def _tangential(rows: list[_PoseRound], speed_m_s: float, nominal_radius_mm: float, mu: float,
                shear_modulus_mpa: float, poisson: float, n_grid: int, bound: Bound
                ) -> list[list[LoadedPatch]]:
    """Creepages and FASTSIM forces of the patches of several poses in one batch: per pose
    (``_PoseRound``: locus and row, patches, approach d [mm], axle angular velocity [rad/s],
    track curvature [1/m]) the patches' ``LoadedPatch``; every quantity is per patch
    (elementwise), so the batch gives each pose the numbers it would get alone, with the numpy
    and FASTSIM call overhead paid once per round of the coupling instead of once per pose."""
    owner: list[int] = []
    flat: list[NormalPatch] = []
    for k, r in enumerate(rows):
        owner.extend([k] * len(r.patches))
        flat.extend(r.patches)
    out: list[list[LoadedPatch]] = [[] for _ in rows]
    if not flat:
        return out
    # per patch: shift, yaw, roll, height - d, omega, kappa, d of its pose
    pose = np.array([[r.locus.shift_mm[r.row], r.locus.yaw_rad[r.row], r.locus.roll_rad[r.row],
                      r.locus.height_mm[r.row] - r.approach_mm, r.omega_rad_s,
                      r.curvature_per_m, r.approach_mm] for r in (rows[k] for k in owner)])
    point = np.array([[p.region.x_track_mm for p in flat],
                      [p.region.y_track_mm for p in flat],
                      [p.region.z_track_mm for p in flat]])
    point[2] -= pose[:, 6]
    delta = np.array([p.contact_angle_rad for p in flat])
    xi, eta, phi = rigid_creepages(rows[0].locus.side, speed_m_s, pose[:, 4], pose[:, 0],
                                   pose[:, 1], pose[:, 2], pose[:, 3], nominal_radius_mm,
                                   point, delta, pose[:, 5])
    fn = np.array([p.normal_force_n for p in flat])
    loaded = fn > 0
    a = np.where(loaded, [p.a_mm for p in flat], 1.0)
    b = np.where(loaded, [p.b_mm for p in flat], 1.0)
    # the totals only (the compiled march; ``fastsim``'s numbers without its fields)
    res = fastsim_forces(xi, eta, phi, a, b, fn, mu, shear_modulus_mpa=shear_modulus_mpa,
                         poisson=poisson, n_x=n_grid, n_y=n_grid, bound=bound)
    for k, p in enumerate(flat):
        out[owner[k]].append(LoadedPatch(p, float(xi[k]), float(eta[k]), float(phi[k]),
                                         float(res.fx_n[k]) if loaded[k] else 0.0,
                                         float(res.fy_n[k]) if loaded[k] else 0.0,
                                         float(res.mz_nmm[k]) if loaded[k] else 0.0))
    return out


@dataclass
class _Coupling:
    """State of one pose's normal / tangential coupling (``loaded_wheel_contact``)."""

    locus: WheelLocus
    ratios: list[list[float]] | None = None
    previous: list[float] = field(default_factory=list)
    guess: float | None = None
    rounds: int = 0
    chosen: str = "auto"
    normal: WheelNormalContact | None = None


def loaded_wheel_contact(locus: WheelLocus, nominal_radius_mm: float,
                         wheel_load_n: ArrayLike = 10_000.0, speed_m_s: float = 2.0,
                         angular_velocity_rad_s: ArrayLike | None = None, mu: float = 0.3,
                         shear_modulus_mpa: float = STEEL_SHEAR_MODULUS_MPA,
                         poisson: float = 0.28, method: str = "auto", n_grid: int = 40,
                         bound: Bound = "parabolic", rtol: float = 1e-4, max_rounds: int = 40,
                         track_curvature_per_m: ArrayLike = 0.0) -> list[LoadedWheel]:
    """Loaded contact of one wheel for every pose of its locus (module docstring).

    Parameters
    ----------
    locus : contact locus of the wheel (``locus.wheel_locus``)
    nominal_radius_mm : r0 of the wheelset [mm] (axle height)
    wheel_load_n : vertical force W on the rail [N], scalar or (N,)
    speed_m_s : rolling speed V [m/s]
    angular_velocity_rad_s : axle angular velocity [rad/s], scalar or (N,); default V / r0
    mu, shear_modulus_mpa, poisson : friction coefficient, G [MPa], nu
    method : normal-contact method ("bem", "kp", "hertz", "auto"; ``normal_contact``)
    n_grid, bound : FASTSIM grid and traction bound
    rtol, max_rounds : convergence of the normal / tangential coupling (normal forces,
        relative to W or the largest patch force if larger); RuntimeError if not reached
    track_curvature_per_m : curvature kappa of the track [1/m] (+ to the left), scalar or (N,):
        the creepages of a wheelset curving quasi-statically (``creepages``); 0 tangent track
    """
    n = locus.gap_mm.shape[0]
    loads = np.broadcast_to(np.asarray(wheel_load_n, dtype=float), (n,))
    if angular_velocity_rad_s is None:
        omegas = np.full(n, speed_m_s * 1000.0 / nominal_radius_mm)
    else:
        omegas = np.broadcast_to(np.asarray(angular_velocity_rad_s, dtype=float), (n,))
    kappas = np.broadcast_to(np.asarray(track_curvature_per_m, dtype=float), (n,))
    young = 2.0 * shear_modulus_mpa * (1.0 + poisson)
    # all poses advance round by round together: the normal problem pose by pose, the
    # creepages and FASTSIM of every pose still iterating in one batch (``_tangential``)
    states = [_Coupling(_row_locus(locus, row), chosen=method) for row in range(n)]
    out: list[LoadedWheel | None] = [None] * n
    active = list(range(n))
    while active:
        for row in active:
            st = states[row]
            st.rounds += 1
            if method == "auto" and st.rounds > 10:
                # a patch at the Hertz criterion's threshold can flip between Hertz and the
                # coarse BEM from round to round; settle it with the coarse BEM
                st.chosen = "bem-coarse"
            st.normal = wheel_normal_contact(st.locus, float(loads[row]), method=st.chosen,
                                             lateral_ratio=st.ratios, young_mpa=young,
                                             poisson=poisson, approach_guess_mm=st.guess,
                                             patch_guess=None if st.normal is None
                                             else [st.normal.patches])[0]
            st.guess = st.normal.approach_mm
        solved = [_solved(states[row]) for row in active]
        batch = _tangential([_PoseRound(states[row].locus, 0, normal.patches,
                                        normal.approach_mm, float(omegas[row]),
                                        float(kappas[row]))
                             for row, normal in zip(active, solved, strict=True)],
                            speed_m_s, nominal_radius_mm, mu, shear_modulus_mpa, poisson,
                            n_grid, bound)
        still = []
        for row, normal, loaded in zip(active, solved, batch, strict=True):
            st = states[row]
            rounds = st.rounds
            ratios = st.ratios
            forces = [p.normal_force_n for p in loaded]
            new = [p.fs_n / p.normal_force_n if p.normal_force_n > 0 else 0.0 for p in loaded]
            if ratios is not None and rounds > 3 and len(ratios[0]) == len(new):
                # under-relaxed after a few rounds, with a weight 1 / (rounds - 2) that falls
                # (1/2, 1/3, ...): a patch that switches between Hertz and the BEM, merges, or
                # gains a grid element makes the map of F_s/F_n discontinuous, and a fixed
                # relaxation can then cycle between two values for ever
                step = 1.0 / (rounds - 2)
                new = [a + step * (b - a) for a, b in zip(ratios[0], new, strict=True)]
            ratio_change = (np.inf if ratios is None or len(ratios[0]) != len(new) else
                            float(np.max(np.abs(np.subtract(new, ratios[0])), initial=0.0)))
            st.ratios = [new]
            # settled when no patch's normal force changes by more than rtol of the larger of
            # the wheel load and the largest patch force (a 70 deg flange patch carries several
            # times the vertical load), or when the ratios F_s/F_n, the coupling's unknowns,
            # no longer move (to rtol; the normal solution of a flange patch can then still
            # alternate by the grid's resolution, ~5e-4 of its force)
            scale = max(float(loads[row]), max(forces, default=0.0))
            if len(forces) == len(st.previous) and (np.max(
                    np.abs(np.subtract(forces, st.previous)), initial=0.0) < rtol * scale
                    or ratio_change < rtol):
                out[row] = LoadedWheel(normal.approach_mm, loaded, rounds)
                continue
            if rounds >= max_rounds:
                raise RuntimeError(f"normal/tangential coupling did not converge at pose {row}")
            st.previous = forces
            still.append(row)
        active = still
    return [w for w in out if w is not None]


def _solved(state: _Coupling) -> WheelNormalContact:
    """The normal solution of a pose's current round (set before its tangential step)."""
    if state.normal is None:
        raise RuntimeError("normal contact not solved")  # pragma: no cover - by construction
    return state.normal


def _row_locus(locus: WheelLocus, row: int) -> WheelLocus:
    """The locus restricted to one pose (shape (1, M))."""
    def pick(a: np.ndarray) -> Any:
        return a[row:row + 1]

    single = WheelLocus(
        side=locus.side, shift_mm=pick(locus.shift_mm), yaw_rad=pick(locus.yaw_rad),
        roll_rad=pick(locus.roll_rad), height_mm=pick(locus.height_mm),
        gap_mm=pick(locus.gap_mm), y_wheel_mm=locus.y_wheel_mm, z_wheel_mm=locus.z_wheel_mm,
        x_track_mm=pick(locus.x_track_mm), y_track_mm=pick(locus.y_track_mm),
        z_track_mm=pick(locus.z_track_mm), z_rail_mm=pick(locus.z_rail_mm),
        contact_angle_rad=pick(locus.contact_angle_rad),
        rolling_radius_mm=locus.rolling_radius_mm,
        curvature_a_per_mm=locus.curvature_a_per_mm, arc_length_mm=locus.arc_length_mm,
        valid=pick(locus.valid))
    # the derived arrays of the whole locus (computed once for all poses, row by row the
    # same numbers) handed to the pose's locus: cached properties live in its __dict__
    single.__dict__.update(arc_step_mm=locus.arc_step_mm,
                           track_width_mm=pick(locus.track_width_mm),
                           sqrt_curvature_a=locus.sqrt_curvature_a)
    return single
