"""The bogie's equilibrium residual and its forward-difference Jacobian as compiled kernels.

``bogie_residual_flat(q, params, tab, tab_right, consts, creep_grid)`` does per state what
``bogie_equations.bogie_residual`` does (creep forces from the smooth Kalker +
Shen-Hedrick-Elkins law of ``contact.creep``, creep_grid 0, or from FASTSIM on an n x n grid):
the contact candidates of each wheel at its shift (``contact_candidates_kernel.slots_one``),
their columns as ``ContactTable._candidate_columns`` (contact angle, rolling radius, Hertz
constants from the smoothed gap's curvature), Hertz normal forces, creepages, the saturated
creep forces (``contact.kalker_kernel.saturated_creep_one``) or FASTSIM's
(``contact.fastsim_kernel.fastsim_totals_one``), the wheelset loads and the 12 scaled
equations (primary and secondary suspension, wheel loads with the cant deficiency's transfer).
A slot without weight or normal force adds exact zeros (its columns and creep forces are not
computed). ``bogie_jacobian_flat`` gives the residual and the forward differences the solvers
take, reusing the loads of the wheelset a perturbation leaves unchanged.

The numpy ``bogie_equations.bogie_residual`` is the reference: the two agree to rounding
(``tests/physics/test_bogie_residual_kernel.py``). The equilibrium solvers evaluate the residual
some 20,000 times per whole-vehicle wear run, most of the calls for one state (MINPACK's
fallback, ``equilibrium_solvers.scipy_polish``) or a handful (the batched Newton's
forward-difference Jacobians), where the numpy form's cost is the overhead of some hundred
array passes over a few dozen numbers (``benchmarks/bench_vehicle_wear_aosta.py``).

Equations, frames and units: ``bogie_equations`` (Wickens / Elkins-Gostling steady curving).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from wearcast.physics.contact.fastsim_kernel import fastsim_totals_one
from wearcast.physics.contact.kalker_kernel import saturated_creep_one
from wearcast.physics.contact.min_gap_kernel import interp_on_interval
from wearcast.physics.contact_candidates_kernel import slot_workspace, slots_one

#: Distinct shifts whose candidates are remembered while a batch is evaluated (the
#: forward-difference Jacobian perturbs the other unknowns at unchanged shifts).
_SHIFT_MEMORY = 16


@njit(cache=True)
def interp_like_numpy(x: float, xp: NDArray[np.float64], fp: NDArray[np.float64]) -> float:
    """``np.interp(x, xp, fp)`` for one x on an increasing grid, with numpy's arithmetic
    (clamped ends, the value at an exact grid point, the slope form between points)."""
    n = xp.size
    if x >= xp[n - 1]:
        return fp[n - 1]
    if x < xp[0]:
        return fp[0]
    # bisection: xp[j] <= x < xp[j + 1]
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) >> 1
        if xp[mid] <= x:
            lo = mid
        else:
            hi = mid
    j = lo
    if xp[j] == x:
        return fp[j]
    return interp_on_interval(x, xp, fp, j)


@njit(cache=True)
def _candidate_columns(shift: float, yc: float, slot_gap: float, g2: float,
                       wheel_y: NDArray[np.float64], wheel_z: NDArray[np.float64],
                       contact_slope: NDArray[np.float64], grid0: float, grid_step: float,
                       r0: float, min_b: float, max_b: float,
                       log_ratio: NDArray[np.float64], approach1: NDArray[np.float64],
                       a1: NDArray[np.float64], b1: NDArray[np.float64], half_spacing: float,
                       out: NDArray[np.float64]) -> None:
    """One candidate's columns (``ContactTable._candidate_columns``) into out: gap, angle,
    lateral [mm], rolling radius [m], approach1 [mm], a1, b1 [mm]. ``contact_slope``
    (n_shift, n_y) on the shift grid ``grid0 + i grid_step``, taken like
    ``ContactTable.contact_slope_at``."""
    wz = interp_like_numpy(yc, wheel_y, wheel_z)
    pos = (shift - grid0) / grid_step
    pos = min(max(pos, 0.0), contact_slope.shape[0] - 1.000001)
    k = int(np.floor(pos))
    w = pos - np.floor(pos)
    slope = ((1.0 - w) * interp_like_numpy(yc, wheel_y, contact_slope[k])
             + w * interp_like_numpy(yc, wheel_y, contact_slope[k + 1]))
    angle = math.atan(-slope)
    cos = math.cos(angle)
    radius = r0 + wz / 1000.0
    curv_a = cos / (2.0 * radius * 1000.0)
    curv_b = min(max(0.5 * g2 * cos**3, min_b), max_b)
    lr = min(max(math.log(curv_b / curv_a), log_ratio[0]), log_ratio[log_ratio.size - 1])
    scale = np.cbrt(curv_a)
    out[0] = slot_gap
    out[1] = angle
    out[2] = half_spacing + shift + yc
    out[3] = radius
    out[4] = interp_like_numpy(lr, log_ratio, approach1) * scale
    out[5] = interp_like_numpy(lr, log_ratio, a1) / scale
    out[6] = interp_like_numpy(lr, log_ratio, b1) / scale


#: Indices of the constants array (``bogie_equations.compiled_residual`` builds it).
#: SLOTS holds the patch slot count per wheel (``contact_candidates_kernel.N_SLOTS``), read
#: at run time rather than compiled in as a global, so a changed slot count never meets a
#: kernel cached with the old one.
(R0, MU, SHEAR, NU, Q_WHEEL, SEMI_WHEELBASE, K_PY, K_PSI, M_WHEELSET, M_REST, K_SECONDARY,
 CENTRES, GRAVITY, COG_HEIGHT, HALF_SPACING, MIN_B, MAX_B, PROMINENCE, SEPARATION, SHARE,
 NO_CONTACT, SPIN_OFFSET, GRID0, GRID_STEP, SLOT_FADE, SLOTS) = range(26)
N_CONSTS = 26


@njit(cache=True)
def _new_memory(n_slots: int) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                       NDArray[np.float64], NDArray[np.int64],
                                       NDArray[np.float64], NDArray[np.float64]]:
    """Remembered shifts, their slot columns (gap, angle, lateral, radius, approach1, a1, b1),
    weights, the next slot to overwrite; work space of ``slots_one`` and for its outputs;
    for n_slots patch slots per wheel."""
    return (np.full(_SHIFT_MEMORY, np.nan), np.empty((_SHIFT_MEMORY, n_slots, 7)),
            np.empty((_SHIFT_MEMORY, n_slots)), np.zeros(1, dtype=np.int64),
            slot_workspace(n_slots), np.empty((4, n_slots)))


@njit(cache=True)
def _slot_columns(shift, tab, consts, memory, g_row):
    """Index into ``memory`` of the candidate columns at ``shift`` (computed if not there)."""
    mem_shift, mem_cols, mem_w, mem_next, work, slots = memory
    for m in range(_SHIFT_MEMORY):
        if mem_shift[m] == shift:
            return m
    (gap, gap2, smoothing, wheel_y, wheel_z, contact_slope, _, _, log_ratio, approach1, a1, b1,
     _, _) = tab
    s_y = slots[0]
    s_gap = slots[1]
    s_g2 = slots[2]
    s_w = slots[3]
    n_slots = s_w.shape[0]
    slots_one(gap, gap2, smoothing, consts[GRID0], consts[GRID_STEP], wheel_y, shift, n_slots,
              consts[PROMINENCE], consts[SEPARATION], consts[SHARE], consts[NO_CONTACT],
              consts[SLOT_FADE], g_row, work, s_y, s_gap, s_g2, s_w)
    hit = mem_next[0]
    mem_next[0] = (hit + 1) % _SHIFT_MEMORY
    mem_shift[hit] = shift
    for t in range(n_slots):
        if s_w[t] == 0.0:
            # a slot without weight (a missing candidate, or one not yet or no longer mature)
            # carries no normal force, so no creep force: every load it adds is an exact zero
            # whatever its columns, given finite ones (the numpy reference computes them)
            cols = mem_cols[hit, t]
            cols[0] = s_gap[t]
            cols[1] = 0.0
            cols[2] = consts[HALF_SPACING] + shift + s_y[t]
            cols[3] = consts[R0]
            cols[4] = 1.0
            cols[5] = 1.0
            cols[6] = 1.0
        else:
            _candidate_columns(shift, s_y[t], s_gap[t], s_g2[t], wheel_y, wheel_z,
                               contact_slope, consts[GRID0], consts[GRID_STEP], consts[R0],
                               consts[MIN_B], consts[MAX_B], log_ratio,
                               approach1, a1, b1, consts[HALF_SPACING], mem_cols[hit, t])
        mem_w[hit, t] = s_w[t]
    return hit


@njit(cache=True)
def _wheelset_sums(qrow, w, k, tab, tab_right, consts, memory, memory_right, g_row,
                   creep_grid, out):
    """Track-frame loads of wheelset w's contacts (``bogie_equations.wheelset_loads``) into
    out: lateral [N], vertical left and right [N], yaw moment [N m], sum r Fx [N m]. The
    left wheel's candidates come from ``tab`` (remembered in ``memory``), the right wheel's
    from ``tab_right`` (``memory_right``): the table of each wheel's own rail."""
    kalker_table = tab[12]
    kalker_rows = tab[13]
    r0 = consts[R0]
    y = qrow[5 * w]
    psi = qrow[5 * w + 1] * 1e-3
    ratio = 1.0 + qrow[5 * w + 2] * 1e-3
    lat = 0.0
    yaw = 0.0
    pitch = 0.0
    for side in range(2):
        sgn = 1.0 if side == 0 else -1.0
        if side == 0:
            hit = _slot_columns(y, tab, consts, memory, g_row)
            mem_cols = memory[1]
            mem_w = memory[2]
        else:
            hit = _slot_columns(-y, tab_right, consts, memory_right, g_row)
            mem_cols = memory_right[1]
            mem_w = memory_right[2]
        d = qrow[5 * w + 3 + side]
        vert = 0.0
        for t in range(mem_w.shape[1]):
            cols = mem_cols[hit, t]
            angle = cols[1]
            lateral = cols[2]
            radius = cols[3]
            cos = math.cos(angle)
            sin = math.sin(angle)
            approach = (d - cols[0]) * cos
            normal = mem_w[hit, t] * max(approach, 0.0) ** 1.5 / cols[4] ** 1.5
            if not normal > 0:
                # no normal force, no traction bound: both creep laws give zero forces, and
                # every load this patch adds is zero
                continue
            n13 = np.cbrt(normal)
            a = cols[5] * n13
            b = cols[6] * n13
            xi = 1.0 - k * sgn * lateral / 1000.0 - ratio * radius / r0
            eta = -sgn * psi / cos  # the contact point's lead (bogie_equations)
            phi = (-ratio * sin / r0 + sgn * k * cos) / 1000.0
            if creep_grid == 0:
                fx, fy, mz, _ = saturated_creep_one(xi, eta, phi, a, b, normal, consts[MU],
                                                    consts[SHEAR], consts[NU], kalker_table,
                                                    kalker_rows)
            else:
                fx, fy, mz = fastsim_totals_one(xi, eta, phi, a, b, normal, consts[MU],
                                                consts[SHEAR], consts[NU], creep_grid,
                                                creep_grid, consts[SPIN_OFFSET], kalker_table,
                                                kalker_rows)
            lat += sgn * (-normal * sin + fy * cos)
            vert += normal * cos + fy * sin
            yaw += -(sgn * lateral / 1000.0) * fx + sgn * mz * cos / 1000.0
            pitch += radius * fx
        out[1 + side] = vert
    out[0] = lat
    out[3] = yaw
    out[4] = pitch


@njit(cache=True)
def _assemble(qrow, k, a_unb, torque, sums, tab, tab_right, consts, out):
    """The 12 scaled equations of a state from its wheelsets' loads ``sums`` (2, 5)
    (``bogie_equations.bogie_residual``) into out; each wheel's rigid rise from its own
    table (``tab`` left, ``tab_right`` right; one shift grid)."""
    shift_grid = tab[6]
    rigid_rise = tab[7]
    rigid_rise_right = tab_right[7]
    r0 = consts[R0]
    q_wheel = consts[Q_WHEEL]
    am = consts[SEMI_WHEELBASE]
    half_spacing = consts[HALF_SPACING]
    yb = qrow[10]
    psib = qrow[11] * 1e-3
    dq = q_wheel * (a_unb / consts[GRAVITY]) * consts[COG_HEIGHT] / (half_spacing / 1000.0)
    bogie_f = 0.0
    bogie_m = 0.0
    for w in range(2):
        x = am if w == 0 else -am
        y = qrow[5 * w]
        psi = qrow[5 * w + 1] * 1e-3
        rise_left = interp_like_numpy(y, shift_grid, rigid_rise) - qrow[5 * w + 3]
        rise_right = interp_like_numpy(-y, shift_grid, rigid_rise_right) - qrow[5 * w + 4]
        roll = (rise_left - rise_right) / (2.0 * half_spacing)
        y_centre = y - 1000.0 * r0 * roll
        dy = (y_centre + 1000.0 * k * x**2 / 2.0 - yb - 1000.0 * psib * x) / 1000.0
        dpsi = psi + k * x - psib
        f_prim = -consts[K_PY] * dy
        m_prim = -consts[K_PSI] * dpsi
        out[5 * w] = (sums[w, 0] + f_prim - consts[M_WHEELSET] * a_unb) / q_wheel
        out[5 * w + 1] = (sums[w, 3] + m_prim) / q_wheel
        out[5 * w + 2] = (torque - sums[w, 4]) / q_wheel
        out[5 * w + 3] = (sums[w, 1] - (q_wheel - dq)) / q_wheel
        out[5 * w + 4] = (sums[w, 2] - (q_wheel + dq)) / q_wheel
        bogie_f += -f_prim
        bogie_m += -m_prim - x * f_prim
    body_yaw = -k * consts[CENTRES] / 2.0
    out[10] = (bogie_f - consts[M_REST] * a_unb) / q_wheel
    out[11] = (bogie_m - consts[K_SECONDARY] * (psib - body_yaw)) / q_wheel


@njit(cache=True)
def _finite(row) -> bool:
    for v in row:
        if not math.isfinite(v):
            return False
    return True


@njit(cache=True)
def bogie_residual_flat(q, params, tab, tab_right, consts, creep_grid):
    """Scaled residual (N, 12) of the states q (N, 12) at the load parameters params (N, 3):
    curvature kappa [1/m], unbalanced acceleration a_unb [m/s^2], torque [N m]; with the
    creep forces of the saturation law (``creep_grid`` 0) or of FASTSIM on a creep_grid x
    creep_grid grid (``fastsim_kernel.fastsim_totals_one``, CONTACT's spin offset).

    tab: the contact table's gap, g'', smoothing, wheel y, z and slope, shift grid, rigid rise,
    Hertz log ratio, approach1, a1, b1, and Kalker's table and row shapes, of the left wheel;
    tab_right: the same of the right wheel (its own rail; the same arrays when both rails
    are one profile, the mirrored track; one shift grid and wheel grid size); consts: the
    constants at the indices above (``bogie_equations.compiled_residual``). A state with a
    non-finite entry gets a NaN residual."""
    n = q.shape[0]
    out = np.empty((n, 12))
    memory = _new_memory(int(consts[SLOTS]))
    memory_right = _new_memory(int(consts[SLOTS]))
    g_row = np.empty(tab[0].shape[1])
    sums = np.empty((2, 5))
    for i in range(n):
        if not _finite(q[i]):
            out[i, :] = np.nan
            continue
        for w in range(2):
            _wheelset_sums(q[i], w, params[i, 0], tab, tab_right, consts, memory,
                           memory_right, g_row, creep_grid, sums[w])
        _assemble(q[i], params[i, 0], params[i, 1], params[i, 2], sums, tab, tab_right, consts,
                  out[i])
    return out


@njit(cache=True)
def bogie_jacobian_flat(q, steps, params, tab, tab_right, consts, creep_grid):
    """Residual r0 (N, 12) of the states q and its forward-difference Jacobian (N, 12, 12),
    column c = (r(q + steps[c] e_c) - r0) / steps[c], as the solvers' finite differences
    (``equilibrium_solvers``) compute from :func:`bogie_residual_flat` -- the same numbers:
    a wheelset's contacts depend on its own five unknowns only, so a perturbed state reuses
    the other wheelset's loads (and both for the bogie's two unknowns) instead of recomputing
    them. A state with a non-finite entry gets NaN."""
    n = q.shape[0]
    r0 = np.empty((n, 12))
    jac = np.empty((n, 12, 12))
    memory = _new_memory(int(consts[SLOTS]))
    memory_right = _new_memory(int(consts[SLOTS]))
    g_row = np.empty(tab[0].shape[1])
    base = np.empty((2, 5))
    sums = np.empty((2, 5))
    qp = np.empty(12)
    rp = np.empty(12)
    for i in range(n):
        if not _finite(q[i]):
            r0[i, :] = np.nan
            jac[i, :, :] = np.nan
            continue
        k = params[i, 0]
        a_unb = params[i, 1]
        torque = params[i, 2]
        for w in range(2):
            _wheelset_sums(q[i], w, k, tab, tab_right, consts, memory, memory_right, g_row,
                           creep_grid, base[w])
        _assemble(q[i], k, a_unb, torque, base, tab, tab_right, consts, r0[i])
        for c in range(12):
            for j in range(12):
                qp[j] = q[i, j]
            qp[c] = q[i, c] + steps[i, c]
            for w in range(2):
                for j in range(5):
                    sums[w, j] = base[w, j]
            if c < 10:
                _wheelset_sums(qp, c // 5, k, tab, tab_right, consts, memory, memory_right,
                               g_row, creep_grid, sums[c // 5])
            _assemble(qp, k, a_unb, torque, sums, tab, tab_right, consts, rp)
            for j in range(12):
                jac[i, j, c] = (rp[j] - r0[i, j]) / steps[i, c]
    return r0, jac
