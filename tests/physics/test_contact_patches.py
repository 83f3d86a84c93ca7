"""Contact patches merged or split by the interpenetration region (CONTACT's rules), the
contact locus with prescribed roll, and the per-wheel normal contact (methods, equilibrium,
symmetry)."""

import numpy as np
import pytest

from wearcast.physics.contact.geometry import contact_table, s1002_60e1
from wearcast.physics.contact.locus import NoContactError, wheel_locus
from wearcast.physics.contact.normal_contact import wheel_normal_contact
from wearcast.physics.contact.patches import patch_regions


@pytest.fixture(scope="module")
def wheelset():
    return s1002_60e1()


def test_prescribed_roll_equal_to_the_solved_one_gives_the_same_locus(wheelset):
    shifts = np.array([0.0, 3.0, 7.0])
    solved = wheel_locus(wheelset, shifts, "left")
    table = contact_table(wheelset, shifts)
    np.testing.assert_allclose(solved.roll_rad, table.roll_rad)
    given = wheel_locus(wheelset, shifts, "left", roll_rad=table.roll_rad)
    np.testing.assert_allclose(given.gap_mm, solved.gap_mm, atol=1e-12)
    # the deepest locus point is the geometry's primary contact
    i = np.argmin(given.gap_mm, axis=1)
    np.testing.assert_allclose(given.y_wheel_mm[i], table.left.primary.y_wheel_mm, atol=0.11)
    # on the tread a larger roll lifts the left wheel (by ~750 mm x 2 mrad): the axle has to
    # come down ~1.5 mm for that wheel to touch again (on the flange the roll also moves the
    # flange sideways, so no such rule holds there)
    tilted = wheel_locus(wheelset, shifts, "left", roll_rad=table.roll_rad + 0.002)
    drop = given.height_mm[:2] - tilted.height_mm[:2]
    np.testing.assert_allclose(drop, 1.5, atol=0.15)  # measured 1.43, 1.38


def test_a_wheel_off_its_rail_is_a_typed_error(wheelset):
    with pytest.raises(NoContactError) as info:
        wheel_locus(wheelset, [400.0], "left", roll_rad=0.0)
    assert isinstance(info.value, ValueError)
    assert str(info.value).startswith(f"{info.value.field}: ")


def test_tread_and_flange_root_regions_merge_and_split_by_distance(wheelset):
    # Manchester case 11 (5.0 mm, yaw 12 mrad): two interpenetration regions (tread,
    # flange root) a few mm apart -> one patch, as CONTACT; with D_SEP = 1 mm they stay two
    locus = wheel_locus(wheelset, [5.0], "left", yaw_rad=0.012, roll_rad=0.0003554)
    approach = 0.03
    merged = patch_regions(locus, 0, approach)
    assert len(merged) == 1 and merged[0].n_regions == 2
    split = patch_regions(locus, 0, approach, dist_sep_mm=1.0)
    assert len(split) == 2 and all(p.n_regions == 1 for p in split)
    # the merged reference is the weight-average of the two, between them
    w = np.array([p.weight for p in split])
    y = np.array([p.y_track_mm for p in split])
    assert merged[0].y_track_mm == pytest.approx(np.sum(w * y) / w.sum(), abs=1e-9)
    assert merged[0].weight == pytest.approx(w.sum(), rel=1e-12)
    assert min(y) < merged[0].y_track_mm < max(y)
    # field side first (CONTACT's order): the tread patch before the root patch
    assert split[0].y_wheel_mm > split[1].y_wheel_mm
    # below the first touch: no patch
    assert patch_regions(locus, 0, -1e-3) == []


def test_two_point_contact_far_apart_stays_two_patches_sharing_the_load():
    # S1002 on 1:20 rails at 6 mm: tread and flange regions > 8 mm apart -> two patches
    wt = s1002_60e1(1.0 / 20.0)
    locus = wheel_locus(wt, [6.0], "left")
    result = wheel_normal_contact(locus, 10_000.0, method="auto")[0]
    assert len(result.patches) == 2
    # vertical equilibrium of the normal forces (no creep forces here)
    assert result.vertical_force_n == pytest.approx(10_000.0, rel=2e-4)
    assert all(p.normal_force_n > 0 for p in result.patches)


@pytest.mark.parametrize(("inclination", "shift"), [(1 / 40, 0.0), (1 / 20, 2.0),
                                                    (1 / 40, 8.0)])
def test_production_method_close_to_the_bem(inclination, shift):
    # acceptance (issue 11): position 0.5 mm, F_n 5 %, peak pressure 10 %; measured on the
    # conformal-tread set p95 0.17 mm / 0.00 % / 2.8 % (benchmarks/normal_contact_accuracy.py)
    locus = wheel_locus(s1002_60e1(inclination), [shift], "left")
    fast = wheel_normal_contact(locus, 10_000.0, method="auto")[0].patches
    ref = wheel_normal_contact(locus, 10_000.0, method="bem")[0].patches
    assert len(fast) == len(ref) == 1
    assert fast[0].centre_y_wheel_mm == pytest.approx(ref[0].centre_y_wheel_mm, abs=0.2)
    assert fast[0].normal_force_n == pytest.approx(ref[0].normal_force_n, rel=0.01)
    assert fast[0].peak_pressure_mpa == pytest.approx(ref[0].peak_pressure_mpa, rel=0.05)
    # the centred 1:40 tread is conformal (not Hertz); the flange at 8 mm is elliptic
    if shift == 0.0:
        assert fast[0].method == "bem-coarse"
    if shift == 8.0:
        assert fast[0].method == "hertz"


def test_mirror_symmetry_of_the_two_wheels(wheelset):
    left = wheel_normal_contact(wheel_locus(wheelset, [2.5], "left", yaw_rad=0.004), 9_000.0,
                                method="bem-coarse")[0]
    right = wheel_normal_contact(wheel_locus(wheelset, [-2.5], "right", yaw_rad=-0.004),
                                 9_000.0, method="bem-coarse")[0]
    assert left.approach_mm == pytest.approx(right.approach_mm, rel=1e-9)
    a, b = left.patches[0], right.patches[0]
    assert a.centre_y_wheel_mm == pytest.approx(b.centre_y_wheel_mm, abs=1e-9)
    assert a.peak_pressure_mpa == pytest.approx(b.peak_pressure_mpa, rel=1e-9)
    assert a.region.contact_angle_rad == pytest.approx(b.region.contact_angle_rad, abs=1e-12)


def test_more_load_more_approach_and_larger_patch(wheelset):
    locus = wheel_locus(wheelset, [3.0, 3.0], "left")
    light, heavy = wheel_normal_contact(locus, np.array([10_000.0, 60_000.0]),
                                        method="bem-coarse")
    assert heavy.approach_mm > light.approach_mm
    assert heavy.patches[0].area_mm2 > light.patches[0].area_mm2
    assert heavy.patches[0].peak_pressure_mpa > light.patches[0].peak_pressure_mpa
    # sub-Hertzian growth of the peak pressure (Hertz: (60/10)^(1/3) = 1.82)
    ratio = heavy.patches[0].peak_pressure_mpa / light.patches[0].peak_pressure_mpa
    assert 1.3 < ratio < 2.0


def test_production_method_on_a_measured_wheel(reference_dir):
    # a raw MiniProf wheel (worn hollow tread) on 60E1 1:40: auto vs the fine BEM, 10 kN
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    from normal_contact_accuracy import compare, measured_wheels

    from wearcast.physics.contact.geometry import WheelsetTrack
    from wearcast.physics.profiles.measured import rail_curve

    wheel = measured_wheels(reference_dir)["whl_left_iter795"]
    table = compare(WheelsetTrack(wheel=wheel, rail=rail_curve("60E1")),
                    np.array([-2.0, 2.0]), 10_000.0, "auto")
    assert np.all(table.patches == table.patches_bem)
    assert np.all(table.d_pos_mm.abs() < 0.5)
    assert np.all(table.d_fn_rel.abs() < 0.05)
    assert np.all(table.d_pmax_rel.abs() < 0.10)


def test_pose_locus_inherits_the_derived_arrays_of_its_rows(wheelset):
    """The coupling's one-pose loci take the arc step, track widths and sqrt(A) from the whole
    locus; they must be what the pose's own locus computes, and the patches the same."""
    from wearcast.physics.contact.locus import WheelLocus
    from wearcast.physics.contact.wheel_rail import _row_locus

    locus = wheel_locus(wheelset, [-3.0, 2.0, 7.5], "left", yaw_rad=0.004)
    for row in range(3):
        handed = _row_locus(locus, row)
        fresh = WheelLocus(**{f: getattr(handed, f) for f in WheelLocus.__dataclass_fields__})
        assert handed.arc_step_mm == fresh.arc_step_mm
        np.testing.assert_array_equal(handed.track_width_mm, fresh.track_width_mm)
        np.testing.assert_array_equal(handed.sqrt_curvature_a, fresh.sqrt_curvature_a)
        for approach in (0.01, 0.08):
            a, b = patch_regions(handed, 0, approach), patch_regions(locus, row, approach)
            assert [r.y_track_mm for r in a] == [r.y_track_mm for r in b]
            assert [r.weight for r in a] == [r.weight for r in b]
