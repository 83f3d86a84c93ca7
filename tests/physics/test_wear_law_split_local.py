"""Wheel/rail attribution of each law's volume and the local application of every law."""

import numpy as np
import pytest

from wearcast.physics.contact.fastsim import fastsim
from wearcast.physics.wear_distribution import local_archard_depth, local_rate_depth
from wearcast.physics.wear_laws import (
    STEEL_DENSITY_UG_PER_MM3,
    USFD_MILD_SLOPE,
    ArchardKTH,
    WearLaw,
    element_depth_rate_mm_per_m,
    wheel_rail_split,
)

Y = np.linspace(-70.0, 60.0, 651)
H = 0.2
R_MM = 460.0


def test_split_follows_each_laws_definition():
    # Seed 004 §2.1: KTH's map is for the wheel only; seed 004 Table 1 doubles it for wheel and
    # rail together, so each body loses half of a volume computed with Table 1.
    assert wheel_rail_split(WearLaw("archard_kth")) == (0.5, 0.5)
    assert ArchardKTH.from_map_means().coefficient_scope == "wheel_and_rail"
    per_body = ArchardKTH.from_map_means(wheel_and_rail_factor=1.0)
    assert per_body.coefficient_scope == "per_body"
    assert wheel_rail_split(WearLaw("archard_kth", per_body)) == (1.0, 1.0)
    # Seed 003 §4.2: K_w is the same for the wheel and for the rail.
    assert wheel_rail_split(WearLaw("usfd")) == (1.0, 1.0)
    with pytest.raises(ValueError, match="coefficient_scope"):
        ArchardKTH(coefficient_scope="both")


def _patch(xi=0.02, eta=0.01, phi=0.0):
    return fastsim(np.array([xi]), np.array([eta]), np.array([phi]), np.array([6.0]),
                   np.array([4.0]), np.array([60_000.0]), 0.3, n_x=30, n_y=30)


def _volume_per_m(depth_normal: np.ndarray, angle: float = 0.0) -> float:
    """Volume per metre rolled of a normal depth on the grid [mm^3/m]."""
    return float(np.sum(depth_normal / np.cos(angle)) * H * 2.0 * np.pi * R_MM)


@pytest.mark.parametrize("angle", [0.0, 0.6])
def test_local_rate_depth_conserves_the_element_volume(angle):
    fs = _patch()
    rate = np.where(fs.in_contact, 1e-4, 0.0)                   # mm/m while in contact
    depth = local_rate_depth(fs, rate, np.array([5.0]), np.array([R_MM]), np.array([angle]), Y)
    area = float(np.sum(np.where(fs.in_contact, 1.0, 0.0)) * fs.dx_mm[0] * fs.dy_mm[0])
    assert _volume_per_m(depth[0], angle) == pytest.approx(1e-4 * area, rel=1e-9)
    assert np.all(depth >= 0)


def test_local_usfd_in_the_mild_regime_matches_the_global_law():
    # Mild USFD is linear in I = |p_t| s: sum K_w(I) dA / rho = 5.3 T gamma / rho, the global
    # law's volume (T gamma from the same FASTSIM field, so the check is exact to the grid).
    fs = _patch(xi=0.0005, eta=0.0003)
    law = WearLaw("usfd")
    slip = np.hypot(fs.sx, fs.sy)
    index = fs.shear_traction_mpa * slip
    assert index.max() < 10.4                                     # mild regime throughout
    rate = element_depth_rate_mm_per_m(law, fs.shear_traction_mpa, slip, fs.pn_mpa, 20.0)
    depth = local_rate_depth(fs, rate, np.array([0.0]), np.array([R_MM]), np.array([0.0]), Y)
    t_gamma = float(np.sum(index) * fs.dx_mm[0] * fs.dy_mm[0])
    assert t_gamma > 0
    assert _volume_per_m(depth[0]) == pytest.approx(
        USFD_MILD_SLOPE * t_gamma / STEEL_DENSITY_UG_PER_MM3, rel=1e-9)


def test_element_archard_rate_equals_the_zone_basis():
    fs = _patch()
    law = WearLaw("archard_kth")
    slip = np.hypot(fs.sx, fs.sy)
    rate = element_depth_rate_mm_per_m(law, fs.shear_traction_mpa, slip, fs.pn_mpa, 20.0)
    general = local_rate_depth(fs, rate, np.array([2.0]), np.array([R_MM]), np.array([0.1]), Y)
    basis = local_archard_depth(fs, 20.0, np.array([2.0]), np.array([R_MM]),
                                np.array([0.1]), Y, law.archard)
    assert general[0] == pytest.approx(basis[0].T @ law.archard.effective_coefficients,
                                       rel=1e-9, abs=1e-18)


def test_element_rates_vanish_in_adhesion_and_grow_with_slip():
    law_names = ("usfd", "krause_poll", "tau_max", "archard_kth")
    for name in law_names:
        rate = element_depth_rate_mm_per_m(WearLaw(name), np.array([100.0, 100.0, 100.0]),
                                           np.array([0.0, 0.001, 0.01]), 500.0, 20.0)
        assert rate[0] == 0.0, name
        assert 0 < rate[1] <= rate[2], name
