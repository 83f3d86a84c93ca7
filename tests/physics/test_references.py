"""Reference-profile catalogue: S1002 and its EN 13715 flange-thickness variants."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.profiles.parameters import flange_parameters
from wearcast.physics.profiles.references import (
    S1002_FLANGE_THICKNESSES_MM,
    builtin_reference,
    builtin_references,
    canonical_s1002_name,
    points_reference,
    s1002_variant_height,
)
from wearcast.physics.profiles.s1002 import s1002_height_mm


@pytest.mark.parametrize("e", S1002_FLANGE_THICKNESSES_MM)
def test_each_variant_has_its_flange_thickness_and_keeps_height_and_slope(e: float) -> None:
    y = np.linspace(-70.0, 60.0, 2601)
    p = flange_parameters(y, s1002_variant_height(e)(y))
    assert p.sd_mm == pytest.approx(e, abs=0.01)
    assert p.sh_mm == pytest.approx(28.0, abs=0.02)
    assert p.qr_mm == pytest.approx(10.8, abs=0.05)


@pytest.mark.parametrize("e", [31.5, 28.5])
def test_variants_keep_the_tread_and_the_back_face(e: float) -> None:
    height = s1002_variant_height(e)
    tread = np.linspace(-26.0, 60.0, 500)
    np.testing.assert_array_equal(height(tread), s1002_height_mm(tread))
    assert height(-70.0) == pytest.approx(float(s1002_height_mm(-70.0)))
    # the bridge over the step is level at S1002's height at y = -26
    bridge = np.linspace(-26.0 - (32.5 - e) + 0.01, -26.01, 20)
    np.testing.assert_allclose(height(bridge), s1002_height_mm(-26.0))
    assert np.isnan(height(-70.5)) and np.isnan(height(60.5))


def test_the_flange_face_moves_towards_the_back_face() -> None:
    # thinner flange: on the flange face (between the moved tip and the bridge) the variant
    # lies below S1002 and equals S1002 taken 3 mm further out
    y = np.linspace(-49.0, -29.5, 500)
    height = s1002_variant_height(29.5)
    assert (height(y) - s1002_height_mm(y)).max() < 0.0
    np.testing.assert_allclose(height(y), s1002_height_mm(y + 3.0))


def test_names_and_bounds() -> None:
    assert canonical_s1002_name("s1002-31.5") == "S1002/31.5"
    assert canonical_s1002_name("S1002 e=30,5") == "S1002/30.5"
    assert canonical_s1002_name("S1002/32.5") == "S1002"
    assert canonical_s1002_name("P8") is None
    assert s1002_variant_height(32.5) is s1002_height_mm
    assert s1002_variant_height(30.5) is s1002_variant_height(30.5)
    with pytest.raises(ValueError, match="flange_thickness_mm"):
        s1002_variant_height(27.0)
    with pytest.raises(ValueError):
        builtin_reference("S1002/34")
    assert [r.name for r in builtin_references()] == [
        "S1002", "S1002/31.5", "S1002/30.5", "S1002/29.5", "S1002/28.5"]


def test_points_reference_interpolates_and_knows_its_parameters() -> None:
    y = np.linspace(-70.0, 60.0, 1301)
    ref = points_reference("drawing", y, s1002_height_mm(y))
    q = np.array([-55.0, -37.5, 0.0, 59.0])
    np.testing.assert_allclose(ref.height_mm(q), s1002_height_mm(q), atol=2e-3)
    assert np.isnan(ref.height_mm(np.array([61.0])))[0]
    p = ref.parameters
    assert (p.sd_mm, p.sh_mm, p.qr_mm) == pytest.approx((32.5, 28.0, 10.8), abs=0.05)
