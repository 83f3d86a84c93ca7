"""Continuation of the curving equilibria: warm-started rows are solved once, not repeated.

A row whose continuation starts at its end parameters (the wear loop's warm start from the
last profile's equilibrium) has no path to halve: its retries would solve the same problem
from the same state. It gets one damped Newton solve and, if that fails, one Powell-hybrid
solve; a row continued from other parameters keeps the halvings and the Powell attempts on
small steps.
"""

from __future__ import annotations

import numpy as np

from wearcast.physics import equilibrium_solvers as es


def _count_calls(monkeypatch, calls: dict, key: str, module, name: str) -> None:
    """Count the calls of ``module.name`` in ``calls[key]`` (the function still runs)."""
    real = getattr(module, name)
    calls[key] = 0

    def counted(*a, **k):
        calls[key] += 1
        return real(*a, **k)

    monkeypatch.setattr(module, name, counted)


def _counting(monkeypatch):
    calls: dict = {}
    _count_calls(monkeypatch, calls, "newton", es, "newton_batch")
    _count_calls(monkeypatch, calls, "polish", es, "scipy_polish")
    return calls


def _no_root(q, p):
    """q^2 + 1 + p: never zero, so every solve fails."""
    return q * q + 1.0 + p


def test_a_warm_row_without_a_solution_is_tried_once_by_each_solver(monkeypatch):
    calls = _counting(monkeypatch)
    p = np.array([[0.5, 0.5]])
    q, norm, ok = es.continuation_batch(_no_root, np.array([[0.3, -0.2]]), p, p, 1e-9)
    assert not ok[0] and np.isfinite(norm[0]) and norm[0] > 1.0
    assert calls == {"newton": 1, "polish": 1}


def test_a_continued_row_keeps_its_halvings_and_polish_attempts(monkeypatch):
    calls = _counting(monkeypatch)
    q, norm, ok = es.continuation_batch(_no_root, np.array([[0.3, -0.2]]),
                                        np.zeros((1, 2)), np.array([[0.5, 0.5]]), 1e-9,
                                        max_halvings=10)
    assert not ok[0]
    # 11 failed attempts (halvings 0..10), Powell on the 6 with halvings >= 5
    assert calls == {"newton": 11, "polish": 6}


def test_a_warm_row_newton_misses_is_the_powell_solution_from_the_warm_state(monkeypatch):
    def fun(q, p):
        return np.arctan(q - p)

    def newton_fails(fun, q0, params, tol, **kw):
        return np.array(q0, dtype=float), np.full(len(q0), np.inf), np.zeros(len(q0), bool)

    q0 = np.array([[0.2, -0.2], [0.0, 0.1]])
    p = np.array([[0.5, -0.25], [0.4, 0.3]])
    expected = [es.scipy_polish(fun, q0[k], p[k], 1e-9) for k in range(2)]
    monkeypatch.setattr(es, "newton_batch", newton_fails)
    q, norm, ok = es.continuation_batch(fun, q0, p, p, 1e-9)
    assert np.all(ok)
    for k in range(2):
        np.testing.assert_array_equal(q[k], expected[k][0])
        assert norm[k] == expected[k][1]


def test_a_warm_row_newton_solves_is_newtons_answer():
    def fun(q, p):
        return np.arctan(q - p) + 0.1 * (q - p) ** 3

    q0 = np.array([[0.45, -0.2]])
    p = np.array([[0.5, -0.25]])
    q_n, norm_n, ok_n = es.newton_batch(fun, q0, p, 1e-9)
    q, norm, ok = es.continuation_batch(fun, q0, p, p, 1e-9)
    assert ok_n[0] and ok[0]
    np.testing.assert_array_equal(q, q_n)
    np.testing.assert_allclose(q[0], p[0], atol=1e-8)


def test_the_polish_finiteness_check_is_the_element_test_also_on_overflow_and_nan():
    """scipy_polish checks states and residuals through one sum: a sum that overflows from
    finite entries must still count them finite, a NaN or infinite entry must not."""
    huge = np.array([1e308, 1e308, -1.0])  # finite entries whose sum overflows
    assert not np.isfinite(sum(huge.tolist()))
    for a in (np.array([1.0, -2.0, 3.5]), huge, np.array([1.0, np.nan, 2.0]),
              np.array([np.inf, -np.inf]), np.array([[1.0, 2.0], [np.inf, 0.0]]),
              np.zeros((2, 3))):
        assert es._all_finite(a) == bool(np.all(np.isfinite(a)))



def test_a_failed_step_cut_at_the_end_is_really_halved(monkeypatch):
    """A step that reaches past t = 1 is cut there; when it fails, the next attempt from the
    same t is half the step that was tried, not the same cut step again (stop 30's C1634-L3
    on a worn rail repeated t 0.969 -> 1 until its halvings ran out)."""
    attempts: list[tuple[float, float]] = []

    def fake_newton(fun, q, params, tol, **_):
        t_from, t_try = q[:, 0], params[:, 0]
        attempts.extend(zip(t_from.tolist(), t_try.tolist(), strict=True))
        ok = np.where(t_from < 0.5, t_try - t_from <= 0.5, t_try - t_from <= 0.1)
        return np.where(ok[:, None], params, q), np.where(ok, 0.0, 1.0), ok

    monkeypatch.setattr(es, "newton_batch", fake_newton)
    monkeypatch.setattr(es, "scipy_polish", lambda fun, q, p, tol, jac=None: (q, 1.0, False))
    q, norm, ok = es.continuation_batch(lambda q, p: q - p, np.zeros((1, 1)),
                                        np.zeros((1, 1)), np.ones((1, 1)), 1e-9)
    assert ok[0] and q[0, 0] == 1.0
    assert len(attempts) == len(set(attempts)), attempts


def _s_curve(q, p):
    """q^3 - 3 q - p: an S-shaped curve of equilibria in p, folds at (q, p) = (-1, 2) and
    (1, -2)."""
    return q ** 3 - 3.0 * q - p


def _s_curve_jac(q, p, steps):
    return _s_curve(q, p), (3.0 * q ** 2 - 3.0)[:, :, None]


def test_arclength_continuation_follows_the_curve_through_its_folds():
    # from the lower branch (q = -sqrt 3 at p = 0) to p = 3: the natural continuation stops at
    # the fold p = 2; the curve through both folds reaches the upper branch's root q = 2.1038
    q0 = np.array([[-np.sqrt(3.0)], [0.0], [2.0]])
    p0 = np.array([[0.0], [0.0], [2.0]])
    p1 = np.array([[3.0], [3.0], [5.0]])
    _, _, ok_natural = es.continuation_batch(_s_curve, q0[:1], p0[:1], p1[:1], 1e-10,
                                             jac=_s_curve_jac)
    assert not ok_natural[0]
    q, norm, ok = es.arclength_continuation_batch(_s_curve, q0, p0, p1, 1e-10,
                                                  jac=_s_curve_jac)
    assert ok.all() and np.all(norm < 1e-10)
    upper = np.roots([1.0, 0.0, -3.0, -3.0]).real.max()
    # row 1 starts on the middle branch: towards increasing p it folds back at p = 2 and runs
    # off to p -> -inf; set out the other way it turns at p = -2 and reaches the upper branch
    assert abs(q[0, 0] - upper) < 1e-9 and abs(q[1, 0] - upper) < 1e-9
    # a row already on a branch without folds is solved where natural continuation goes
    assert abs(_s_curve(q[2:], p1[2:])[0, 0]) < 1e-10 and q[2, 0] > 2.0


def test_arclength_rows_are_independent():
    q0 = np.array([[-np.sqrt(3.0)], [0.0], [2.0]])
    p0 = np.array([[0.0], [0.0], [2.0]])
    p1 = np.array([[3.0], [3.0], [5.0]])
    q_all, _, ok_all = es.arclength_continuation_batch(_s_curve, q0, p0, p1, 1e-10,
                                                       jac=_s_curve_jac)
    for k in range(3):
        q_k, _, ok_k = es.arclength_continuation_batch(_s_curve, q0[k:k + 1], p0[k:k + 1],
                                                       p1[k:k + 1], 1e-10, jac=_s_curve_jac)
        assert ok_k[0] == ok_all[k] and abs(q_k[0, 0] - q_all[k, 0]) < 1e-9


def test_arclength_reports_a_row_without_an_equilibrium_as_failed():
    # q^2 + 1 + p has no root at all, not even at the start: not converged, q_start kept
    q, norm, ok = es.arclength_continuation_batch(
        _no_root, np.array([[0.3, -0.2]]), np.zeros((1, 2)), np.array([[0.5, 0.5]]), 1e-9,
        jac=lambda q, p, s: (_no_root(q, p), np.stack([np.diag(2.0 * r) for r in q])))
    assert not ok[0] and norm[0] > 1.0 and np.array_equal(q, [[0.3, -0.2]])


def _jump(q, p):
    """arctan(q - p), its root moved by 2 where q > 1 (a contact changing hands): the curve of
    equilibria q = p breaks at p = 1, and Newton on arctan from 2 away diverges (its
    corrections grow), so no continuation crosses it."""
    return np.arctan(q - p + 2.0 * (q > 1.0))


def _jump_jac(q, p, steps):
    d = q - p + 2.0 * (q > 1.0)
    return _jump(q, p), 1.0 / (1.0 + d * d)[:, :, None]


def _counting_corrector(monkeypatch):
    calls: dict = {}
    _count_calls(monkeypatch, calls, "augmented", es, "_augmented")
    return calls


def test_the_corrector_gives_up_a_step_whose_residual_grows(monkeypatch):
    """Pseudo-arclength across a jump of the residual: the row fails either way, with the
    monotonicity test after fewer corrector iterations (each failed step ends when a
    correction grows past CORRECTION_GROWTH times the one before, not after corrector_iter
    iterations)."""
    calls = _counting_corrector(monkeypatch)
    args = (_jump, np.zeros((1, 1)), np.zeros((1, 1)), np.array([[3.0]]), 1e-10)
    runs = {}
    for label, growth in (("test", es.CORRECTION_GROWTH), ("no test", np.inf)):
        calls["augmented"] = 0
        q, norm, ok = es.arclength_continuation_batch(*args, jac=_jump_jac,
                                                      max_growth=growth)
        runs[label] = (bool(ok[0]), q[0, 0], calls["augmented"])
    assert runs["test"][:2] == runs["no test"][:2] == (False, 0.0)
    assert runs["test"][2] < 0.7 * runs["no test"][2], runs


def test_the_monotonicity_test_keeps_the_folds_answer():
    """On the smooth S-curve the test rejects nothing a converging corrector needs: the same
    roots through both folds as without it."""
    q0 = np.array([[-np.sqrt(3.0)], [0.0], [2.0]])
    p0 = np.array([[0.0], [0.0], [2.0]])
    p1 = np.array([[3.0], [3.0], [5.0]])
    q_t, n_t, ok_t = es.arclength_continuation_batch(_s_curve, q0, p0, p1, 1e-10,
                                                     jac=_s_curve_jac)
    q_n, n_n, ok_n = es.arclength_continuation_batch(_s_curve, q0, p0, p1, 1e-10,
                                                     jac=_s_curve_jac, max_growth=np.inf)
    assert ok_t.all() and ok_n.all()
    np.testing.assert_allclose(q_t, q_n, atol=1e-9)
