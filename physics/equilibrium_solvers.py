"""Batched solvers of the curving equilibrium: damped Newton with forward-difference Jacobians,
MINPACK's Powell hybrid as a fallback, continuation in the load parameters, and
pseudo-arclength continuation through folds where the natural continuation stops.

Generic in the residual: ``fun(q (N, n), params (N, p)) -> residual (N, n)``, many independent
equilibria solved at once (``curving.solve_curving_cases_or_none``).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import root


def _jacobian(fun, q, h=1e-6):
    """Forward-difference Jacobian of a batched residual, one vectorised call."""
    steps = h * np.maximum(1.0, np.abs(q))
    batch = q[None, :] + np.diag(steps)
    r_all = fun(np.vstack([q[None, :], batch]))
    return ((r_all[1:] - r_all[0]) / steps[:, None]).T


_LINE_SEARCH = np.array([1.0, 0.5, 0.25, 0.1, 0.03])


def newton_batch(fun, q0, params, tol, max_iter=20, h=1e-6, jac=None):
    """Damped Newton for many independent equilibria at once.

    fun(q (N, n), params (N, p)) -> residual (N, n). Each iteration evaluates the
    forward-difference Jacobians of all rows in one call and a backtracking line search (the
    full step, then the shorter steps of the rows it does not improve enough).
    ``jac(q (N, n), params, steps (N, n)) -> (residual (N, n), Jacobian (N, n, n))``: the
    same forward differences from a faster evaluator (column c from the step steps[:, c] on
    unknown c), used instead of the batched call of ``fun``. Returns (q, residual norms,
    converged mask).
    """
    q = np.array(q0, dtype=float)
    nb, n = q.shape
    norm = np.linalg.norm(fun(q, params), axis=-1)
    active = ~(norm < tol)
    eye = np.eye(n)
    for _ in range(max_iter):
        if not np.any(active):
            break
        idx = np.nonzero(active)[0]
        qa, pa = q[idx], params[idx]
        steps = h * np.maximum(1.0, np.abs(qa))  # (na, n)
        if jac is None:
            states = np.concatenate([qa[:, None, :], qa[:, None, :] + steps[:, :, None] * eye],
                                    axis=1)  # (na, n+1, n)
            res = fun(states.reshape(-1, n), np.repeat(pa, n + 1, axis=0)).reshape(
                len(idx), n + 1, n)
            r0 = res[:, 0]
            jm = np.swapaxes((res[:, 1:] - r0[:, None, :]) / steps[:, :, None], 1, 2)
        else:
            r0, jm = jac(qa, pa, steps)
        try:
            dx = np.linalg.solve(jm, -r0[..., None])[..., 0]
        except np.linalg.LinAlgError:
            dx = np.stack([np.linalg.lstsq(j, -r, rcond=None)[0] for j, r in zip(jm, r0,
                                                                                  strict=True)])
        n0 = np.linalg.norm(r0, axis=-1)
        trial = qa[:, None, :] + _LINE_SEARCH[None, :, None] * dx[:, None, :]
        # the full step first; the shorter ones only for the rows it does not improve enough
        # (the first good step is taken, so the others' residuals would not be used)
        n_ls = len(_LINE_SEARCH)
        nt = np.full((len(idx), n_ls), np.inf)
        nt[:, 0] = np.linalg.norm(fun(trial[:, 0], pa), axis=-1)
        rest = ~(nt[:, 0] < (1.0 - 1e-4 * _LINE_SEARCH[0]) * n0)
        if np.any(rest):
            nt[rest, 1:] = np.linalg.norm(
                fun(trial[rest, 1:].reshape(-1, n), np.repeat(pa[rest], n_ls - 1, axis=0)),
                axis=-1).reshape(-1, n_ls - 1)
        good = nt < (1.0 - 1e-4 * _LINE_SEARCH[None, :]) * n0[:, None]
        pick = np.where(np.any(good, axis=1), np.argmax(good, axis=1), np.argmin(nt, axis=1))
        improved = np.take_along_axis(nt, pick[:, None], axis=1)[:, 0] < n0
        new_q = trial[np.arange(len(idx)), pick]
        q[idx] = np.where(improved[:, None], new_q, qa)
        norm[idx] = np.where(improved, np.take_along_axis(nt, pick[:, None], axis=1)[:, 0], n0)
        stalled = ~improved
        active[idx] = ~(norm[idx] < tol) & ~stalled
    return q, norm, norm < tol


def _all_finite(a) -> bool:
    """Every entry of the array ``a`` is finite: one Python sum of its entries (finite: all
    entries are; Python floats overflow and meet inf - inf without numpy's warnings), the
    element test only when the sum is not finite (a non-finite entry, or an overflow)."""
    return math.isfinite(sum(a.ravel().tolist())) or bool(np.all(np.isfinite(a)))


def scipy_polish(fun, q0, param, tol, jac=None):
    """scipy.optimize.root (Powell hybrid) on one row, the fallback of the batched Newton.
    ``jac``: as :func:`newton_batch`'s (the same forward differences, faster)."""
    # MINPACK may probe non-finite states on a badly worn profile; answer those (and any
    # non-finite residual) with a large finite residual so it backs off instead of indexing the
    # contact table with NaN.
    # MINPACK calls f and jacobian hundreds of times per row, one state each: the finiteness
    # checks go through one sum (finite sum: every entry finite; a non-finite or overflowing
    # sum falls back to the element test), the same values as testing every entry.
    big = np.full(np.shape(q0), 1e12)
    param_row = np.ascontiguousarray(param, dtype=float)[None, :]

    def f(z):
        if not _all_finite(z):
            return big
        r = fun(z[None, :], param_row)[0]
        return r if _all_finite(r) else np.where(np.isfinite(r), r, 1e12)

    def jacobian(z):
        if not _all_finite(z):
            return np.eye(len(z))
        if jac is None:
            j = _jacobian(lambda qq: fun(qq, np.repeat(param_row, len(qq), axis=0)), z)
        else:
            j = jac(z[None, :], param_row, 1e-6 * np.maximum(1.0, np.abs(z))[None, :])[1][0]
        return j if _all_finite(j) else np.where(np.isfinite(j), j, 0.0)

    sol = root(f, q0, jac=jacobian, method="hybr", options={"xtol": 1e-13, "maxfev": 300})
    if not np.all(np.isfinite(sol.x)):
        return np.asarray(q0, dtype=float), float("inf"), False
    norm = float(np.linalg.norm(f(sol.x)))
    return sol.x, norm, norm < tol


def continuation_batch(fun, q_start, p_start, p_end, tol, max_halvings=10, jac=None):
    """Continuation of many equilibria in the load parameters p (N, p), linear from p_start to
    p_end, each row with its own step (doubled on success, halved on failure). Returns
    (q, norms, converged).

    A row that starts at its end parameters (p_start = p_end: a warm start from an earlier
    equilibrium) has no path to continue along: every retry would solve the same problem from
    the same state, so it gets one Newton solve and, if that fails, one Powell-hybrid solve
    (what the halvings would have repeated, deterministically, up to ``max_halvings`` times).
    ``jac``: as :func:`newton_batch`'s."""
    nb = len(q_start)
    q = np.array(q_start, dtype=float)
    t = np.zeros(nb)
    step = np.ones(nb)
    halvings = np.zeros(nb, dtype=int)
    norm = np.zeros(nb)
    failed = np.zeros(nb, dtype=bool)
    no_path = np.all(np.asarray(p_start) == np.asarray(p_end), axis=-1)
    while True:
        todo = (t < 1.0 - 1e-12) & ~failed
        if not np.any(todo):
            break
        idx = np.nonzero(todo)[0]
        t_try = np.minimum(t[idx] + step[idx], 1.0)
        params = p_start[idx] + t_try[:, None] * (p_end[idx] - p_start[idx])
        q_new, n_new, ok = newton_batch(fun, q[idx], params, tol, jac=jac)
        for k in np.nonzero(~ok)[0]:
            # small steps, or no path at all: let scipy try as well
            if no_path[idx[k]] or halvings[idx[k]] >= max_halvings // 2:
                q_s, n_s, ok_s = scipy_polish(fun, q[idx[k]], params[k], tol, jac=jac)
                if ok_s:
                    q_new[k], n_new[k], ok[k] = q_s, n_s, True
        q[idx[ok]] = q_new[ok]
        t[idx[ok]] = t_try[ok]
        step[idx[ok]] = np.minimum(step[idx[ok]] * 2.0, 1.0)
        # halve the step that was tried (t_try may have been cut at t = 1)
        step[idx[~ok]] = (t_try[~ok] - t[idx[~ok]]) / 2.0
        halvings[idx[~ok]] += 1
        norm[idx] = n_new
        failed[idx[~ok]] = (halvings[idx[~ok]] > max_halvings) | no_path[idx[~ok]]
    return q, norm, ~failed


#: Scale of the load parameter t in the arclength (t_scale t against the unknowns, which are
#: O(1-10) in mm, mrad and 1e-3): a step of arclength 1 moves t by at most 1 / ARC_T_SCALE.
ARC_T_SCALE = 10.0


def _augmented(jac, fun, q, tau, p_start, dp, h=1e-6):
    """Residual (N, n) and Jacobian (N, n, n + 1) of R(q, p_start + tau / ARC_T_SCALE dp) in
    the unknowns (q, tau): ``jac``'s forward differences in q plus one in tau."""
    params = p_start + (tau / ARC_T_SCALE)[:, None] * dp
    steps = h * np.maximum(1.0, np.abs(q))
    r, jq = jac(q, params, steps)
    r_t = fun(q, p_start + ((tau + h) / ARC_T_SCALE)[:, None] * dp)
    return r, np.concatenate([jq, ((r_t - r) / h)[:, :, None]], axis=2)


def _tangent(jm, v_prev):
    """Unit tangent (N, n + 1) of the solution curve: J w = 0 with w . v_prev = 1 (the
    orientation kept from the previous tangent, so the curve is followed through folds)."""
    nb, n, _ = jm.shape
    a = np.concatenate([jm, v_prev[:, None, :]], axis=1)
    b = np.zeros((nb, n + 1))
    b[:, -1] = 1.0
    w = _solve_rows(a, b)
    return w / np.linalg.norm(w, axis=-1, keepdims=True)


def _solve_rows(a, b):
    """a x = b row by row (batched solve; least squares for a singular row)."""
    try:
        return np.linalg.solve(a, b[..., None])[..., 0]
    except np.linalg.LinAlgError:
        return np.stack([np.linalg.lstsq(m, v, rcond=None)[0] for m, v in zip(a, b,
                                                                             strict=True)])


#: The arclength corrector's monotonicity test: a Newton correction more than this many times
#: the previous one ends the step as failed. 4 passes the S-curve's folds
#: (``tests/physics/test_equilibrium_solvers.py``; 2 does not: near a fold the corrector may
#: take one correction larger than the one before and still converge) and on the Aosta null
#: run of the diagnosis (README, Wear loop section, stop 33) ends most failed steps after 2-3
#: corrections instead of 8.
CORRECTION_GROWTH = 4.0


def arclength_continuation_batch(fun, q_start, p_start, p_end, tol, jac, ds0=0.5, ds_max=3.0,
                                 ds_min=1e-6, max_steps=300, corrector_iter=8, t_min=-2.0,
                                 max_growth=CORRECTION_GROWTH):
    """Pseudo-arclength continuation of R(q, p) = 0 along p = p_start + t (p_end - p_start),
    t from 0 to 1, for many independent rows: it follows the solution curve through folds
    (turning points in t), where :func:`continuation_batch` stops.

    Keller's pseudo-arclength method ([Keller 1977], [Allgower–Georg 2003] ch. 2 in
    docs/references.md): the unknowns are (q, tau) with tau = ARC_T_SCALE t; each step predicts
    along the unit tangent w (J w = 0, w . w_prev = 1) by the arclength ds and corrects by
    Newton on [R(q, tau) = 0, w . (x - x_pred) = 0]; a corrector that does not reach ``tol`` in
    ``corrector_iter`` iterations, or whose correction grows past ``max_growth`` times the one
    before (the monotonicity test of Newton's method, [Deuflhard 2004] ch. 2–3 in
    docs/references.md, in the loose form :data:`CORRECTION_GROWTH` explains), halves ds (the
    row fails below ``ds_min``), a converged step lengthens it by 1.5 (at most ``ds_max``).
    Where tau passes ARC_T_SCALE the state is interpolated to t = 1 and solved there by
    Newton. A row first solves t = 0 from
    ``q_start`` and sets out towards increasing t; a curve that turns back below ``t_min``
    (the start's branch leads away from the end) is followed once more from the start the
    other way round (an S-shaped curve of a start on its middle branch reaches t = 1 over
    the fold at negative t). ``jac``: as :func:`newton_batch`'s (required: the tangent needs
    J).
    Returns (q, residual norms at p_end, converged) like :func:`continuation_batch`; a row
    that fails keeps ``q_start``, with the residual norm of its Newton solve at t = 0 where
    that failed, of the final Newton solve at t = 1 where that failed, else inf (t = 1 not
    reached).

    Which equilibrium this finds: the one connected to the start through the folds. Past a
    fold a real system jumps to another branch (hysteresis); the connected one is where the
    quasi-static curving of a hollow-worn wheel ends up in the usual case that the branch
    through the folds carries on to t = 1 (the caller checks the answer like any other).
    """
    q0 = np.array(q_start, dtype=float)
    p_start = np.asarray(p_start, dtype=float)
    dp = np.asarray(p_end, dtype=float) - p_start
    nb = len(q0)
    q_out = q0.copy()
    norm_out = np.full(nb, np.inf)
    ok_out = np.zeros(nb, dtype=bool)
    q, norm, ok0 = newton_batch(fun, q0, p_start, tol, jac=jac)
    norm_out[:] = norm
    rows = np.nonzero(ok0)[0]
    for orientation in (1.0, -1.0):
        if rows.size == 0:
            break
        q_r, n_r, ok_r, back = _follow_curve(fun, jac, q[rows], p_start[rows], dp[rows], tol,
                                             orientation, ds0, ds_max, ds_min, max_steps,
                                             corrector_iter, t_min, max_growth)
        q_out[rows[ok_r]] = q_r[ok_r]
        norm_out[rows] = n_r
        ok_out[rows] = ok_r
        rows = rows[back]
    return q_out, norm_out, ok_out


def _follow_curve(fun, jac, q, p_start, dp, tol, orientation, ds0, ds_max, ds_min, max_steps,
                  corrector_iter, t_min, max_growth):
    """One pass of :func:`arclength_continuation_batch` from the equilibria q at t = 0,
    setting out towards increasing t (``orientation`` 1) or decreasing t (-1). Returns (q at
    t = 1, residual norms (inf where not reached), converged, turned back below t_min)."""
    nb, n = q.shape
    q_out = q.copy()
    norm_out = np.full(nb, np.inf)
    ok_out = np.zeros(nb, dtype=bool)
    x = np.concatenate([q, np.zeros((nb, 1))], axis=1)
    _, jm = _augmented(jac, fun, x[:, :n], x[:, n], p_start, dp)
    e_t = np.zeros_like(x)
    e_t[:, n] = 1.0
    v = orientation * _tangent(jm, e_t)
    ds = np.full(nb, ds0)
    steps = np.zeros(nb, dtype=int)
    active = np.ones(nb, dtype=bool)
    finish_q = np.zeros((nb, n))
    finished = np.zeros(nb, dtype=bool)
    while np.any(active):
        a = np.nonzero(active)[0]
        steps[a] += 1
        xp = x[a] + ds[a, None] * v[a]
        xc = xp.copy()
        conv = np.zeros(a.size, dtype=bool)
        diverged = np.zeros(a.size, dtype=bool)
        dx_prev = np.full(a.size, np.inf)
        jm_c = np.zeros((a.size, n, n + 1))
        for _ in range(corrector_iter):
            todo = np.nonzero(~conv & ~diverged)[0]
            if todo.size == 0:
                break
            r, jm = _augmented(jac, fun, xc[todo, :n], xc[todo, n], p_start[a[todo]],
                               dp[a[todo]])
            jm_c[todo] = jm
            arc = np.einsum("ij,ij->i", v[a[todo]], xc[todo] - xp[todo])
            done = (np.linalg.norm(r, axis=-1) < tol) & (np.abs(arc) < 1e-9)
            conv[todo[done]] = True
            go = todo[~done]
            if go.size == 0:
                break
            g = np.concatenate([r[~done], arc[~done, None]], axis=1)
            aug = np.concatenate([jm[~done], v[a[go]][:, None, :]], axis=1)
            dx = _solve_rows(aug, -g)
            # monotonicity test: a correction more than max_growth times the one before means
            # a corrector thrown off the curve (across a jump of the residual, or diverging):
            # the step fails now rather than after corrector_iter iterations
            dx_norm = np.linalg.norm(dx, axis=-1)
            up = dx_norm > max_growth * dx_prev[go]
            diverged[go[up]] = True
            dx_prev[go] = dx_norm
            go, dx = go[~up], dx[~up]
            xc[go] = xc[go] + dx
            bad = ~np.all(np.isfinite(xc[go]), axis=1)
            xc[go[bad]] = xp[go[bad]]
        # rows whose corrector converged: a step along the curve
        good, fail = a[conv], a[~conv]
        ds[fail] /= 2.0
        active[fail[ds[fail] < ds_min]] = False
        if good.size:
            x_new = xc[conv]
            past = x_new[:, n] >= ARC_T_SCALE
            for k in np.nonzero(past)[0]:
                i = good[k]
                w = (ARC_T_SCALE - x[i, n]) / (x_new[k, n] - x[i, n])
                finish_q[i] = x[i, :n] + w * (x_new[k, :n] - x[i, :n])
                finished[i] = True
                active[i] = False
            on = ~past
            if np.any(on):
                g_on = good[on]
                v[g_on] = _tangent(jm_c[conv][on], v[g_on])
                x[g_on] = x_new[on]
                ds[g_on] = np.minimum(ds[g_on] * 1.5, ds_max)
        back = x[:, n] < ARC_T_SCALE * t_min
        active &= (steps < max_steps) & ~back
    if np.any(finished):
        f = np.nonzero(finished)[0]
        q_f, n_f, ok_f = newton_batch(fun, finish_q[f], p_start[f] + dp[f], tol, jac=jac)
        q_out[f[ok_f]] = q_f[ok_f]
        norm_out[f] = n_f
        ok_out[f] = ok_f
    return q_out, norm_out, ok_out, x[:, n] < ARC_T_SCALE * t_min
