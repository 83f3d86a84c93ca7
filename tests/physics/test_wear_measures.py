"""Wear measures: T-gamma, tau_max, Tg/A, KTH/Archard and Krause-Poll indices and regimes."""

import numpy as np
import pytest

from wearcast.physics.contact.fastsim import fastsim
from wearcast.physics.wear_measures import (
    HB_TO_MPA,
    contact_wear_measures,
    krause_poll_index,
    kth_archard_index,
    kth_zone,
    rigid_sliding_velocity_m_s,
    t_gamma,
    t_gamma_per_area,
    tau_max,
    tau_max_p0_over_mu_eff,
)


def test_t_gamma_hand_computed():
    # |1000*0.002| + |-2000*(-0.001)| + |5000 N mm * 1e-4 1/mm| = 2 + 2 + 0.5 N
    assert t_gamma(1000.0, -2000.0, 5000.0, 0.002, -0.001, 1e-4) == pytest.approx(4.5)
    assert t_gamma_per_area(4.5, 3.0, 2.0) == pytest.approx(4.5 / (np.pi * 6.0))


def test_tau_max_is_bounded_by_mu_p_and_reaches_it_in_full_slip():
    r = fastsim([0.0, 0.05], [0.0, 0.0], [0.0, 0.0], 6.0, 4.0, 60_000.0, 0.3)
    tm = tau_max(r)
    assert tm[0] == 0.0  # free rolling: no traction
    peak = 2 * 60_000.0 / (np.pi * 24.0)  # parabolic bound peak
    assert tm[1] <= 0.3 * peak + 1e-9
    assert tm[1] == pytest.approx(0.3 * peak, rel=2e-3)  # full slip sits on the bound


def test_p0_over_mu_eff_variant_and_its_divergence():
    # mu_eff = 500/1000 = 0.5 -> 1000 / 0.5
    assert tau_max_p0_over_mu_eff(1000.0, 300.0, 400.0, 1000.0) == pytest.approx(2000.0)
    small = tau_max_p0_over_mu_eff(1000.0, [1e-3, 1e-6, 0.0], 0.0, 1000.0)
    assert small[0] < small[1] and np.isinf(small[2])


def test_contact_wear_measures_bundle():
    r = fastsim(1e-3, -5e-4, 1e-4, 6.0, 4.0, 60_000.0, 0.3)
    m = contact_wear_measures(r, 1e-3, -5e-4, 1e-4, 6.0, 4.0)
    assert m.t_gamma_n == pytest.approx(abs(r.fx_n * 1e-3) + abs(r.fy_n * 5e-4)
                                        + abs(r.mz_nmm * 1e-4))
    assert m.tau_max_mpa == pytest.approx(np.max(np.hypot(r.px_mpa, r.py_mpa)))


def test_kth_zones_and_boundaries():
    # seed 000 §III: <0.2 m/s zone I, 0.2-0.7 zone II, >0.7 zone III, p > 0.8 H zone IV
    h = 300 * HB_TO_MPA
    v = np.array([0.0, 0.1999, 0.2, 0.7, 0.7001, 5.0, 0.1])
    p = np.array([100, 100, 100, 100, 100, 100, 0.8 * h + 1])
    assert kth_zone(v, p).tolist() == [1, 1, 2, 2, 3, 3, 4]
    assert kth_zone(0.1, 0.8 * h).item() == 1  # exactly 0.8 H is not yet zone IV


def test_kth_archard_index_with_seed_004_coefficients():
    idx = kth_archard_index(10_000.0, [0.1, 0.5, 1.0, 0.1], 20.0, [500, 500, 500, 3000])
    # seed 004 Table 1: mild 1.43e-4, severe 1.00e-3, mild 1.43e-4, seizure 1.00e-2
    assert idx.coefficient.tolist() == [1.43e-4, 1.0e-3, 1.43e-4, 1.0e-2]
    assert idx.regime.tolist() == ["mild", "severe", "mild", "catastrophic"]
    # hand: k N / H * (v_s / v_roll) * 1000 mm/m = 1e-3 * 1e4 / 2942 * 0.025 * 1000
    assert idx.wear_rate_mm3_per_m[1] == pytest.approx(1e-3 * 1e4 / (300 * HB_TO_MPA) * 25.0)


def test_rigid_sliding_velocity():
    assert rigid_sliding_velocity_m_s(20.0, 3e-3, 4e-3) == pytest.approx(0.1)


def test_krause_poll_regime_boundary_and_rates():
    # P/A = Tg v / A: 400 N * 10 m/s / 1000 mm^2 = 4 W/mm^2 is still mild (seed 004 eq. 1: <=)
    kp = krause_poll_index([400.0, 400.4, 10.0], 10.0, 1000.0)
    assert kp.power_density_w_per_mm2 == pytest.approx([4.0, 4.004, 0.1])
    assert kp.regime.tolist() == ["mild", "severe", "mild"]
    assert kp.coefficient_m3_per_j.tolist() == [9.871e-14, 9.871e-13, 9.871e-14]
    # worn volume per metre rolled: C * Tg * 1 m = 9.871e-14 * 400 m^3 = 3.9484e-2 mm^3
    assert kp.wear_rate_mm3_per_m[0] == pytest.approx(3.9484e-2)
    # the severe rate jumps tenfold across the boundary
    assert kp.wear_rate_mm3_per_m[1] / kp.wear_rate_mm3_per_m[0] == pytest.approx(10.01)
