"""Equilibrium of the bogie with the contact pipeline's forces at its pose (issue 11).

The curving equilibrium (``curving``) is solved with the contact table's elastic patches
(``bogie_equations``); here the one contact pipeline (``curving_contacts``) is evaluated at an
equilibrium's pose (``pipeline_at``), the bogie residual with its forces (``pipeline_residual``)
and, on request, the equilibrium of those forces by Broyden's method from the table's
(``pipeline_force_equilibrium``; ``curving.solve_curving_cases_or_none`` with
``pipeline_equilibrium=True``).
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.bogie_equations import (
    SHEAR_MODULUS_MPA,
    BogieContacts,
    bogie_residual,
    centre_shift,
    wheel_loads,
    wheelset_roll,
)
from wearcast.physics.curving_contacts import pipeline_contacts
from wearcast.physics.curving_table import TAPE_CIRCLE_HALF_SPACING_MM, ContactTable
from wearcast.physics.vehicles import BogieVehicle


def pipeline_at(q, vehicle: BogieVehicle, table: ContactTable, params, creep_grid: int
                 ) -> tuple[BogieContacts, NDArray, NDArray, dict[int, str]]:
    """The pipeline's contacts (``curving_contacts``) at the states q (m, 12) with parameters
    (m, >= 2): (contacts, peak pressures [MPa], ok (m,), errors per row)."""
    m = q.shape[0]
    ws = q[:, :10].reshape(m, 2, 5)
    y, d = ws[..., 0], ws[..., 3:5]
    loads = np.broadcast_to(wheel_loads(vehicle, params[:, 1])[:, None, :], (m, 2, 2))
    pc = pipeline_contacts(table.track, TAPE_CIRCLE_HALF_SPACING_MM - table.rail_offset_mm,
                           centre_shift(table, y, d), ws[..., 1] * 1e-3, wheelset_roll(table, y, d),
                           1.0 + ws[..., 2] * 1e-3, loads, params[:, 0], vehicle.friction,
                           SHEAR_MODULUS_MPA, creep_grid)
    c = BogieContacts(**{f.name: getattr(pc, f.name) for f in fields(BogieContacts)})
    return c, pc.peak_pressure_mpa, pc.ok, pc.errors


#: Scaled residual (as DEFAULT_TOLERANCE) at which the equilibrium with the pipeline's forces
#: counts as found (``pipeline_force_equilibrium``): 1e-3 of the static wheel load, 50 N on a 50 kN
#: wheel. The pipeline's forces are only piecewise smooth in the pose (patches merge and split,
#: Hertz and the coarse BEM take turns, its normal / tangential coupling settles to 1e-4 of the
#: load), so a tighter tolerance is not reached.
PIPELINE_TOLERANCE = 1e-3
#: Most Broyden iterations of ``pipeline_force_equilibrium``.
PIPELINE_MAX_ITERATIONS = 40
#: Largest Broyden step in any scaled unknown of ``pipeline_force_equilibrium`` (mm, mrad, 1e-3).
PIPELINE_MAX_STEP = 1.0
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


def pipeline_force_equilibrium(q, vehicle: BogieVehicle, table: ContactTable, params, grid: int,
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
        return bogie_residual(qq, vehicle, table, pp[:, 0], pp[:, 1], pp[:, 2],
                               creep_grid=creep_grid)

    steps = 1e-6 * np.maximum(1.0, np.abs(q))
    states = q[:, None, :] + np.concatenate([np.zeros((m, 1, n)),
                                             steps[:, :, None] * np.eye(n)], axis=1)
    r_all = table_res(states.reshape(-1, n), np.repeat(params, n + 1, axis=0)).reshape(
        m, n + 1, n)
    jac = np.swapaxes((r_all[:, 1:] - r_all[:, :1]) / steps[:, :, None], 1, 2)
    _, _, ok, _, f = pipeline_residual(q, vehicle, table, params, grid, creep_grid)
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
        _, _, ok_n, _, f_new = pipeline_residual(x_new, vehicle, table, params[act], grid,
                                                  creep_grid)
        worse = ok_n & (np.linalg.norm(f_new, axis=-1) > norm[act])
        if np.any(worse):
            w = np.nonzero(worse)[0]
            x_new[w] = q[act[w]] + 0.3 * dx[w]
            _, _, ok_w, _, f_w = pipeline_residual(x_new[w], vehicle, table, params[act[w]],
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

