"""FASTSIM against CONTACT's published fastsim example, and its physical limits."""

import numpy as np
import pytest

from wearcast.physics.contact.fastsim import contact_combined_flexibilities, fastsim
from wearcast.physics.contact.kalker import fastsim_flexibilities, linear_creep_forces

# CONTACT examples/fastsim.inp and its fastsim.ref_out (Vollebregt CONTACT, docs/references.md):
# a=8, b=4 mm, Fn=82 kN, G=82 GPa, nu=0.28, mu=0.3, xi=0, eta=-6.25e-4, phi=6.25e-4 1/mm.
CASE = dict(xi=0.0, eta=-6.25e-4, phi_per_mm=6.25e-4, a_mm=8.0, b_mm=4.0,
            normal_force_n=82_000.0, mu=0.3)
MU_FN = 0.3 * 82_000.0


@pytest.mark.parametrize(
    ("bound", "n", "fy_rel", "mz_nmm", "n_adh"),
    [
        # fastsim.ref_out cases 2, 3 (40x40) and 5, 6 (200x200): Fy/(mu Fn), Mz, NADH.
        ("parabolic", 40, -0.6118, -3.900e4, 738),
        ("elliptic", 40, -0.6016, -4.829e4, 618),
        ("parabolic", 200, -0.6359, -3.798e4, 18424),
        ("elliptic", 200, -0.5956, -4.530e4, 16572),
    ],
)
def test_reproduces_contact_fastsim_reference(bound, n, fy_rel, mz_nmm, n_adh):
    # Same discretisation and flexibility rule as CONTACT, so agreement to the printed digits
    # (4 decimals in Fy/(mu Fn), 4 significant digits in Mz) and the exact adhesion count.
    r = fastsim(**CASE, bound=bound, n_x=n, n_y=n)
    assert r.fy_n / MU_FN == pytest.approx(fy_rel, abs=5e-5)
    assert r.mz_nmm == pytest.approx(mz_nmm, abs=5.1e1)
    assert abs(r.fx_n) < 1e-6
    assert int(r.adhesion.sum()) == n_adh
    assert int(r.in_contact.sum()) == (1264 if n == 40 else 31428)


def test_combined_flexibility_rule_matches_contact_printout():
    # fastsim.ref_out prints FLX1..3 = 0.4937e-4, 0.5152e-4, 0.4090e-4; README: w = 0.080.
    l1, l2, l3, w = contact_combined_flexibilities(**CASE)
    assert (l1, l2, l3) == pytest.approx((0.4937e-4, 0.5152e-4, 0.4090e-4), abs=5e-9)
    assert w == pytest.approx(0.080, abs=5e-4)


def test_close_to_exact_theory():
    # CONTACT's exact (half-space) solution: Fy/(mu Fn) = -0.6074; FASTSIM is an approximation
    # (within ~1% here on 40x40, ~5% on 200x200 parabolic) -> loose 6% check, both bounds.
    for bound in ("parabolic", "elliptic"):
        r = fastsim(**CASE, bound=bound)
        assert r.fy_n / MU_FN == pytest.approx(-0.6074, rel=0.06)


def test_small_creepage_gives_linear_theory():
    # Tiny creepages: full adhesion, and textbook FASTSIM's continuum limit is Kalker's linear
    # Fx = -G a b C11 xi, Fy = -G a b C22 eta (by construction of L1, L2). CONTACT's march is
    # first order (each strip's first element counts a whole step from the leading edge): on
    # 120x120 the excess is ~0.9 %, so 1.5 % tolerance; the error halves with the step.
    a, b = 6.0, 4.0
    r = fastsim(1e-7, -2e-7, 0.0, a, b, 80_000.0, 0.3, n_x=120, n_y=120,
                combined_flexibility=False)
    lin = linear_creep_forces(1e-7, -2e-7, 0.0, a, b)
    assert r.fx_n == pytest.approx(lin.fx_n, rel=1.5e-2)
    assert r.fy_n == pytest.approx(lin.fy_n, rel=1.5e-2)
    fine = fastsim(1e-7, -2e-7, 0.0, a, b, 80_000.0, 0.3, n_x=240, n_y=120,
                   combined_flexibility=False)
    assert abs(fine.fx_n / lin.fx_n - 1) < 0.6 * abs(r.fx_n / lin.fx_n - 1)
    assert r.adhesion.sum() == r.in_contact.sum()
    # pure spin: Fy = -G (ab)^1.5 C23 phi through L3
    r = fastsim(0.0, 0.0, 1e-8, a, b, 80_000.0, 0.3, n_x=120, n_y=120,
                combined_flexibility=False)
    lin = linear_creep_forces(0.0, 0.0, 1e-8, a, b)
    assert r.fy_n == pytest.approx(lin.fy_n, rel=1.5e-2)


def test_large_creepage_saturates_and_fully_slides():
    r = fastsim(0.05, 0.05, 0.0, 6.0, 4.0, 80_000.0, 0.3)
    ft = np.hypot(r.fx_n, r.fy_n)
    assert ft == pytest.approx(0.3 * 80_000.0, rel=2e-3)  # discrete sum of the bound
    assert r.slip_area_fraction > 0.97
    assert np.all(r.shear_traction_mpa <= 0.3 * r.pn_mpa + 1e-9)
    # slip opposes traction where the patch slides
    dot = r.sx * r.px_mpa + r.sy * r.py_mpa
    assert np.all(dot[r.slipping] <= 1e-12)


@pytest.mark.parametrize("combined", [True, False])
def test_odd_symmetry_in_creepage(combined):
    args = (6.0, 4.0, 60_000.0, 0.3)
    r1 = fastsim(2e-3, -1e-3, 3e-4, *args, combined_flexibility=combined)
    r2 = fastsim(-2e-3, 1e-3, -3e-4, *args, combined_flexibility=combined)
    assert r1.fx_n == pytest.approx(-r2.fx_n, rel=1e-12)
    assert r1.fy_n == pytest.approx(-r2.fy_n, rel=1e-12)
    assert r1.mz_nmm == pytest.approx(-r2.mz_nmm, rel=1e-12)


def test_pure_lateral_creepage_gives_no_longitudinal_force_and_mirror_symmetry():
    r = fastsim(0.0, 1e-3, 0.0, 6.0, 4.0, 60_000.0, 0.3)
    assert abs(r.fx_n) < 1e-9 * abs(r.fy_n)
    # no spin: the traction field is mirror-symmetric in y
    assert np.allclose(r.py_mpa, r.py_mpa[::-1, :])


def test_batching_equals_single_runs():
    xi = np.array([1e-3, -2e-3, 0.0])
    eta = np.array([0.0, 1e-3, -3e-3])
    phi = np.array([1e-4, 0.0, -2e-4])
    a = np.array([5.0, 8.0, 3.0])
    b = np.array([4.0, 3.0, 7.0])
    batch = fastsim(xi, eta, phi, a, b, 70_000.0, 0.25)
    for k in range(3):
        one = fastsim(xi[k], eta[k], phi[k], a[k], b[k], 70_000.0, 0.25)
        assert batch.fy_n[k] == pytest.approx(float(one.fy_n), rel=1e-12)
        assert np.array_equal(batch.adhesion[k], one.adhesion)
    assert batch.px_mpa.shape == (3, 40, 40)


def test_textbook_flexibilities_option():
    r = fastsim(**CASE, combined_flexibility=False)
    assert np.allclose(r.flexibility_mm_per_mpa, fastsim_flexibilities(8.0, 4.0))
    # textbook FASTSIM is a little stiffer here: |Fy| larger than CONTACT's -0.6118
    assert r.fy_n / MU_FN < -0.6118


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="bound"):
        fastsim(**CASE, bound="square")
    with pytest.raises(ValueError, match="semi-axes"):
        fastsim(0, 0, 0, -1.0, 1.0, 1.0, 0.3)


@pytest.mark.parametrize(
    ("bound", "n", "fy_rel", "mz_nmm"),
    [("parabolic", 40, -0.6118, -3.900e4), ("elliptic", 40, -0.6016, -4.829e4),
     ("parabolic", 200, -0.6359, -3.798e4)],
)
def test_fast_totals_reproduce_contact_and_fastsim(bound, n, fy_rel, mz_nmm):
    # fastsim_forces (compiled kernel, totals only) gives CONTACT's printed numbers and the
    # same totals as the numpy march of fastsim, to rounding
    from wearcast.physics.contact.fastsim import fastsim_forces

    r = fastsim_forces(**CASE, bound=bound, n_x=n, n_y=n)
    assert r.fy_n / MU_FN == pytest.approx(fy_rel, abs=5e-5)
    assert r.mz_nmm == pytest.approx(mz_nmm, abs=5.1e1)
    rng = np.random.default_rng(3)
    k = 50
    args = dict(xi=rng.uniform(-3e-3, 3e-3, k), eta=rng.uniform(-3e-3, 3e-3, k),
                phi_per_mm=rng.uniform(-1e-3, 1e-3, k), a_mm=rng.uniform(2, 9, k),
                b_mm=rng.uniform(2, 9, k), normal_force_n=rng.uniform(1e4, 1e5, k), mu=0.3)
    full = fastsim(**args, bound=bound, n_x=n, n_y=n)
    fast = fastsim_forces(**args, bound=bound, n_x=n, n_y=n)
    scale = 0.3 * args["normal_force_n"]
    np.testing.assert_allclose(fast.fx_n / scale, full.fx_n / scale, atol=1e-12)
    np.testing.assert_allclose(fast.fy_n / scale, full.fy_n / scale, atol=1e-12)
    np.testing.assert_allclose(fast.mz_nmm / (scale * args["a_mm"]),
                               full.mz_nmm / (scale * args["a_mm"]), atol=1e-12)
