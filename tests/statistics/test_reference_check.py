"""A measured shape that its declared reference cannot have worn into is flagged."""

from __future__ import annotations

import numpy as np

from wearcast.physics.profiles.references import s1002_variant_height
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.processing import process_profile


def _instrument(z: np.ndarray, y: np.ndarray) -> np.ndarray:
    return z - float(np.interp(0.0, y, z))


def test_a_worn_s1002_fits_s1002_even_when_tread_wear_raises_sd() -> None:
    y = np.linspace(-70.0, 60.0, 651)
    z = s1002_height_mm(y) - 1.7 * np.exp(-((y - 4.0) / 22.0) ** 2)  # deep tread wear
    p = process_profile(y, _instrument(z, y), alignment="datum")
    assert p.parameters.sd_mm > 33.0  # EN 15313 Sd grows with tread wear
    assert p.reference_check is not None and p.reference_check.fits, p.reference_check
    assert p.areas.tread_mm2 > 50.0


def test_a_full_flange_declared_as_a_thin_flange_variant_is_flagged() -> None:
    y = np.linspace(-70.0, 60.0, 651)
    p = process_profile(y, s1002_height_mm(y), alignment="datum",
                        reference_height=s1002_variant_height(28.5))
    assert p.reference_check is not None and not p.reference_check.fits
    assert any("flange thickness" in r for r in p.reference_check.reasons)
    assert p.areas.flange_mm2 < -5.0  # what would have been stored silently


def test_the_matching_variant_fits_with_no_wear() -> None:
    y = np.linspace(-70.0, 60.0, 1301)
    height = s1002_variant_height(30.5)
    p = process_profile(y, height(y), alignment="datum", reference_height=height)
    assert p.reference_check is not None and p.reference_check.fits
    assert abs(p.areas.flange_mm2) < 0.5 and abs(p.areas.tread_mm2) < 0.5


def test_material_above_the_reference_is_flagged() -> None:
    y = np.linspace(-70.0, 60.0, 651)
    z = s1002_height_mm(y) + 0.6 * np.exp(-((y - 20.0) / 15.0) ** 2)
    p = process_profile(y, z, alignment="datum")
    assert p.reference_check is not None and not p.reference_check.fits
    assert any("tread wear area" in r for r in p.reference_check.reasons)


def test_a_stretch_of_material_above_the_reference_is_flagged_even_when_areas_balance() -> None:
    # +0.5 mm over y = -25 … -5 (20 mm) and 0.4 mm of wear over y = 10 … 40: tread area
    # about +2 mm², yet the raised stretch cannot be wear from S1002
    y = np.linspace(-70.0, 60.0, 1301)
    bump = 0.5 * ((y > -25.0) & (y < -5.0)) - 0.4 * ((y > 10.0) & (y < 40.0))
    p = process_profile(y, s1002_height_mm(y) + bump, alignment="datum")
    assert p.areas.tread_mm2 > -5.0
    assert p.reference_check is not None and not p.reference_check.fits
    assert any("above the reference over y" in r for r in p.reference_check.reasons)
