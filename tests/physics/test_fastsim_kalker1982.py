"""Kalker's 1982 FASTSIM paper cases (normalised form), and the map onto our ``fastsim``."""

import numpy as np
import pytest

from wearcast.physics.contact.fastsim_kalker1982 import (
    fastsim_normalised,
    fastsim_normalised_on_grid,
    kalker_strips,
    normalised_to_physical,
    physical_to_normalised,
)

# Kalker, VSD 11 (1982), test cases as held in the public C++ port's tests
# (criogenox/C_Normal_Tangential_Railway_Contact, tang_fastsim/tests/test_paper.cpp), all with
# mx = my = 5: (ux, uy, fix, fiy), tol -> (Tx, Ty). Cases 1 and 3 are
# the tol variants of cases 0 and 2. Tx is printed with the opposite sign
# to ours (the port flips it too); Ty has ours.
PAPER = [
    ((0.0, -2.0, 2.0, 4.0), 3.0, (0.0, 0.1843)),
    ((0.0, -2.0, 2.0, 4.0), 0.09, (0.0, 0.1850)),
    ((1.0, -2.0, 2.0, 4.0), 0.09, (0.5720, 0.1838)),
    ((1.0, -2.0, 2.0, 4.0), 3.0, (0.5684, 0.1857)),
    ((1.0, -2.0, 2.0, 1.0), 0.09, (0.4530, 0.8299)),
]


@pytest.mark.parametrize(("u", "tol", "expected"), PAPER)
def test_reproduces_kalker_1982_printed_values(u, tol, expected):
    # Same discretisation as Kalker's routine, which is deterministic: agreement to the printed
    # 4 decimals, i.e. within half a unit of the last digit (measured: <= 4.9e-5).
    r = fastsim_normalised(*u, mx=5, my=5, tol=tol)
    assert -r.tx == pytest.approx(expected[0], abs=5e-5)
    assert r.ty == pytest.approx(expected[1], abs=5e-5)


def test_strip_layout_follows_the_sign_change_line():
    # ux/fix = 0.5: the upper half-disc is cut on y' in [0.5, 1] (2 strips of 0.25), the lower
    # on [-1, 0.5] (4 strips of 0.375); with tol = 3 no bisection; widths cover [-1, 1].
    y, dy, adaptive = kalker_strips(1.0, -2.0, 2.0, 4.0, 5, 3.0)
    assert adaptive
    assert np.sum(dy) == pytest.approx(2.0)
    assert np.any(np.isclose(y + dy / 2, 0.5)) and np.any(np.isclose(y - dy / 2, 0.5))
    assert sorted(np.round(dy, 12)) == [0.25, 0.25, 0.375, 0.375, 0.375, 0.375]
    # tol = 0.09 bisects the strips touching y' = 0.5 until their half-width is <= tol
    y, dy, _ = kalker_strips(1.0, -2.0, 2.0, 4.0, 5, 0.09)
    assert np.sum(dy) == pytest.approx(2.0)
    near = np.abs(y - 0.5) == np.min(np.abs(y - 0.5))
    assert np.all(dy[near] / 2 <= 0.09)
    # large creepage (|uy| > |fiy|): equal strips, 2 (my // 2 + 1) of them
    y, dy, adaptive = kalker_strips(1.0, -2.0, 2.0, 1.0, 5, 0.09)
    assert not adaptive and y.size == 6 and np.allclose(dy, 1 / 3)


@pytest.mark.parametrize("u", [(0.0, -2.0, 2.0, 4.0), (1.0, -2.0, 2.0, 4.0), (1.0, -2.0, 2.0, 1.0),
                               (0.3, 0.5, 0.0, 0.0), (-0.4, 0.2, 1.0, 0.5)])
def test_normalisation_maps_onto_our_fastsim(u):
    # Kalker's strips and CONTACT's grid (our fastsim, mapped by normalised_to_physical) are
    # different discretisations of the same problem; both are first order in the step, so
    # Richardson-extrapolate 200 -> 400 and compare the limits. Measured agreement <= 5e-5;
    # 5e-4 allows for the remaining second-order error. A wrong normalisation (e.g. fiy/fix
    # not a/b, or p0 not parabolic) moves the limit by far more (>1e-2).
    def limit(f):
        coarse, fine = np.array(f(200)), np.array(f(400))
        return 2 * fine - coarse

    k = limit(lambda n: (lambda r: (r.tx, r.ty))(fastsim_normalised(*u, mx=n, my=n, tol=1e-4)))
    g = limit(lambda n: fastsim_normalised_on_grid(*u, n_x=n, n_y=n))
    assert k == pytest.approx(g, abs=5e-4)


def test_physical_and_normalised_inputs_round_trip():
    u = (0.7, -1.3, 2.0, 3.0)
    p = normalised_to_physical(*u, b_mm=4.0)
    assert p.a_mm / p.b_mm == pytest.approx(1.5)
    back = physical_to_normalised(p.xi, p.eta, p.phi_per_mm, p.a_mm, p.b_mm, p.normal_force_n,
                                  p.mu, p.flexibilities_mm_per_mpa)
    assert np.array(back) == pytest.approx(np.array(u), rel=1e-12)
    with pytest.raises(ValueError):
        normalised_to_physical(0.0, 0.0, 0.0, 1.0)


def test_point_and_mirror_symmetry():
    u = np.array([0.4, -0.9, 1.5, 2.5])
    r = fastsim_normalised(*u, mx=7, my=9, tol=0.05)
    # all creepages reversed: all forces reversed (exactly, same strips)
    neg = fastsim_normalised(*(-u), mx=7, my=9, tol=0.05)
    assert (neg.tx, neg.ty) == pytest.approx((-r.tx, -r.ty), abs=1e-14)
    # mirror y -> -y: (ux, uy, fix, fiy) -> (ux, -uy, -fix, -fiy) gives (Tx, -Ty)
    mir = fastsim_normalised(u[0], -u[1], -u[2], -u[3], mx=7, my=9, tol=0.05)
    assert (mir.tx, mir.ty) == pytest.approx((r.tx, -r.ty), abs=1e-14)


def test_linear_limit_and_full_slip():
    # Tiny creepage, full adhesion: Px = -ux (x0 - x) on the disc, so
    # Tx = (2/pi) * (-ux) * int 2 (1 - y^2) dy = -16 ux/(3 pi) (Kalker's linear simplified theory).
    ux = 1e-4
    r = fastsim_normalised(ux, 0.0, 0.0, 0.0, mx=50, my=200)
    assert r.slip_fraction == 0.0
    assert r.tx == pytest.approx(-16 * ux / (3 * np.pi), rel=1e-4)
    assert r.ty == 0.0
    # Huge creepage: every point on the bound, |T| -> 1 (discrete integral of 1 - x^2 - y^2).
    r = fastsim_normalised(50.0, 50.0, 0.0, 0.0, mx=200, my=200)
    assert r.slip_fraction == 1.0
    assert np.hypot(r.tx, r.ty) == pytest.approx(1.0, abs=2e-4)
    assert r.tx == pytest.approx(r.ty) and r.tx < 0


def test_rejects_bad_discretisation():
    with pytest.raises(ValueError):
        fastsim_normalised(0.0, 0.0, 0.0, 0.0, mx=0)
    with pytest.raises(ValueError):
        fastsim_normalised(0.0, 0.0, 0.0, 0.0, my=2.5)
    with pytest.raises(ValueError):
        fastsim_normalised(0.0, 0.0, 1.0, 1.0, tol=0.0)
