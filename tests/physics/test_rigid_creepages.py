"""Rigid-body creepages with the curve's terms (``contact.creepages``)."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.contact.creepages import rigid_creepages


@pytest.mark.parametrize("side", ["left", "right"])
def test_curve_terms_match_the_small_angle_creepages(side):
    # A wheel of radius r touching at its lowest point, lateral position y_c = s 750 mm, contact
    # angle delta = 0, no yaw or roll, axle turning at (1 + e) V / r0 on a curve kappa:
    # xi = (1 + e) r / r0 - (1 - kappa y) (y the track y of the contact, + left),
    # eta = 0, phi = -s kappa (module docstring; curving's table formulas with their signs
    # negated, CONTACT's convention).
    s = 1.0 if side == "left" else -1.0
    r0, r, e, kappa = 460.0, 462.0, 2e-3, 1.0 / 300.0
    point = np.array([[0.0], [s * 750.0], [r0 - r]])
    xi, eta, phi = rigid_creepages(side, 20.0, (1 + e) * 20_000.0 / r0, 0.0, 0.0, 0.0, 0.0, r0,
                                   point, [0.0], track_curvature_per_m=kappa)
    assert xi[0] == pytest.approx((1 + e) * r / r0 - (1 - kappa * s * 750.0 / 1000.0),
                                  rel=1e-9)
    assert eta[0] == pytest.approx(0.0, abs=1e-12)
    assert phi[0] == pytest.approx(-s * kappa / 1000.0, rel=1e-9)
    # the curve terms vanish on tangent track, and the creepages do not depend on V
    xi0, _, phi0 = rigid_creepages(side, 20.0, (1 + e) * 20_000.0 / r0, 0.0, 0.0, 0.0, 0.0, r0,
                                   point, [0.0])
    assert xi0[0] == pytest.approx((1 + e) * r / r0 - 1, rel=1e-9)
    assert phi0[0] == pytest.approx(0.0, abs=1e-15)
    xi2, _, phi2 = rigid_creepages(side, 40.0, (1 + e) * 40_000.0 / r0, 0.0, 0.0, 0.0, 0.0, r0,
                                   point, [0.0], track_curvature_per_m=kappa)
    assert (xi2[0], phi2[0]) == pytest.approx((xi[0], phi[0]), rel=1e-12)
