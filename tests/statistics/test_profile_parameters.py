"""Tests of wearcast.statistics.profile_parameters: Sd, Sh, qR and the limits."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from wearcast.physics.profiles.s1002 import s1002_height_mm, s1002_profile
from wearcast.statistics.cleaning import clean_profile
from wearcast.statistics.profile_parameters import (
    DEFAULT_LIMITS,
    FlangeParameters,
    WheelLimits,
    flange_parameters,
    parameters_from_wear_curve,
)
from wearcast.statistics.wear_curves import DEFAULT_GRID_Y_MM


@pytest.mark.parametrize("step_mm", [0.1, 0.5])
def test_s1002_new_gives_the_published_parameters(step_mm):
    # DESIGN.md / reference README: S1002 new has Sd 32.50, Sh 28.00, qR 10.80 mm. The exact
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


def _flange_face_worn(y, lateral_mm):
    """S1002 with the flange face (field-side flank, -55 < y < -30) moved towards the
    flange by ``lateral_mm``; tip, flange back and tread untouched."""
    z = s1002_height_mm(y)
    flank = (y > -55.0) & (y < -30.0)
    return np.where(flank, np.minimum(z, s1002_height_mm(y + lateral_mm)), z)


def test_flange_face_worn_2mm_thins_the_flange_by_2mm():
    y = np.linspace(-70.0, 60.0, 2601)
    p = flange_parameters(y, _flange_face_worn(y, 2.0))
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


def test_parameters_from_zero_wear_curve_are_s1002():
    p = parameters_from_wear_curve(DEFAULT_GRID_Y_MM, np.zeros(DEFAULT_GRID_Y_MM.size))
    assert (p.sd_mm, p.sh_mm, p.qr_mm) == pytest.approx((32.5, 28.0, 10.8), abs=0.01)


def test_parameters_from_wear_curve_match_the_worn_profile():
    grid = DEFAULT_GRID_Y_MM
    wear = s1002_height_mm(grid) - _flange_face_worn(grid, 1.5)
    p = parameters_from_wear_curve(grid, wear)
    assert p.sd_mm == pytest.approx(31.0, abs=0.01)


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


def test_default_limits_are_the_cited_ones():
    # reference README "Wheel limits" (EBO Anlage 6 / EisbBBV Anlage 2)
    assert DEFAULT_LIMITS.sd_min_mm == 22.0
    assert DEFAULT_LIMITS.sh_max_mm == 36.0
    assert DEFAULT_LIMITS.qr_min_mm == 6.5
    assert DEFAULT_LIMITS.exceeded(FlangeParameters(32.5, 28.0, 10.8)) == ()
    assert DEFAULT_LIMITS.exceeded(FlangeParameters(21.0, 36.5, 6.0)) == ("sd", "sh", "qr")
    domestic = WheelLimits(sd_min_mm=20.0)
    assert domestic.exceeded(FlangeParameters(21.0, 30.0, 8.0)) == ()


def _read_regular_miniprof(path):
    """Tiny local reader of a regular MiniProf file: ``Key=Value`` header, points after the
    first blank line, X from the back face and Y up (reference README format notes)."""
    text = path.read_text(errors="replace")
    header, body = text.split("\n\n", 1)
    values = dict(re.findall(r"^(Sd|Sh|qR)=([-0-9.]+)", header, flags=re.MULTILINE))
    points = np.array([[float(v) for v in line.replace(",", " ").split()[:2]]
                       for line in body.splitlines() if line.strip()])
    return {k: float(v) for k, v in values.items()}, points[:, 0] - 70.0, points[:, 1]


@pytest.mark.parametrize(
    "name",
    [
        "left-wheel-v1-pre-dry.whl",
        "right-wheel-v1-pre-dry.whl",
        "whl_left_iter288.whl",
        "whl_left_iter795.whl",
    ],
)
def test_recomputed_parameters_match_the_miniprof_header(reference_dir, name):
    # Reference README: recomputing Sd/Sh/qR from the points of the regular MiniProf files
    # agrees with the instrument's header to 0.02-0.17 mm (the instrument smooths its points).
    # Measured here (|Sd|/|Sh|/|qR| differences): left-wheel 0.022/0.020/0.016, right-wheel
    # 0.079/0.173/0.011, iter288 0.035/0.008/0.019, iter795 0.011/0.011/0.025 mm. 0.2 mm covers the
    # README's range; the parameters are computed in the instrument frame (y = X - 70).
    header, y, z = _read_regular_miniprof(reference_dir / "miniprof" / name)
    cleaned = clean_profile(y, z)
    p = flange_parameters(cleaned.y_mm, cleaned.z_mm)
    assert p.sd_mm == pytest.approx(header["Sd"], abs=0.2)
    assert p.sh_mm == pytest.approx(header["Sh"], abs=0.2)
    assert p.qr_mm == pytest.approx(header["qR"], abs=0.2)
