"""Hertz contact: closed forms, symmetry, scaling, load sharing, CONTACT's Hertz numbers."""

import numpy as np
import pytest

from wearcast.physics.contact.hertz import (
    effective_modulus_mpa,
    hertz_contact,
    normal_force_from_approach,
    split_load_between_patches,
)


def test_circular_contact_matches_closed_form():
    # A = B = 1/(2R): a = b = (3 F R / (4 E*))^(1/3), delta = a^2 / R (Johnson eq. 4.22-4.23).
    f, r = 50_000.0, 300.0
    patch = hertz_contact(f, 1 / (2 * r), 1 / (2 * r))
    e_star = effective_modulus_mpa()
    a = (3 * f * r / (4 * e_star)) ** (1 / 3)
    assert patch.a_mm == pytest.approx(a, rel=1e-9)
    assert patch.b_mm == pytest.approx(a, rel=1e-9)
    assert patch.approach_mm == pytest.approx(a**2 / r, rel=1e-9)
    assert patch.p0_mpa == pytest.approx(3 * f / (2 * np.pi * a**2), rel=1e-12)


def test_contact_reference_case_fastsim_inp():
    # CONTACT fastsim.ref_out: curvatures A1 = 0.8464e-3, B1 = 0.2406e-2 1/mm, Fn = 82 kN,
    # G = 82 GPa, nu = 0.28 -> AA = 8, BB = 4 mm, approach 9.266e-2 mm, pmax 1223 MPa.
    # The curvatures are printed to 4 digits, so the semi-axes agree to ~1e-4 relative.
    e = 2 * 82_000 * 1.28
    patch = hertz_contact(82_000, 0.8464e-3, 0.2406e-2, young_mpa=e, poisson=0.28)
    assert patch.a_mm == pytest.approx(8.0, rel=2e-4)
    assert patch.b_mm == pytest.approx(4.0, rel=2e-4)
    assert patch.approach_mm == pytest.approx(9.266e-2, rel=5e-4)
    assert patch.p0_mpa == pytest.approx(1223.0, abs=1.0)


@pytest.mark.parametrize("ratio", [1.0001, 1.3, 3.0, 17.0, 400.0])
def test_swapping_curvatures_swaps_axes_and_p0_identity(ratio):
    f, ca = 30_000.0, 1e-3
    p1 = hertz_contact(f, ca, ca * ratio)
    p2 = hertz_contact(f, ca * ratio, ca)
    assert p1.a_mm == pytest.approx(p2.b_mm, rel=1e-10)
    assert p1.b_mm == pytest.approx(p2.a_mm, rel=1e-10)
    assert p1.a_mm > p1.b_mm  # the smaller curvature gives the longer axis
    assert p1.p0_mpa == pytest.approx(3 * f / (2 * np.pi * p1.a_mm * p1.b_mm), rel=1e-12)
    assert p1.approach_mm == pytest.approx(p2.approach_mm, rel=1e-10)


def test_force_scales_with_approach_to_the_power_1_5():
    f = np.array([1e3, 1e4, 1e5])
    patch = hertz_contact(f, 2e-4, 3e-3)
    ratio = f / patch.approach_mm**1.5
    assert np.allclose(ratio, ratio[0], rtol=1e-9)
    assert normal_force_from_approach(patch.approach_mm, 2e-4, 3e-3) == pytest.approx(f, rel=1e-8)
    assert normal_force_from_approach(-0.01, 2e-4, 3e-3) == 0.0


def test_split_load_equilibrium_and_common_penetration():
    ca = np.array([1e-3, 4e-3])
    cb = np.array([2e-3, 9e-3])
    forces = split_load_between_patches(20_000.0, ca, cb)
    assert forces.sum() == pytest.approx(20_000.0, rel=1e-9)
    d = [hertz_contact(f, a, b).approach_mm for f, a, b in zip(forces, ca, cb, strict=True)]
    assert d[0] == pytest.approx(d[1], rel=1e-8)
    # a gap larger than the penetration leaves the second patch unloaded
    forces = split_load_between_patches(20_000.0, ca, cb, gap_mm=[0.0, 1.0])
    assert forces[1] == 0.0 and forces[0] == pytest.approx(20_000.0, rel=1e-9)
    # inclined patch: the load is carried by the normal-force components
    forces = split_load_between_patches(10_000.0, ca, cb, load_cosine=[1.0, 0.5])
    assert forces[0] + 0.5 * forces[1] == pytest.approx(10_000.0, rel=1e-9)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="curvatures"):
        hertz_contact(1e3, -1e-3, 1e-3)
    with pytest.raises(ValueError, match="normal_force_n"):
        hertz_contact(-1.0, 1e-3, 1e-3)
