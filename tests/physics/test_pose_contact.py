"""The contact API (``contact.pose_contact``): properties and CONTACT's Manchester A-2.2."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.contact.geometry import s1002_60e1
from wearcast.physics.contact.locus import NoContactError
from wearcast.physics.contact.pose_contact import Pose, contact_at_poses
from wearcast.physics.contact.track_profiles import wheel_curve_from_height, wheelset_track
from wearcast.physics.profiles.s1002 import s1002_height_mm


def test_vertical_equilibrium_and_mirror_symmetry():
    # the patches carry the prescribed vertical load (sum Fn cos + Fs sin = W, the pipeline's
    # rtol 1e-4 W); the right wheel at -y is the mirror image of the left wheel at +y
    track = s1002_60e1()
    poses = [Pose(2.0, 0.0, None, 10_000.0), Pose(6.5, 0.002, None, 60_000.0)]
    left = contact_at_poses(track, "left", poses)
    mirrored = [Pose(-p.shift_mm, -p.yaw_rad, None, p.wheel_load_n) for p in poses]
    right = contact_at_poses(track, "right", mirrored)
    for lc, rc, pose in zip(left, right, poses, strict=True):
        assert lc.loaded.vertical_force_n == pytest.approx(pose.wheel_load_n, rel=2e-4)
        a, b = lc.to_dict(), rc.to_dict()
        assert a["n_patches"] == b["n_patches"]
        assert a["roll_rad"] == pytest.approx(-b["roll_rad"], abs=1e-9)
        for pa, pb in zip(a["patches"], b["patches"], strict=True):
            assert pa["y_wheel_mm"] == pytest.approx(pb["y_wheel_mm"], abs=1e-6)
            assert pa["contact_angle_rad"] == pytest.approx(pb["contact_angle_rad"], abs=1e-9)
            assert pa["normal_force_n"] == pytest.approx(pb["normal_force_n"], rel=1e-6)


def test_prescribed_roll_equal_to_the_solved_one_gives_the_same_contact():
    track = s1002_60e1()
    solved = contact_at_poses(track, "left", [Pose(3.0)])[0]
    given = contact_at_poses(track, "left", [Pose(3.0, 0.0, solved.roll_rad)])[0]
    assert not given.roll_solved and solved.roll_solved
    d_s, d_g = solved.to_dict(), given.to_dict()
    assert d_g["n_patches"] == d_s["n_patches"]
    for ps, pg in zip(d_s["patches"], d_g["patches"], strict=True):
        assert pg["y_wheel_mm"] == pytest.approx(ps["y_wheel_mm"], abs=1e-3)
        assert pg["normal_force_n"] == pytest.approx(ps["normal_force_n"], rel=1e-3)


def test_beyond_flange_contact_the_point_climbs_towards_the_tip_with_the_roll():
    # with the roll solved the flanging wheel climbs its rail as the shift grows: the roll grows
    # and the contact runs from the root (6 mm) over the 60-70 deg flank towards the rounded
    # flange tip (its angle then falls again); the track built from S1002's height function
    # (``track_profiles``) gives the contact of the analytic curve within 0.15 mm; mixed
    # solved and prescribed poses come back in the order given
    analytic = s1002_60e1()
    sampled = wheelset_track(wheel_curve_from_height(s1002_height_mm, (-60.0, 60.0)), "60E1",
                             1.0 / 40.0, 460.0)
    shifts = [6.0, 7.0, 8.0, 9.0, 10.0]
    found = contact_at_poses(analytic, "left", [Pose(s) for s in shifts])
    again = contact_at_poses(sampled, "left", [Pose(s) for s in shifts])
    rolls = [c.roll_rad for c in found]
    y = [c.loaded.dominant.normal.centre_y_wheel_mm for c in found]
    assert np.all(np.diff(rolls) > 0)
    assert np.all(np.diff(y) < 0)
    assert abs(found[0].loaded.dominant.contact_angle_rad) < np.radians(35.0)
    assert abs(found[1].loaded.dominant.contact_angle_rad) > np.radians(55.0)
    for c, d in zip(found, again, strict=True):
        assert d.loaded.dominant.normal.centre_y_wheel_mm == pytest.approx(
            c.loaded.dominant.normal.centre_y_wheel_mm, abs=0.15)
    mixed = contact_at_poses(analytic, "left", [Pose(9.0), Pose(7.0, 0.0, rolls[1]), Pose(8.0)])
    assert [c.pose.shift_mm for c in mixed] == [9.0, 7.0, 8.0]
    assert mixed[1].loaded.dominant.normal_force_n == pytest.approx(
        found[1].loaded.dominant.normal_force_n, rel=1e-3)


def test_a_wheel_that_cannot_reach_its_rail_names_the_field():
    # only the outer 15 mm of the tread: no rail lies below it (a 422 in the service)
    narrow = wheelset_track(wheel_curve_from_height(s1002_height_mm, (45.0, 60.0)), "60E1",
                            1.0 / 40.0, 460.0)
    with pytest.raises(NoContactError) as err:
        contact_at_poses(narrow, "left", [Pose(0.0)])
    assert err.value.field == "shift"
    with pytest.raises(ValueError, match="side"):
        contact_at_poses(s1002_60e1(), "middle", [Pose(0.0)])
    with pytest.raises(ValueError, match="poses"):
        contact_at_poses(s1002_60e1(), "left", [])


def test_manchester_a22_from_contact_files_through_the_api(reference_dir):
    # CONTACT's case 15 (left wheel at 7.0 mm, flange) and case 3 (1.0 mm, tread) read
    # from CONTACT's own profile files: position within 0.5 mm and Fn within 2 % (issue 11's
    # goals; the full 42-case comparison is benchmarks/manchester_profiles.py)
    from wearcast.physics.contact.geometry import WheelsetTrack
    from wearcast.physics.profiles.simpack import rail_curve, read_simpack_profile, wheel_curve

    bench = reference_dir / "contact-benchmark"
    if not (bench / "MBench_S1002_v3.prw").is_file():
        pytest.skip("CONTACT's MBench profile files not found")
    track = WheelsetTrack(wheel=wheel_curve(read_simpack_profile(bench / "MBench_S1002_v3.prw")),
                          rail=rail_curve(read_simpack_profile(bench / "MBench_UIC60_v3.prr")),
                          rail_inclination=0.0)
    found = contact_at_poses(track, "left", [Pose(1.0), Pose(7.0, 0.0084)],
                             shear_modulus_mpa=82_000.0)
    for c in found:
        assert c.loaded.vertical_force_n == pytest.approx(10_000.0, rel=2e-4)
        assert c.to_dict()["n_patches"] == 1
    assert abs(found[1].loaded.dominant.contact_angle_rad) > np.radians(55.0)
    assert abs(found[0].loaded.dominant.contact_angle_rad) < np.radians(5.0)
