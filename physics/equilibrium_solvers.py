"""Batched solvers of the curving equilibrium: damped Newton with forward-difference Jacobians,
MINPACK's Powell hybrid as a fallback, and continuation in the load parameters.

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
        step[idx[~ok]] /= 2.0
        halvings[idx[~ok]] += 1
        norm[idx] = n_new
        failed[idx[~ok]] = (halvings[idx[~ok]] > max_halvings) | no_path[idx[~ok]]
    return q, norm, ~failed
