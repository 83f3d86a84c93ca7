"""Kalker's creepage coefficients: table nodes, nu interpolation, continuity, asymptotes."""

import numpy as np
import pytest

from wearcast.physics.contact.kalker import (
    fastsim_flexibilities,
    kalker_coefficients,
    linear_creep_forces,
)

# Rows typed from Kalker's tables of the linear-theory coefficients (Kalker 1967,
# docs/references.md).
NODES = [
    # (a, b, nu, C11, C22, C23, C33)
    (0.1, 1.0, 0.0, 2.51, 2.51, 0.334, 6.42),
    (0.5, 1.0, 0.25, 3.62, 3.01, 0.929, 1.93),
    (1.0, 1.0, 0.5, 5.20, 3.98, 1.63, 1.16),
    (1.0, 0.5, 0.25, 5.10, 4.90, 2.62, 0.82),
    (1.0, 0.1, 0.5, 12.9, 16.0, 18.0, 0.23),
    (1.0, 0.8, 0.0, 3.65, 3.65, 1.58, 1.10),
]


@pytest.mark.parametrize(("a", "b", "nu", "c11", "c22", "c23", "c33"), NODES)
def test_exact_values_at_table_nodes(a, b, nu, c11, c22, c23, c33):
    c = kalker_coefficients(a, b, nu)
    assert (c.c11, c.c22, c.c23, c.c33) == pytest.approx((c11, c22, c23, c33), rel=1e-12)


def test_nu_interpolation_reproduces_nodes_and_stays_between():
    g = np.linspace(0.1, 1.0, 10)
    for nu in (0.0, 0.25, 0.5):
        c = kalker_coefficients(g, 1.0, nu)
        assert np.all(np.isfinite(c.c11))
    lo = kalker_coefficients(g, 1.0, 0.25)
    hi = kalker_coefficients(g, 1.0, 0.5)
    mid = kalker_coefficients(g, 1.0, 0.28)
    assert np.all((mid.c11 > lo.c11) & (mid.c11 < hi.c11))


def test_contact_flexibilities_for_fastsim_inp():
    # CONTACT fastsim.ref_out prints FLX1..3 = 0.4937e-4, 0.5152e-4, 0.4090e-4 for a=8, b=4,
    # G=82 GPa, nu=0.28, AFTER its combined-flexibility rule (w = 0.080). Undoing that rule
    # (test_fastsim checks the rule) the plain values must be L = 8a/(3 C G) etc. with our C.
    l1, l2, l3 = fastsim_flexibilities(8.0, 4.0, 82_000.0, 0.28)
    c = kalker_coefficients(8.0, 4.0, 0.28)
    assert l1 == pytest.approx(64 / (3 * c.c11 * 82_000.0))
    assert l3 == pytest.approx(np.pi * 8 * np.sqrt(2) / (4 * c.c23 * 82_000.0))


def test_continuity_at_a_equals_b():
    eps = 1e-7
    left = kalker_coefficients(1.0 - eps, 1.0, 0.28)
    right = kalker_coefficients(1.0, 1.0 - eps, 0.28)
    for name in ("c11", "c22", "c23", "c33"):
        assert getattr(left, name) == pytest.approx(getattr(right, name), rel=1e-5)


def test_outside_table_uses_asymptotes_and_refuses_bad_nu():
    c = kalker_coefficients(0.01, 1.0, 0.0)
    assert c.c11 == pytest.approx(np.pi**2 / 4)  # Kalker's a << b asymptote
    assert c.c33 == pytest.approx(6.42)  # held at the g = 0.1 row
    with pytest.raises(ValueError, match="poisson"):
        kalker_coefficients(1.0, 1.0, 0.6)


def test_linear_forces_odd_in_creepage():
    f1 = linear_creep_forces(1e-3, -2e-3, 1e-4, 6.0, 4.0)
    f2 = linear_creep_forces(-1e-3, 2e-3, -1e-4, 6.0, 4.0)
    assert (f1.fx_n, f1.fy_n, f1.mz_nmm) == pytest.approx((-f2.fx_n, -f2.fy_n, -f2.mz_nmm))
    c = kalker_coefficients(6.0, 4.0)
    assert f1.fx_n == pytest.approx(-82_000.0 * 24.0 * c.c11 * 1e-3)


def test_compiled_kernel_matches_numpy_reference():
    # the compiled kernel (kalker_kernel) against the numpy reference over the table's rows,
    # between them, the slender asymptotes on both sides and several Poisson ratios
    from wearcast.physics.contact.kalker import _kalker_coefficients_numpy

    rng = np.random.default_rng(7)
    ratio = np.concatenate([np.geomspace(1e-3, 1e3, 400), rng.uniform(0.05, 20.0, 400),
                            [0.1, 1.0, 10.0]])
    a = rng.uniform(0.5, 10.0, ratio.size)
    for nu in (0.0, 0.25, 0.28, 0.5):
        got = kalker_coefficients(a, a / ratio, nu)
        ref = _kalker_coefficients_numpy(a, a / ratio, nu)
        for name in ("c11", "c22", "c23", "c33"):
            np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-12,
                                       atol=0.0)
    assert np.shape(kalker_coefficients(np.ones((2, 3)), 2.0).c23) == (2, 3)
