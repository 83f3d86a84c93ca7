"""Quasi-static curving of a two-axle bogie: wheelset shifts and yaws, contact forces.

The model (Wickens / Elkins-Gostling style steady curving, solved as a nonlinear equilibrium)
is in its concept modules:

* ``curve_cases``: the operating point (curvature, unbalanced lateral acceleration from the
  cant deficiency, speed, torque; seeds 001 §4 and 003 §5.3);
* ``curving_table``: the contact table (tabulated, smoothed wheel-rail gap from the rigid
  multi-point geometry with its solved roll; its names are re-exported here);
* ``bogie_equations``: the 12 unknowns, the contacts (elastic Hertz patches, creepages,
  FASTSIM or the smooth saturation law) and the 12 equations of the bogie's equilibrium;
* ``bogie_residual_kernel``: the same residual and its forward-difference Jacobian compiled
  (numba; ``bogie_equations.CompiledBogie``), what the solvers evaluate;
* ``equilibrium_solvers``: batched damped Newton, MINPACK's Powell hybrid, continuation;
* ``pipeline_equilibrium``: the contact pipeline's forces at (or in equilibrium near) the
  table's pose;
* ``curving_result``: the result; ``wear_measures.equilibrium_wear_measures``: tau_max, T_gamma
  and p0 of the final contacts.

This module solves it. Solution from straight track with continuation in the load parameter
(curvature, unbalanced acceleration and torque scaled together from 0), a batched damped
Newton method with ``scipy.optimize.root`` (hybr) as fallback, first with the smooth saturation
law (``contact.creep``), then from that equilibrium with FASTSIM's forces. Where the curve of
equilibria folds back in the load parameter (a hollow-worn tread: the centred tangent
equilibrium can turn back at a small curvature) the natural continuation stops at the
fold; those cases are followed along the curve through its folds by pseudo-arclength
continuation (``equilibrium_solvers.arclength_continuation_batch``). Failure raises
:class:`CurvingConvergenceError`. Linear-theory check: Boocock (1969), Wickens (2003).
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.bogie_equations import (
    N_STATE as N_STATE,
)
from wearcast.physics.bogie_equations import (
    SHEAR_MODULUS_MPA as SHEAR_MODULUS_MPA,
)
from wearcast.physics.bogie_equations import (
    WHEELSET_SHIFT_COLUMNS,
    BogieContacts,
    CompiledBogie,
    bogie_contacts,
    bogie_residual,
    centre_shift,
    initial_state,
    wheelset_loads,
    wheelset_roll,
    wheelset_unknowns,
)
from wearcast.physics.curve_cases import CANT_BASE_MM as CANT_BASE_MM
from wearcast.physics.curve_cases import CurveCase as CurveCase
from wearcast.physics.curve_cases import curve_case as curve_case
from wearcast.physics.curve_cases import speed_from_cant_deficiency as speed_from_cant_deficiency
from wearcast.physics.curving_result import FLANGE_SPLIT_Y_MM as FLANGE_SPLIT_Y_MM
from wearcast.physics.curving_result import CurvingResult as CurvingResult

# the contact table lives in curving_table; its names are re-exported for the table's users
from wearcast.physics.curving_table import GAUGE_MM as GAUGE_MM
from wearcast.physics.curving_table import ContactTable as ContactTable
from wearcast.physics.curving_table import build_contact_table as build_contact_table
from wearcast.physics.curving_table import conical_wheel as conical_wheel
from wearcast.physics.curving_table import contact_table_for as contact_table_for
from wearcast.physics.curving_table import measured_wheel_table_for as measured_wheel_table_for
from wearcast.physics.curving_table import vehicle_contact_table
from wearcast.physics.equilibrium_solvers import (
    arclength_continuation_batch,
    continuation_batch,
    newton_batch,
    scipy_polish,
)
from wearcast.physics.pipeline_equilibrium import PIPELINE_TOLERANCE as PIPELINE_TOLERANCE
from wearcast.physics.pipeline_equilibrium import (
    pipeline_force_equilibrium,
    pipeline_residual,
)
from wearcast.physics.vehicles import BogieVehicle
from wearcast.physics.vocabulary import SIDES as SIDES
from wearcast.physics.wear_measures import TAU_MAX_BOUND as TAU_MAX_BOUND
from wearcast.physics.wear_measures import equilibrium_wear_measures

#: Default tolerance on the scaled equilibrium residual (see ``solve_curving``).
DEFAULT_TOLERANCE = 1e-6
#: FASTSIM grid (n x n) of the creep forces in the curving equilibrium; 16 x 16 keeps the forces
#: within 0.03 mu Fn of a 40 x 40 grid at the equilibria of ``benchmarks/curving_creep_law.py``.
DEFAULT_CREEP_GRID = 16
#: Tolerance of the equilibrium with FASTSIM's forces (scaled residual, as DEFAULT_TOLERANCE):
#: FASTSIM's totals are only piecewise smooth in the creepages (grid elements switch between
#: adhesion and slip), so Newton can stall near 1e-5 of the wheel load: a solve that stalls
#: below 1e-4 (5 N on a 50 kN wheel) counts as converged. ``CurvingResult.residual_norm``
#: reports what was reached.
FASTSIM_TOLERANCE = 1e-4


class CurvingConvergenceError(RuntimeError):
    """The curving equilibrium was not found.

    Attributes: ``radius_m`` (signed by direction, inf for tangent), ``residual_norm``.
    """

    def __init__(self, message: str, radius_m: float, residual_norm: float):
        super().__init__(f"{message} (radius {radius_m:g} m, residual norm {residual_norm:.3g})")
        self.radius_m = radius_m
        self.residual_norm = residual_norm



#: Residual [scaled] of a state whose wheelset leaves the contact table (:class:`_OnTable`).
_OFF_TABLE_RESIDUAL = 1e3


class _OnTable:
    """A ``CompiledBogie`` restricted to the contact table's range of shift: a state with a
    wheelset's contact shift beyond it gets the residual ``_OFF_TABLE_RESIDUAL`` in every
    equation, so no solver accepts it or steps to it. Beyond its range the table repeats its
    last row (``ContactTable.candidates``): the contacts stop moving with the shift, the
    wheelset has no lateral stiffness there and the equations hold at spurious states (a
    worn metro_b wheel on a worn rail at 300 m: Newton's first step from centred wheelsets
    went to -41 m and converged there, residual 2e-8)."""

    def __init__(self, bogie: CompiledBogie, table: ContactTable):
        self.bogie = bogie
        sides = (table,) if table.right is None else (table, table.right)
        self.limit_mm = min(min(-float(t.shift_mm[0]), float(t.shift_mm[-1])) for t in sides)
        self._shift_columns = WHEELSET_SHIFT_COLUMNS

    def _off(self, q: NDArray) -> NDArray[np.bool_]:
        # one comparison per wheelset's shift column (MINPACK calls this for single states
        # some 10^5 times a wear run: no fancy indexing)
        a, b = self._shift_columns
        return ((np.abs(q[:, a]) > self.limit_mm) | (np.abs(q[:, b]) > self.limit_mm))[:, None]

    def residual(self, q: NDArray, params: NDArray) -> NDArray[np.float64]:
        """``CompiledBogie.residual``, ``_OFF_TABLE_RESIDUAL`` off the table."""
        res = self.bogie.residual(q, params)
        off = self._off(q)
        return np.where(off, _OFF_TABLE_RESIDUAL, res) if off.any() else res

    def jacobian(self, q: NDArray, params: NDArray, steps: NDArray
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``CompiledBogie.jacobian`` with the residual of :meth:`residual`."""
        res, jac = self.bogie.jacobian(q, params, steps)
        off = self._off(q)
        return (np.where(off, _OFF_TABLE_RESIDUAL, res) if off.any() else res), jac


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
    table : contact table (default: the vehicle's profile pair on the curve's rails, cached,
        ``curving_table.vehicle_contact_table``)
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

    Every case is continued from the tangent track's equilibrium (solved once from centred
    wheelsets; the centred state where that fails) with curvature, unbalanced acceleration and
    torque scaled from 0 to their values (the step of each case doubled on success and halved
    on failure) by a batched damped Newton method with forward-difference
    Jacobians; a case whose steps become small is also tried with ``scipy.optimize.root``
    (Powell hybrid). FASTSIM runs once, batched, on all final contacts.

    Parameters
    ----------
    vehicle : BogieVehicle
    cases : operating points (:func:`curve_case`)
    labels : per case (radius_m or None, direction, cant_mm) for the results (default from
        the curvature)
    table, tol, fastsim_grid : as :func:`solve_curving`; a given table serves every case
        (a table with a rail per side, ``ContactTable.right``, puts its left rail under the
        left wheels whatever the curve's direction); without one each case takes the
        vehicle's rails of its own direction (``curving_table.track_rails``: a vehicle with a
        high and a low rail runs the cases of each direction, and tangent track, on their
        own tables)
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
        (``CurvingResult.pipeline``, ``curving_contacts``; ~10-40 ms per wheel on a shared
        core, ``benchmarks/bench_wear_tables.py``); a case at which
        the pipeline fails fails like one that does not converge. The equilibrium and the
        contacts that feed wear stay the table's: at the table's pose the pipeline's forces
        leave up to 1.7 wheel loads unbalanced on a flange (``pipeline_residual_norm``;
        ``benchmarks/curving_flange_vs_geometry.py``)
    pipeline_equilibrium : with ``contact_pipeline``, evaluate the pipeline at the equilibrium
        of ITS forces instead of the table's (``pipeline_force_equilibrium``: a homotopy from
        the table's equilibrium, Newton with the pipeline's forward-difference Jacobian;
        ~60 pipeline evaluations of the point, a few seconds per operating point on one core,
        ``benchmarks/table_contact_models.py``);
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
    if table is None and (vehicle.high_rail_profile is not None
                          or vehicle.low_rail_profile is not None):
        return _solve_by_direction(vehicle, cases, labels, tol, fastsim_grid, skip_failed,
                                   initial_states, creep_grid, contact_pipeline,
                                   pipeline_equilibrium)
    table = vehicle_contact_table(vehicle) if table is None else table
    n = len(cases)
    if labels is None:
        labels = [(None if c.curvature_per_m == 0 else 1.0 / abs(c.curvature_per_m),
                   "left" if c.curvature_per_m >= 0 else "right", 0.0) for c in cases]
    p_end = np.array([[c.curvature_per_m, c.unbalanced_acceleration_m_s2, c.torque_nm]
                      for c in cases], dtype=float).reshape(n, 3)
    p_start = np.zeros_like(p_end)
    q0 = np.repeat(initial_state(vehicle, table)[None, :], n, axis=0)
    for k, state in enumerate(initial_states or []):
        if state is not None:
            q0[k] = state
            p_start[k] = p_end[k]

    # bogie_residual with the saturation law, compiled (bogie_residual is its reference)
    saturation = _OnTable(CompiledBogie(vehicle, table), table)
    # the continuation starts from the tangent track's equilibrium (the load parameters 0),
    # solved once from the centred wheelsets (Newton, then Powell hybrid): on a conformal worn
    # pair (the measured wheel W288 on the measured worn rail avg_low2.ban) the wheelsets sit
    # between the two flange roots, far from the centred state, and a first continuation step
    # from the centred state converged only at some curves (at 255 m, not at 250 m; helper
    # flange11). Where that solve fails the continuation starts from the centred state as before
    fresh = np.nonzero(np.all(p_start == 0.0, axis=-1) & np.any(p_end != 0.0, axis=-1))[0]
    if fresh.size:
        q_t, _, ok_t = newton_batch(saturation.residual, q0[fresh[:1]], p_start[fresh[:1]],
                                    tol, jac=saturation.jacobian)
        if not ok_t[0]:
            q_p, _, ok_p = scipy_polish(saturation.residual, q0[fresh[0]], p_start[fresh[0]],
                                        tol, jac=saturation.jacobian)
            q_t[0], ok_t[0] = q_p, ok_p
        if ok_t[0]:
            q0[fresh] = q_t[0]
    q, norm, ok = continuation_batch(saturation.residual, q0, p_start, p_end, tol,
                                     jac=saturation.jacobian)
    # where the curve of equilibria folds back in the load (a hollow-worn tread: the centred
    # tangent equilibrium can turn back at a small curvature), follow it through the folds
    folded = np.nonzero(~ok & np.any(p_start != p_end, axis=-1))[0]
    if folded.size:
        q_a, norm_a, ok_a = arclength_continuation_batch(
            saturation.residual, q0[folded], p_start[folded], p_end[folded], tol,
            jac=saturation.jacobian)
        q[folded[ok_a]], norm[folded[ok_a]], ok[folded[ok_a]] = q_a[ok_a], norm_a[ok_a], True
    q_saturation = q.copy()
    if creep_grid is not None and np.any(ok):
        # the saturation law's equilibrium is the start of Newton with FASTSIM's forces
        fastsim = _OnTable(CompiledBogie(vehicle, table, creep_grid), table)
        rows = np.nonzero(ok)[0]
        q_f, norm_f, ok_f = newton_batch(fastsim.residual, q[rows], p_end[rows], tol,
                                          max_iter=30, jac=fastsim.jacobian)
        for m in np.nonzero(~ok_f)[0]:
            q_s, n_s, ok_s = scipy_polish(fastsim.residual, q_f[m], p_end[rows[m]], tol,
                                          jac=fastsim.jacobian)
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
    res, c = bogie_residual(q, vehicle, table, p_end[:, 0], p_end[:, 1], p_end[:, 2],
                             return_contacts=True, creep_grid=creep_grid)
    norm = np.linalg.norm(res, axis=-1)
    wear = equilibrium_wear_measures(c.xi, c.eta, c.phi_per_mm, c.a_mm, c.b_mm, c.normal_force_n,
                                 c.fx_n, c.fy_n, c.mz_nmm, vehicle.friction, fastsim_grid)
    pipeline: list[dict[str, NDArray] | None] = [None] * n
    pipeline_norm = np.full(n, np.nan)
    if contact_pipeline and np.any(ok):
        rows = np.nonzero(ok)[0]
        grid = DEFAULT_CREEP_GRID if creep_grid is None else creep_grid
        q_p = q[rows]
        if pipeline_equilibrium:
            q_p, _ = pipeline_force_equilibrium(q_p, vehicle, table, p_end[rows], grid,
                                                creep_grid)
        cp, peak, ok_p, errors, res_p = pipeline_residual(q_p, vehicle, table, p_end[rows],
                                                           grid, creep_grid)
        wear_p = equilibrium_wear_measures(cp.xi, cp.eta, cp.phi_per_mm, cp.a_mm, cp.b_mm,
                                       cp.normal_force_n, cp.fx_n, cp.fy_n, cp.mz_nmm,
                                       vehicle.friction, fastsim_grid)
        ws_p = wheelset_unknowns(q_p)
        pose = {"state": q_p,
                "wheelset_shift_mm": centre_shift(table, ws_p[..., 0], ws_p[..., 3:5]),
                "wheelset_roll_rad": wheelset_roll(table, ws_p[..., 0], ws_p[..., 3:5]),
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
            pipeline[row] = {**{f.name: getattr(cp, f.name)[j] for f in fields(BogieContacts)},
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
        ws = wheelset_unknowns(q[k])
        shown_r = np.inf if radius_m is None else float(radius_m)
        results.append(CurvingResult(
            radius_m=shown_r, direction=direction, cant_mm=float(cant_mm),
            speed_m_s=case.speed_m_s,
            unbalanced_acceleration_m_s2=case.unbalanced_acceleration_m_s2,
            wheelset_shift_mm=centre_shift(table, ws[:, 0], ws[:, 3:5]),
            contact_shift_mm=ws[:, 0].copy(),
            wheelset_roll_rad=wheelset_roll(table, ws[:, 0], ws[:, 3:5]),
            wheelset_yaw_rad=ws[:, 1] * 1e-3,
            rolling_ratio=1.0 + ws[:, 2] * 1e-3, bogie_shift_mm=float(q[k, 10]),
            bogie_yaw_rad=float(q[k, 11]) * 1e-3,
            **{f.name: getattr(c, f.name)[k] for f in fields(BogieContacts)},
            p0_mpa=wear["p0_mpa"][k],
            tau_max_mpa=wear["tau_max_mpa"][k], t_gamma_n=wear["t_gamma_n"][k],
            in_contact=wear["in_contact"][k], residual_norm=float(norm[k]),
            state=q[k].copy(), saturation_state=q_saturation[k].copy(),
            creep_grid=creep_grid, pipeline=pipeline[k],
            pipeline_residual_norm=float(pipeline_norm[k])))
    return results


def _solve_by_direction(vehicle: BogieVehicle, cases: list[CurveCase],
                        labels: list[tuple[float | None, str, float]] | None, tol: float,
                        fastsim_grid: int, skip_failed: bool,
                        initial_states: list[NDArray | None] | None, creep_grid: int | None,
                        contact_pipeline: bool, pipeline_equilibrium: bool
                        ) -> list[CurvingResult | None]:
    """:func:`solve_curving_cases_or_none` of a vehicle with a high and a low rail: the cases
    grouped by the curve's direction (tangent track apart), each group on its rails' table."""
    groups: dict[str | None, list[int]] = {}
    for k, c in enumerate(cases):
        kappa = c.curvature_per_m
        groups.setdefault(None if kappa == 0 else ("left" if kappa > 0 else "right"),
                          []).append(k)
    out: list[CurvingResult | None] = [None] * len(cases)
    for direction, idx in groups.items():
        res = solve_curving_cases_or_none(
            vehicle, [cases[k] for k in idx],
            None if labels is None else [labels[k] for k in idx],
            vehicle_contact_table(vehicle, direction), tol, fastsim_grid, skip_failed,
            None if initial_states is None else [initial_states[k] for k in idx],
            creep_grid, contact_pipeline, pipeline_equilibrium)
        for k, r in zip(idx, res, strict=True):
            out[k] = r
    return out


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
        c = bogie_contacts(table, q[:, 0:1], q[:, 1:2] * 1e-3, q[:, 2:3] * 1e-3,
                      q[:, None, 3:5], k, r0, friction)
        lat, vert, yaw, pitch = wheelset_loads(c)
        return np.concatenate([lat, yaw, -pitch, vert[:, 0] - wheel_load_n], axis=-1
                              ) / wheel_load_n

    q0 = np.array([[0.0, 0.0, 0.0, d0, d0]])
    q, norm, ok = continuation_batch(fun, q0, np.zeros((1, 1)), np.array([[kappa]]), tol)
    if not ok[0]:
        raise CurvingConvergenceError("free wheelset did not converge", sign * radius_m,
                                      float(norm[0]))
    c = bogie_contacts(table, q[:, 0:1], q[:, 1:2] * 1e-3, q[:, 2:3] * 1e-3, q[:, None, 3:5],
                  np.array([kappa]), r0, friction)
    loaded = c.normal_force_n[0, 0] > 0
    xi = np.array([np.sum(np.where(loaded[s], c.xi[0, 0, s], 0.0) * c.normal_force_n[0, 0, s])
                   / np.sum(c.normal_force_n[0, 0, s]) for s in range(2)])
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
    table = vehicle_contact_table(vehicle, "left")

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
