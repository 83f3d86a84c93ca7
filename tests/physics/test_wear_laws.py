"""Wear laws against the coefficients printed in seeds 000, 002, 003, 004."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wearcast.physics.wear_laws import (
    ArchardKTH,
    WearLaw,
    archard_basis,
    archard_kth_rate,
    krause_poll_rate,
    kth_zone,
    tau_max_rate,
    usfd_coefficient,
    usfd_rate,
)
from wearcast.physics.wear_measures import kth_archard_index

H_MPA = 300.0 * 9.80665


def test_seed_004_table_1_is_seed_000_map_means_doubled_and_divided_by_7():
    # Seed 004 Table 1 (reference/published/wear_law_coefficients.csv): 1.43e-4, 1.00e-3,
    # 1.43e-4, 1.00e-2. Seed 000 §III/§VI map means 5e-4, 35e-4, 5e-4 (and 350e-4 for the
    # 300e-4..400e-4 range), x2 for wheel+rail (seed 004 §2.1), /7 (seed 002 §2.2). Table 1
    # prints three significant digits, hence rel 5e-3.
    law = ArchardKTH.from_map_means()
    assert law.effective_coefficients == pytest.approx([1.43e-4, 1.00e-3, 1.43e-4, 1.00e-2],
                                                       rel=5e-3)


def test_kth_zone_boundaries():
    # Seed 000 §III: v < 0.2 m/s zone 1, 0.2-0.7 zone 2, > 0.7 zone 3, p > 0.8 H zone 4.
    v = np.array([0.19, 0.2, 0.7, 0.71, 0.1])
    p = np.array([1000.0, 1000.0, 1000.0, 1000.0, 0.81 * H_MPA])
    assert kth_zone(v, p).tolist() == [1, 2, 2, 3, 4]
    assert kth_zone(0.1, 0.79 * H_MPA).item() == 1


def test_archard_rate_agrees_with_wear_measures_index_and_contamination_divides():
    fn, vs, vr, p = np.array([5e4, 8e4]), np.array([0.1, 0.5]), 20.0, np.array([900.0, 1500.0])
    ref = kth_archard_index(fn, vs, vr, p).wear_rate_mm3_per_m
    assert archard_kth_rate(fn, vs, vr, p) == pytest.approx(ref, rel=1e-12)
    dirty = ArchardKTH(contamination_factor=7.0)
    assert archard_kth_rate(fn, vs, vr, p, dirty) == pytest.approx(ref / 7.0, rel=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(1e-6, 1e-1), min_size=4, max_size=4),
       st.floats(0.0, 2.0), st.floats(100.0, 3000.0))
def test_archard_is_linear_in_zone_coefficients(k, vs, p):
    law = ArchardKTH().with_coefficients(k)
    basis = archard_basis(6e4, vs, 25.0, p, law)
    assert basis.shape == (4,) and np.count_nonzero(basis) <= 1
    assert basis @ np.asarray(k) == pytest.approx(archard_kth_rate(6e4, vs, 25.0, p, law))


def test_krause_poll_regimes():
    # Seed 004 eq. (1): C = 9.871e-14 m^3/J up to 4 W/mm^2, 9.871e-13 above; P = Tg v.
    tg, area = np.array([100.0, 1000.0]), 100.0
    rate = krause_poll_rate(tg, 2.0, area)  # P/A = 2 and 20 W/mm^2
    assert rate == pytest.approx([9.871e-14 * 100 * 1e9, 9.871e-13 * 1000 * 1e9])


def test_usfd_branches_and_jump():
    # Seed 003 eq. (1): 5.3 Iw; 55.1; 61.9 Iw - 4778.7 (ug/(m mm^2)).
    assert usfd_coefficient([5.0, 50.0, 100.0]) == pytest.approx([26.5, 55.1, 1411.3])
    # The printed third branch starts at 61.9*77.2 - 4778.7 = -0.02: a drop to ~0.
    assert usfd_coefficient(77.3, "as_printed") == pytest.approx(61.9 * 77.3 - 4778.7)
    assert usfd_coefficient(77.3, "continuous") == pytest.approx(55.1)
    iw = np.linspace(0.0, 200.0, 20001)
    assert np.all(np.diff(usfd_coefficient(iw, "continuous")) >= -1e-9)
    assert np.any(np.diff(usfd_coefficient(iw, "as_printed")) < -50.0)
    # Continuous at the first bound to the printed rounding (5.3*10.4 = 55.12).
    assert usfd_coefficient(10.4 - 1e-9) == pytest.approx(55.1, abs=0.03)


def test_usfd_rate_converts_mass_to_volume():
    # Iw = 50 N/mm^2 on 100 mm^2: 55.1 ug/(m mm^2) * 100 mm^2 / 7850 ug/mm^3.
    assert usfd_rate(5000.0, 100.0) == pytest.approx(55.1 * 100 / 7850.0)


def test_tau_max_rate_threshold():
    rate = tau_max_rate([100.0, 300.0], 50.0, 1e-6, threshold_mpa=200.0)
    assert rate == pytest.approx([0.0, 1e-6 * 100.0 * 50.0])


def test_bad_inputs_are_refused():
    with pytest.raises(ValueError, match="wear law"):
        WearLaw(name="nope")
    with pytest.raises(ValueError, match="coefficients"):
        ArchardKTH(coefficients=(1.0, 2.0, 3.0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="jump"):
        usfd_coefficient(10.0, "smooth")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="rolling_speed"):
        archard_basis(1.0, 0.1, 0.0, 10.0)
