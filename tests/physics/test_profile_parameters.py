"""Tests of wearcast.physics.profiles.parameters: Sd, Sh, qR (EN 15313 / MiniProf)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from tests.conftest import flange_face_worn_s1002
from wearcast.physics.profiles.parameters import (
    flange_parameters,
    nominal_frame_flange_parameters,
    tape_circle_height_mm,
)
from wearcast.physics.profiles.s1002 import s1002_height_mm, s1002_profile


@pytest.mark.parametrize("step_mm", [0.1, 0.5])
def test_s1002_new_gives_the_published_parameters(step_mm):
    # docs/conventions.md / reference README: S1002 new has Sd 32.50, Sh 28.00, qR 10.80 mm. The
    # exact
    # values of the analytic profile are Sd = 32.500, Sh = 28.000 and qR = 10.794 (flank arc
    # F: z = 26 at y = -48.294); the published 10.80 is rounded, so 0.01 mm holds.
    y, z = s1002_profile(step_mm)
    p = flange_parameters(y, z)
    assert p.sd_mm == pytest.approx(32.50, abs=0.01)
    assert p.sh_mm == pytest.approx(28.00, abs=0.01)
    assert p.qr_mm == pytest.approx(10.80, abs=0.01)


def test_s1002_qr_matches_the_arc_geometry():
    # qR point: section F arc, centre (-58.558326413, 8.834924130), R = 20, at z = 26
    y_qr = -58.558326413 + np.sqrt(20.0**2 - (26.0 - 8.834924130) ** 2)
    y_sd = brentq(lambda y: s1002_height_mm(y) - 10.0, -39.0, -36.0)
    y, z = s1002_profile(0.05)
    assert flange_parameters(y, z).qr_mm == pytest.approx(y_sd - y_qr, abs=1e-3)


def test_flange_face_worn_2mm_thins_the_flange_by_2mm():
    y = np.linspace(-70.0, 60.0, 2601)
    p = flange_parameters(y, flange_face_worn_s1002(y, 2.0))
    assert p.sd_mm == pytest.approx(30.50, abs=0.01)
    assert p.sh_mm == pytest.approx(28.00, abs=0.01)  # tip and tape circle unchanged
    assert p.qr_mm == pytest.approx(10.794, abs=0.01)  # both flank points moved alike


def test_tread_wear_raises_the_flange_and_moves_the_sd_point():
    # 1 mm uniform tread wear (y > -30): Sh = 29; the Sd point is now 9 mm above the old
    # tape-circle height on the unworn flank.
    y = np.linspace(-70.0, 60.0, 2601)
    z = s1002_height_mm(y) - np.where(y > -30.0, 1.0, 0.0)
    p = flange_parameters(y, z)
    y_sd = brentq(lambda v: s1002_height_mm(v) - 9.0, -39.0, -35.5)
    assert p.sh_mm == pytest.approx(29.0, abs=0.01)
    assert p.sd_mm == pytest.approx(y_sd + 70.0, abs=0.01)


def test_profile_without_tape_circle_gives_nan():
    y = np.linspace(-70.0, -5.0, 300)
    p = flange_parameters(y, s1002_height_mm(y))
    assert np.isnan(p.sd_mm) and np.isnan(p.sh_mm) and np.isnan(p.qr_mm)


@settings(max_examples=25, deadline=None)
@given(dz=st.floats(-5.0, 5.0), step=st.floats(0.05, 0.6))
def test_parameters_ignore_vertical_offset_and_sampling(dz, step):
    # Property: Sd, Sh, qR are defined relative to the tape-circle height and the tip,
    # so lifting the profile changes nothing; sampling changes them by < 0.01 mm.
    y = np.arange(-70.0, 60.0, step)
    p = flange_parameters(y, s1002_height_mm(y) + dz)
    assert (p.sd_mm, p.sh_mm, p.qr_mm) == pytest.approx((32.5, 28.0, 10.794), abs=0.01)


def test_nominal_frame_gives_the_published_s1002_parameters():
    # docs/conventions.md: S1002 new Sd 32.50, Sh 28.00, qR 10.80 mm on the wear loop's 0.2 mm grid;
    # chord crossings there: Sd 32.5018, qR 10.7963 (exact 32.500 / 10.794), within 0.01 mm.
    y = np.linspace(-70.0, 60.0, 651)
    p = nominal_frame_flange_parameters(y, s1002_height_mm(y))
    assert (p.sd_mm, p.sh_mm, p.qr_mm) == pytest.approx((32.50, 28.00, 10.80), abs=0.01)


def test_nominal_frame_ignores_tread_wear_where_en_15313_counts_it():
    # 1 mm uniform tread wear (y > -30): EN 15313 (profile's own z(0)) gives Sh 29 and the Sd
    # point 9 mm above the old tape circle; the wear loop's nominal frame (z = 0) keeps Sh 28
    # and the Sd height at 10 mm, so its Sd and qR equal those of the new profile.
    y = np.linspace(-70.0, 60.0, 651)
    z_new = s1002_height_mm(y)
    z = z_new - np.where(y > -30.0, 1.0, 0.0)
    nominal, new = nominal_frame_flange_parameters(y, z), nominal_frame_flange_parameters(y, z_new)
    assert nominal.sh_mm == 28.0 and (nominal.sd_mm, nominal.qr_mm) == (new.sd_mm, new.qr_mm)
    assert flange_parameters(y, z).sh_mm == pytest.approx(29.0, abs=0.01)


def test_nominal_frame_is_the_one_definition_with_its_options():
    y = np.linspace(-70.0, 60.0, 651)
    z = s1002_height_mm(y) - 0.8 * np.exp(-0.5 * ((y + 38.0) / 3.0) ** 2)
    p = flange_parameters(y, z, tip_region_y_mm=(-np.inf, -25.0), tape_circle_z_mm=0.0,
                          interpolation="linear")
    assert nominal_frame_flange_parameters(y, z) == p
    # A chord cuts the convex flank inside the curve: |linear - quadratic| Sd < 0.005 mm here.
    assert abs(p.sd_mm - flange_parameters(y, z, tape_circle_z_mm=0.0).sd_mm) < 0.005
    with pytest.raises(ValueError, match="interpolation"):
        flange_parameters(y, z, interpolation="cubic")


def test_tape_circle_height_gives_np_interp_numbers():
    # the one interpolation at y = 0 (tape circle) behind Sd/Sh/qR, the datum check and the
    # wear at the tape circle: np.interp's numbers to the bit, on a point, between points
    # and beyond the ends (the end heights)
    rng = np.random.default_rng(3)
    for shift in (0.0, 0.13, -0.37, 5.0, -5.0, 2.0):
        y = np.sort(rng.uniform(-3.0, 3.0, 40)) + shift
        y[10] = 0.0 if shift == 2.0 else y[10]
        y = np.sort(y)
        z = rng.normal(0.0, 1.0, y.size)
        assert tape_circle_height_mm(y, z) == float(np.interp(0.0, y, z))
    for bad in (([], []), ([-1.0, 1.0], [0.0])):
        with pytest.raises(ValueError, match="y_mm"):
            tape_circle_height_mm(*bad)
