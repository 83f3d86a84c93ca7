"""SIMPACK / CONTACT profile files (.prw / .prr): parsing and the benchmark's own files."""

import numpy as np
import pytest

from wearcast.physics.profiles.rails import rail_60e1_height_mm
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.profiles.simpack import (
    ProfileFileError,
    parse_simpack_profile,
    rail_curve,
    read_simpack_profile,
    wheel_curve,
)

TEXT = """! comment line
  header.begin
    version = 1
    type    = 1   ! wheel
  header.end
  spline.begin
    comment   = 'test ! not a comment'
    mirror.y  = 1
    inversion = 1
    shift.z   = 0.5
    units.len.f = +1.0e+03
    point.begin
    ! y z
!9.0 9.0
1.0  2.0
2.0  3.0
3.0  5.0  1.0
    point.end
  spline.end
"""


def test_parse_applies_the_processing_settings():
    prof = parse_simpack_profile(TEXT)
    assert prof.kind == "wheel"
    assert prof.comment == "test ! not a comment"
    # shift.z, then mirror.y, then inversion (order reversed)
    np.testing.assert_allclose(prof.y_mm, [-3.0, -2.0, -1.0])
    np.testing.assert_allclose(prof.z_mm, [5.5, 3.5, 2.5])


def test_units_in_metres():
    prof = parse_simpack_profile(TEXT.replace("+1.0e+03", "1.0"))
    np.testing.assert_allclose(prof.y_mm, [-3000.0, -2000.0, -1000.0])


@pytest.mark.parametrize(("text", "field"), [
    ("header.begin\n type = 1\nheader.end\n", "point"),
    (TEXT.replace("2.0  3.0", "2.0  abc"), "point"),
    (TEXT.replace("type    = 1", "type = 7"), "type"),
    (TEXT.replace("3.0  5.0  1.0\n", "").replace("2.0  3.0\n", ""), "point"),
])
def test_bad_files_name_the_field(text, field):
    with pytest.raises(ProfileFileError) as info:
        parse_simpack_profile(text)
    assert info.value.field == field
    assert isinstance(info.value, ValueError)


def test_wheel_and_rail_kinds_are_checked():
    prof = parse_simpack_profile(TEXT)
    with pytest.raises(ProfileFileError):
        rail_curve(prof)


def test_benchmark_profiles_match_the_analytic_ones(reference_dir):
    bench = reference_dir / "contact-benchmark"
    wheel = read_simpack_profile(bench / "MBench_S1002_v3.prw")
    rail = read_simpack_profile(bench / "MBench_UIC60_v3.prr")
    assert wheel.kind == "wheel" and rail.kind == "rail"
    assert wheel.y_mm.size == 399 and rail.y_mm.size == 495
    # the S1002 file, mirrored by its header, is the Netter definition to 2e-6 mm
    # (reference README: < 1e-5 mm)
    assert np.max(np.abs(s1002_height_mm(wheel.y_mm) - wheel.z_mm)) < 1e-5
    curve = wheel_curve(wheel)
    assert curve.height_mm(-55.0) == pytest.approx(28.0, abs=1e-4)
    # the rail file is canted 1:40 with z down; turned back upright it is 60E1 (R300/R80/R13)
    # to the reference README's 0.017 mm RMS, once its top is moved to (0, 0)
    upright = rail_curve(rail, inclination=-1.0 / 40.0)
    s = upright.sample(0.1)
    y, z = upright.point(s)
    top = np.argmax(z)
    y, z = y - y[top], z - z[top]
    head = (y > -33.0) & (y < 33.0)
    dev = z[head] - rail_60e1_height_mm(y[head])
    assert np.sqrt(np.mean(dev**2)) < 0.03
