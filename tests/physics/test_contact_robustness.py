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
