"""Saturated creep law (Kalker linear + Shen-Hedrick-Elkins) against FASTSIM."""

import numpy as np
import pytest

from wearcast.physics.contact.creep import creep_forces, creep_forces_fastsim, she_saturation
from wearcast.physics.contact.kalker import kalker_coefficients, linear_creep_forces

A, B, FN, MU = 6.0, 4.0, 80_000.0, 0.3
# characteristic creepage: linear force reaches mu Fn
C_CHAR = MU * FN / (82_000.0 * A * B * float(kalker_coefficients(A, B).c11))


def test_small_creepage_is_linear_and_large_saturates():
    lin = linear_creep_forces(1e-7, 2e-7, 1e-8, A, B)
    she = creep_forces(1e-7, 2e-7, 1e-8, A, B, FN, MU)
    # SHE ratio is 1 - u/3 + ..., u = F_lin/(mu Fn) ~ 1e-4 here
    assert she.fx_n == pytest.approx(lin.fx_n, rel=1e-4)
    assert she.mz_nmm == pytest.approx(lin.mz_nmm, rel=1e-4)
    big = creep_forces(0.1, -0.05, 0.0, A, B, FN, MU)
    assert np.hypot(big.fx_n, big.fy_n) == pytest.approx(MU * FN, rel=1e-12)


def test_saturation_is_smooth_at_the_switch():
    u = np.array([3 - 1e-6, 3 + 1e-6])
    f = u * she_saturation(u)
    assert f == pytest.approx([1.0, 1.0], abs=1e-9)
    # slope of F_sat(u) = (1 - u/3)^2 vanishes at u = 3 from the left (C1; indeed C2)
    h = 1e-4
    slope = ((3 - h) * she_saturation(3 - h) - (3 - 2 * h) * she_saturation(3 - 2 * h)) / h
    assert abs(slope) < 1e-6


def test_odd_in_creepage_and_zero_without_load():
    f1 = creep_forces(1e-3, -2e-3, 1e-4, A, B, FN, MU)
    f2 = creep_forces(-1e-3, 2e-3, -1e-4, A, B, FN, MU)
    assert (f1.fx_n, f1.fy_n, f1.mz_nmm) == pytest.approx((-f2.fx_n, -f2.fy_n, -f2.mz_nmm))
    zero = creep_forces(1e-3, 0.0, 0.0, A, B, 0.0, MU)
    assert zero.fx_n == 0.0


def test_agreement_with_fastsim_over_creepage_range():
    # Measured agreement (module docstring / report): pure xi or eta from 0 to 8 x the
    # characteristic creepage: |F_SHE - F_FASTSIM| <= 0.01 mu Fn; random xi, eta within 4 x and
    # spin |phi a| within the characteristic creepage: max 0.085, mean 0.03 mu Fn.
    s = np.linspace(-8, 8, 33) * C_CHAR
    zero = np.zeros_like(s)
    for xi, eta in ((s, zero), (zero, s)):
        she = creep_forces(xi, eta, zero, A, B, FN, MU)
        fs = creep_forces_fastsim(xi, eta, zero, A, B, FN, MU, n_x=60, n_y=60)
        err = np.hypot(she.fx_n - fs.fx_n, she.fy_n - fs.fy_n) / (MU * FN)
        assert err.max() < 0.01
    rng = np.random.default_rng(1)
    xi, eta = rng.uniform(-4, 4, (2, 200)) * C_CHAR
    phi = rng.uniform(-1, 1, 200) * C_CHAR / A
    she = creep_forces(xi, eta, phi, A, B, FN, MU)
    fs = creep_forces_fastsim(xi, eta, phi, A, B, FN, MU, n_x=60, n_y=60)
    err = np.hypot(she.fx_n - fs.fx_n, she.fy_n - fs.fy_n) / (MU * FN)
    assert err.max() < 0.1
    assert err.mean() < 0.04


def test_large_spin_is_the_known_weakness():
    # Pure spin far beyond the characteristic value: FASTSIM's lateral force peaks near
    # 0.75 mu Fn and falls to ~0.5 mu Fn at phi a = 8 x the characteristic creepage, while SHE
    # saturates the linear spin force to mu Fn. Documented; asserted so a change shows.
    phi = 8 * C_CHAR / A
    she = creep_forces(0.0, 0.0, phi, A, B, FN, MU)
    fs = creep_forces_fastsim(0.0, 0.0, phi, A, B, FN, MU, n_x=60, n_y=60)
    assert abs(she.fy_n) / (MU * FN) > 0.99
    assert 0.4 < abs(fs.fy_n) / (MU * FN) < 0.6


def test_compiled_kernel_matches_numpy_reference():
    # the compiled saturated forces (kalker_kernel.saturated_creep_flat) against the numpy
    # reference: linear range, saturation, spin, unloaded patches and zero friction, broadcast
    from wearcast.physics.contact.creep import _creep_forces_numpy

    rng = np.random.default_rng(3)
    n = 500
    xi, eta = rng.normal(0.0, 3e-3, (2, n))
    phi = rng.normal(0.0, 2e-4, n)
    a, b = rng.uniform(0.5, 12.0, (2, n))
    fn = np.where(rng.random(n) < 0.1, 0.0, rng.uniform(0.0, 1e5, n))
    xi[:5] = 0.0
    eta[:5] = 0.0
    phi[:5] = 0.0
    for mu in (0.3, np.where(rng.random(n) < 0.1, 0.0, 0.35)):
        got = creep_forces(xi, eta, phi, a, b, fn, mu)
        ref = _creep_forces_numpy(xi, eta, phi, a, b, fn, mu)
        for name in ("fx_n", "fy_n", "mz_nmm", "saturation"):
            np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-12,
                                       atol=1e-9)
    shaped = creep_forces(xi[:6].reshape(2, 3), 0.0, 0.0, 6.0, 4.0, 80_000.0, 0.3)
    assert shaped.fx_n.shape == (2, 3)
    with pytest.raises(ValueError):
        creep_forces(1e-3, 0.0, 0.0, 0.0, 4.0, 80_000.0, 0.3)
