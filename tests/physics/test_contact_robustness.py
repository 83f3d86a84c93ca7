"""The contact pipeline on raw measured MiniProf wheels: no untyped exception over a sweep of
shifts, yaw and roll (``benchmarks/contact_robustness.py`` runs the full sweep), and a typed
``NoContactError`` for a wheel that cannot touch its rail."""

import sys
from pathlib import Path

import numpy as np
import pytest

from wearcast.physics.contact.geometry import WheelsetTrack
from wearcast.physics.contact.locus import NoContactError, wheel_locus
from wearcast.physics.contact.normal_contact import wheel_normal_contact
from wearcast.physics.profiles.measured import ProfileCurve, rail_curve

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from contact_robustness import raw_wheels, sweep  # noqa: E402


@pytest.mark.parametrize("name", ["Car7216_0001r", "whl_left_iter795"])
def test_raw_measured_wheels_sweep_without_exceptions(reference_dir, name):
    # a new-ish and a heavily worn wheel, raw points (to_wheel_frame only)
    wheel = raw_wheels(reference_dir, 0.02)[name]
    poses, failures, messages, patches = sweep(wheel, np.array([-6.0, 1.0, 8.0]), (0.01,),
                                               (None, 0.002))
    assert poses == 6
    assert not failures, messages
    assert sum(patches.values()) == 6


@pytest.mark.slow
def test_all_raw_wheels_full_sweep(reference_dir):
    for name, wheel in raw_wheels(reference_dir, 0.02).items():
        _, failures, messages, _ = sweep(wheel, np.arange(-8.0, 10.01, 2.0), (-0.01, 0.0, 0.01),
                                         (None, 0.002))
        assert not failures, (name, messages)


def test_a_wheel_that_cannot_reach_its_rail_is_a_typed_error():
    # a "wheel" that is only a flange back far outboard of the rail head: no rail below it
    y = np.linspace(-140.0, -120.0, 41)
    wheel = ProfileCurve.from_points(y, 0.01 * (y + 130.0) ** 2)
    wt = WheelsetTrack(wheel=wheel, rail=rail_curve("60E1"))
    with pytest.raises(NoContactError) as info:
        locus = wheel_locus(wt, [0.0], "left", roll_rad=0.0)
        wheel_normal_contact(locus, 10_000.0)
    assert info.value.field in ("shift", "wheel")
    # phrased "field: reason", which the service maps to a 422 naming the field
    assert str(info.value) == f"{info.value.field}: {info.value.reason}"


def test_worn_wheels_on_a_worn_measured_rail_sweep_without_exceptions(reference_dir):
    # issue 11, "robust on measured data": a worn wheel on a worn rail (MiniProf avg_low2.ban,
    # a measured low rail), two of the wheels over shifts, yaw and roll
    from contact_robustness import measured_rail

    rail = measured_rail(reference_dir / "miniprof" / "avg_low2.ban")
    wheels = raw_wheels(reference_dir, 0.02)
    for name in ("Car7216_0001r", "whl_left_iter795"):
        poses, failures, messages, patches = sweep(wheels[name], np.array([-5.0, 1.0, 7.0]),
                                                   (0.0, 0.01), (None, 0.002), rail)
        assert not failures, (name, messages)
        assert sum(patches.values()) == poses == 12


def test_the_coarse_boundary_element_force_is_continuous_in_the_approach(reference_dir):
    # The coarse BEM grid sits on a fixed lattice (patch_plane.lattice): as the approach
    # grows, elements join at the margin, out of contact. With a grid stretched over the
    # interpenetration region instead, the force of this measured wheel on avg_low2.ban jumped
    # by 2 % of the load within 1e-9 mm of approach (an element count changing), and the
    # approach iteration could not carry the load.
    from contact_robustness import measured_rail

    from wearcast.physics.contact.normal_contact import patch_normal_contact
    from wearcast.physics.contact.patches import patch_regions
    from wearcast.physics.contact.track_profiles import wheelset_track

    rail = measured_rail(reference_dir / "miniprof" / "avg_low2.ban")
    wheel = raw_wheels(reference_dir, 0.02)["Car7216_0001r"]
    wt = wheelset_track(wheel, rail, 1.0 / 40.0, 460.0)
    roll = wheel_locus(wt, [-5.0], "left", yaw_rad=0.01).roll_rad + 0.002
    locus = wheel_locus(wt, [-5.0], "left", yaw_rad=0.01, roll_rad=roll)
    approaches = np.linspace(0.0290, 0.0300, 201)
    forces = []
    for d in approaches:
        regions = patch_regions(locus, 0, d)
        forces.append(sum(patch_normal_contact(locus, 0, r, d, "bem-coarse", 2.1e5, 0.28,
                                               0.2).normal_force_n for r in regions))
    steps = np.abs(np.diff(forces))
    # a smooth force grows by ~ dF/dd * 5e-6 mm ~ 3 N per step here; a jump is 200 N
    assert np.max(steps) < 5.0 * np.median(steps) + 1.0
