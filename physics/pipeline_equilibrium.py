"""Equilibrium of the bogie with the contact pipeline's forces at its pose (issue 11).

The curving equilibrium (``curving``) is solved with the contact table's elastic patches
(``bogie_equations``); here the one contact pipeline (``curving_contacts``) is evaluated at an
equilibrium's pose (``pipeline_at``), the bogie residual with its forces (``pipeline_residual``)
and, on request, the equilibrium of those forces by a homotopy from the table's
(``pipeline_force_equilibrium``; ``curving.solve_curving_cases_or_none`` with
``pipeline_equilibrium=True``, ``wear_tables`` with ``contact_model="pipeline_equilibrium"``).
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.bogie_equations import (
    N_STATE,
    SHEAR_MODULUS_MPA,
    BogieContacts,
    CompiledBogie,
    bogie_residual,
    centre_shift,
    wheel_loads,
    wheelset_roll,
    wheelset_unknowns,
)
from wearcast.physics.curving_contacts import pipeline_contacts
from wearcast.physics.curving_table import TAPE_CIRCLE_HALF_SPACING_MM, ContactTable
from wearcast.physics.vehicles import BogieVehicle


def pipeline_at(q, vehicle: BogieVehicle, table: ContactTable, params, creep_grid: int
                 ) -> tuple[BogieContacts, NDArray, NDArray, dict[int, str]]:
    """The pipeline's contacts (``curving_contacts``) at the states q (m, 12) with parameters
    (m, >= 2): (contacts, peak pressures [MPa], ok (m,), errors per row)."""
    m = q.shape[0]
    ws = wheelset_unknowns(q)
    y, d = ws[..., 0], ws[..., 3:5]
    loads = np.broadcast_to(wheel_loads(vehicle, params[:, 1])[:, None, :], (m, 2, 2))
    origins = (TAPE_CIRCLE_HALF_SPACING_MM - table.rail_offset_mm,
               TAPE_CIRCLE_HALF_SPACING_MM - table.side(1).rail_offset_mm)
    pc = pipeline_contacts(table.track, origins,
                           centre_shift(table, y, d), ws[..., 1] * 1e-3, wheelset_roll(table, y, d),
                           1.0 + ws[..., 2] * 1e-3, loads, params[:, 0], vehicle.friction,
                           SHEAR_MODULUS_MPA, creep_grid)
    c = BogieContacts(**{f.name: getattr(pc, f.name) for f in fields(BogieContacts)})
    return c, pc.peak_pressure_mpa, pc.ok, pc.errors


#: Scaled residual (as DEFAULT_TOLERANCE) at which the equilibrium with the pipeline's forces
#: counts as found (``pipeline_force_equilibrium``): 2e-3 of the static wheel load, 100 N on a
#: 50 kN wheel. The pipeline's forces are only piecewise smooth in the pose (patches merge and
#: split, Hertz and the coarse BEM take turns, its normal / tangential coupling settles to 1e-4
#: of the load), so a tighter tolerance is not always reached: on the Aosta and metro B classes
#: (``benchmarks/table_contact_models.py``) 46 of 48 operating points stop below 1e-3, the
#: Minuetto trailer at 162 m (cant 110 mm) at 1.01e-3 and at 774 m (cant 40 mm) at 1.9e-3,
#: where no step of the line search lowers the residual further.
PIPELINE_TOLERANCE = 2e-3
#: First load step of the homotopy F_table + lambda (F_pipeline - F_table) from the table's
#: equilibrium (lambda = 0) to the pipeline's (lambda = 1) in ``pipeline_force_equilibrium``;
#: a solved step doubles the next (up to ``PIPELINE_LARGEST_STEP``), a failed one is halved.
PIPELINE_FIRST_STEP = 0.25
#: Pipeline residual at the table's equilibrium (scaled, as PIPELINE_TOLERANCE) below which
#: the homotopy starts with the whole load step (lambda = 1): the contacts differ little
#: (tread contacts, large radii) and one Newton solve finds the pipeline's equilibrium.
PIPELINE_DIRECT_RESIDUAL = 0.1
#: Largest load step of the homotopy: in one step of 0.5 from the table's equilibrium Newton
#: runs off into flange climbing at 150 m (Manchester trailer, measured).
PIPELINE_LARGEST_STEP = 0.25
#: Smallest load step before a row counts as failed.
PIPELINE_SMALLEST_STEP = 1.0 / 32.0
#: Scaled residual at which an intermediate homotopy stage counts as solved (the last stage
#: needs ``PIPELINE_TOLERANCE``).
PIPELINE_STAGE_TOLERANCE = 1e-2
#: Most Newton iterations per homotopy stage of ``pipeline_force_equilibrium``.
PIPELINE_MAX_ITERATIONS = 8
#: Largest Newton step in any scaled unknown of ``pipeline_force_equilibrium`` (mm, mrad, 1e-3).
PIPELINE_MAX_STEP = 2.0
#: Forward-difference steps of the pipeline's contact forces in the wheelset unknowns
#: (y [mm], psi [mrad], e [1e-3], d_left, d_right [mm]): 10 um, above the pipeline's
#: normal / tangential coupling noise (1e-4 of the load) over its flange stiffness.
PIPELINE_FD_STEPS = np.array([1e-2, 1e-2, 1e-2, 1e-2, 1e-2])
#: Step lengths of the backtracking line search on the homotopy residual.
_LINE_SEARCH = (1.0, 0.5, 0.25, 0.1)
#: Residual rows of the wheels' vertical loads (state layout above).
_VERTICAL_ROWS = [3, 4, 8, 9]


def pipeline_residual(q, vehicle: BogieVehicle, table: ContactTable, params, grid: int,
                       creep_grid: int | None):
    """The bogie residual with the pipeline's contact forces at the states q (m, 12).

    The pipeline carries each wheel's prescribed vertical load by construction, so the vertical
    rows keep the table's equations: they fix the approaches d, which only set the roll.
    Returns (contacts, peak pressures, ok, errors, residual (m, 12))."""
    c, peak, ok, errors = pipeline_at(q, vehicle, table, params, grid)
    res = bogie_residual(q, vehicle, table, params[:, 0], params[:, 1], params[:, 2],
                          contacts=c)
    res_t = bogie_residual(q, vehicle, table, params[:, 0], params[:, 1], params[:, 2],
                            creep_grid=creep_grid)
    res[:, _VERTICAL_ROWS] = res_t[:, _VERTICAL_ROWS]
    return c, peak, ok, errors, res


def _pipeline_defect(q, vehicle: BogieVehicle, table: ContactTable, params, grid: int,
                     creep_grid: int | None, compiled: CompiledBogie):
    """The pipeline's residual less the table's at the states q (m, 12): (defect (m, 12),
    ok (m,)). Only the contact rows differ (lateral, yaw, pitch of each wheelset); the
    suspension's terms cancel."""
    _, _, ok, _, f_p = pipeline_residual(q, vehicle, table, params, grid, creep_grid)
    return f_p - compiled.residual(q, params), ok


def _defect_jacobian(q, defect, vehicle: BogieVehicle, table: ContactTable, params, grid: int,
                     creep_grid: int | None, compiled: CompiledBogie):
    """Forward-difference Jacobian (m, 12, 12) of the defect (``_pipeline_defect``) and the
    rows where every perturbed pipeline evaluation succeeded. A wheelset's contacts depend on
    its own five unknowns only, so one pipeline evaluation perturbs the same unknown of both
    wheelsets and gives two blocks: five evaluations in all."""
    m = q.shape[0]
    jac = np.zeros((m, N_STATE, N_STATE))
    ok = np.ones(m, dtype=bool)
    for c, h in enumerate(PIPELINE_FD_STEPS):
        qq = q.copy()
        qq[:, [c, 5 + c]] += h
        d_c, ok_c = _pipeline_defect(qq, vehicle, table, params, grid, creep_grid, compiled)
        diff = (d_c - defect) / h
        if not np.all(ok_c):
            # the pipeline fails at a few isolated poses (an empty patch list within 5 um of a
            # patch split on a flange root): a backward difference there
            b = np.nonzero(~ok_c)[0]
            qb = q[b].copy()
            qb[:, [c, 5 + c]] -= h
            d_b, ok_b = _pipeline_defect(qb, vehicle, table, params[b], grid, creep_grid,
                                         compiled)
            diff[b] = (defect[b] - d_b) / h
            ok_c[b] = ok_b
        ok &= ok_c
        jac[:, 0:5, c] = diff[:, 0:5]
        jac[:, 5:10, 5 + c] = diff[:, 5:10]
    return jac, ok


def _newton_stage(q, defect, f_table, lam, tol, vehicle: BogieVehicle, table: ContactTable,
                  params, grid: int, creep_grid: int | None, compiled: CompiledBogie, best):
    """Newton's method on F_table + lambda defect (rows' lambda (k,), tolerances (k,)) from the
    states q (k, 12) with their defects and table residuals; updates ``best`` (states and
    norms of the full pipeline residual, indexed like q) with every evaluated state. Returns
    (q, defect, f_table, converged (k,)), new arrays."""
    q, defect, f_table = q.copy(), defect.copy(), f_table.copy()
    fd = 1e-6 * np.maximum(1.0, np.abs(q))
    norm = np.linalg.norm(f_table + lam[:, None] * defect, axis=-1)
    stalled = np.zeros(q.shape[0], dtype=bool)
    for _ in range(PIPELINE_MAX_ITERATIONS):
        act = np.nonzero(~stalled & ~(norm < tol))[0]
        if act.size == 0:
            break
        qa, pa, la = q[act], params[act], lam[act]
        f_t, j_t = compiled.jacobian(qa, pa, fd[act])
        j_d, ok_j = _defect_jacobian(qa, defect[act], vehicle, table, pa, grid, creep_grid,
                                     compiled)
        stalled[act[~ok_j]] = True
        jac = j_t + la[:, None, None] * j_d
        rhs = -(f_t + la[:, None] * defect[act])
        try:
            dx = np.linalg.solve(jac, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:
            dx = np.stack([np.linalg.lstsq(a, b, rcond=None)[0]
                           for a, b in zip(jac, rhs, strict=True)])
        dx *= np.minimum(1.0, PIPELINE_MAX_STEP / np.max(np.abs(dx), axis=-1))[:, None]
        moved = np.zeros(act.size, dtype=bool)
        todo = ~stalled[act]
        for alpha in _LINE_SEARCH:
            rows = np.nonzero(todo)[0]
            if rows.size == 0:
                break
            x_new = qa[rows] + alpha * dx[rows]
            d_new, ok_n = _pipeline_defect(x_new, vehicle, table, pa[rows], grid, creep_grid,
                                           compiled)
            f_new = compiled.residual(x_new, pa[rows])
            full = np.where(ok_n, np.linalg.norm(f_new + d_new, axis=-1), np.inf)
            b = act[rows]
            better = full < best[1][b]
            best[0][b[better]], best[1][b[better]] = x_new[better], full[better]
            n_new = np.linalg.norm(f_new + la[rows, None] * d_new, axis=-1)
            good = ok_n & (n_new < (1.0 - 1e-4 * alpha) * norm[b])
            g = b[good]
            q[g], defect[g], f_table[g], norm[g] = (x_new[good], d_new[good], f_new[good],
                                                    n_new[good])
            moved[rows[good]] = True
            todo[rows[good]] = False
        # a row that no step improves has stalled
        stalled[act[~moved]] = True
    return q, defect, f_table, norm < tol


def pipeline_force_equilibrium(q, vehicle: BogieVehicle, table: ContactTable, params, grid: int,
                               creep_grid: int | None) -> tuple[NDArray, NDArray]:
    """Equilibrium states (m, 12) of the bogie with the pipeline's contact forces, and the
    scaled norms of the pipeline's residual there (m,).

    Homotopy from the table's equilibria q: F(q, lambda) = F_table(q) + lambda (F_pipeline(q) -
    F_table(q)), lambda from 0 to 1 in steps from ``PIPELINE_FIRST_STEP`` (1 where the
    pipeline's residual at q is below ``PIPELINE_DIRECT_RESIDUAL``; doubled after a
    solved step up to ``PIPELINE_LARGEST_STEP``, halved after a failed one down to
    ``PIPELINE_SMALLEST_STEP``; Allgower & Georg 1990, ch. 1-2, a natural-parameter
    continuation). Each step is solved by Newton's method with the Jacobian
    J_table + lambda J_defect -- the table's from its compiled forward differences
    (``CompiledBogie.jacobian``), the defect's from forward differences of the pipeline
    (``_defect_jacobian``, five pipeline evaluations; keeping it over full steps, a chord
    method, took a third more evaluations) -- and a backtracking line search on |F(., lambda)|.

    Why not Newton or Broyden on F_pipeline from the table's equilibrium: on a flange the
    pipeline's lateral force is nearly flat in the shift over millimetres (0.6-0.7 wheel loads
    from the flank at 62-70 deg while the table's roll lifts the wheel) and then falls by a
    wheel load within 0.1 mm, where its conformal root-flank patch moves from the flank to the
    root: |F_pipeline| rises on the way from the table's pose to the root (the line search
    stops) and falls the other way, into flange climbing (the shift ran to -20 mm at 150 m).
    Along the homotopy the table's restoring stiffness keeps the path on the root side until
    the pipeline's stiff band holds it.

    Returns per row the state of the smallest pipeline residual found and that residual's norm
    (rows where the pipeline fails keep theirs, with an infinite norm; the caller reports
    them).
    """
    q = np.array(q, dtype=float)
    m = q.shape[0]
    compiled = CompiledBogie(vehicle, table, creep_grid)
    defect, ok = _pipeline_defect(q, vehicle, table, params, grid, creep_grid, compiled)
    f_table = compiled.residual(q, params)
    best = (q.copy(), np.where(ok, np.linalg.norm(f_table + defect, axis=-1), np.inf))
    lam = np.zeros(m)
    step = np.where(best[1] < PIPELINE_DIRECT_RESIDUAL, 1.0, PIPELINE_FIRST_STEP)
    failed = ~ok
    while True:
        act = np.nonzero(~failed & (lam < 1.0))[0]
        if act.size == 0:
            break
        lam_try = np.minimum(lam[act] + step[act], 1.0)
        tol = np.where(lam_try >= 1.0, PIPELINE_TOLERANCE, PIPELINE_STAGE_TOLERANCE)
        sub_best = (best[0][act].copy(), best[1][act].copy())
        q_n, d_n, f_n, conv = _newton_stage(q[act], defect[act], f_table[act], lam_try, tol,
                                            vehicle, table, params[act], grid, creep_grid,
                                            compiled, sub_best)
        best[0][act], best[1][act] = sub_best
        a = act[conv]
        q[a], defect[a], f_table[a], lam[a] = q_n[conv], d_n[conv], f_n[conv], lam_try[conv]
        step[a] = np.minimum(2.0 * step[a], PIPELINE_LARGEST_STEP)
        f = act[~conv]
        step[f] *= 0.5
        failed[f[step[f] < PIPELINE_SMALLEST_STEP]] = True
    return best
