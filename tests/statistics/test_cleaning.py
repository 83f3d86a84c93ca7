"""Tests of wearcast.statistics.cleaning: ordering, orientation, removals and refusals."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics.profiles.s1002 import s1002_height_mm, s1002_profile
from wearcast.statistics.cleaning import clean_profile, resample_profile


def _s1002(n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    y = np.linspace(-70.0, 60.0, n)
    return y, s1002_height_mm(y)


def test_clean_s1002_is_unchanged():
    y, z = _s1002()
    cleaned = clean_profile(y, z)
    np.testing.assert_array_equal(cleaned.y_mm, y)
    np.testing.assert_array_equal(cleaned.z_mm, z)
    assert cleaned.n_removed == 0
    assert cleaned.notes == ()


def test_reversed_point_order_gives_ascending_profile():
    y, z = _s1002()
    cleaned = clean_profile(y[::-1], z[::-1])
    np.testing.assert_array_equal(cleaned.y_mm, y)
    np.testing.assert_array_equal(cleaned.z_mm, z)


def test_shuffled_points_are_sorted_and_said_so():
    y, z = _s1002()
    order = np.random.default_rng(3).permutation(y.size)
    cleaned = clean_profile(y[order], z[order])
    np.testing.assert_array_equal(cleaned.y_mm, y)
    assert any("sorted" in note for note in cleaned.notes)


@pytest.mark.parametrize(
    ("flip_y", "flip_z", "expected"),
    [
        (False, True, ("downward",)),
        (True, False, ("mirrored",)),
        (True, True, ("downward", "mirrored")),
    ],
)
def test_orientation_is_detected_and_fixed(flip_y, flip_z, expected):
    y, z = _s1002()
    y_in = -y if flip_y else y
    z_in = -z if flip_z else z
    cleaned = clean_profile(y_in, z_in)
    np.testing.assert_allclose(cleaned.y_mm, y, atol=1e-12)
    np.testing.assert_allclose(cleaned.z_mm, z, atol=1e-12)
    for word in expected:
        assert any(word in note for note in cleaned.notes), cleaned.notes


def test_nan_points_are_dropped_and_infinite_refused():
    y, z = _s1002()
    z_nan = z.copy()
    z_nan[[10, 200]] = np.nan
    cleaned = clean_profile(y, z_nan)
    assert cleaned.n_removed == 2
    assert np.isfinite(cleaned.z_mm).all()
    assert any("NaN" in note for note in cleaned.notes)
    z_inf = z.copy()
    z_inf[5] = np.inf
    with pytest.raises(ValueError, match="infinite"):
        clean_profile(y, z_inf)


def test_duplicates_and_too_close_points_are_merged():
    y, z = s1002_profile(0.5)  # lateral bins of 0.05 mm start at -70: 0.5 mm steps align
    y_extra = np.array([y[150], y[200] + 0.02])  # an exact duplicate, a point 0.02 mm away
    y_raw = np.concatenate([y, y_extra])
    z_raw = np.concatenate([z, s1002_height_mm(y_extra)])
    order = np.argsort(y_raw, kind="stable")
    cleaned = clean_profile(y_raw[order], z_raw[order])
    assert cleaned.n_removed == 2
    assert cleaned.y_mm.size == y.size
    assert np.all(np.diff(cleaned.y_mm) > 0.0)
    assert any("merged 2" in note for note in cleaned.notes)
    assert cleaned.y_mm[200] == pytest.approx(y[200] + 0.01)  # the bin mean
    # bin means of points on the curve stay within the curve's sag over 0.02 mm
    np.testing.assert_allclose(cleaned.z_mm, s1002_height_mm(cleaned.y_mm), atol=1e-4)


def test_zigzag_near_flange_tip_is_removed():
    y, z = _s1002()
    tip = int(np.argmin(np.abs(y + 55.0)))
    # the instrument steps back and forth near the tip: insert points that go backwards
    y_back = y[tip] - np.array([0.2, 0.35, 0.1])
    z_back = s1002_height_mm(y_back) + 0.3  # off the surface, as a probe bounce would be
    y_raw = np.concatenate([y[: tip + 1], y_back, y[tip + 1 :]])
    z_raw = np.concatenate([z[: tip + 1], z_back, z[tip + 1 :]])
    cleaned = clean_profile(y_raw, z_raw)
    assert np.all(np.diff(cleaned.y_mm) > 0.0)
    np.testing.assert_allclose(cleaned.z_mm, s1002_height_mm(cleaned.y_mm), atol=1e-9)
    assert any("zig-zag" in note for note in cleaned.notes)


def test_spike_is_removed():
    y, z = _s1002()
    z_spiked = z.copy()
    z_spiked[250] += 5.0
    cleaned = clean_profile(y, z_spiked)
    assert cleaned.n_removed == 1
    assert y[250] not in cleaned.y_mm


def test_vertical_back_face_is_trimmed():
    y, z = _s1002()
    # MiniProf-style back face: a vertical run at y = -70 from z = -20 up to the flange back,
    # with 0.05 mm lateral jitter, in the instrument's order (back face first)
    rng = np.random.default_rng(1)
    z_face = np.linspace(-20.0, 9.0, 60)
    y_face = -70.0 - np.abs(rng.normal(0.0, 0.05, z_face.size))
    cleaned = clean_profile(np.r_[y_face, y], np.r_[z_face, z])
    on_s1002 = np.abs(cleaned.z_mm - s1002_height_mm(np.clip(cleaned.y_mm, -70, 60)))
    assert cleaned.z_mm.min() > -3.0  # the back face's low points are gone
    assert np.nanmax(on_s1002[cleaned.y_mm >= -69.5]) < 1e-9


def test_metres_are_refused():
    y, z = _s1002()
    with pytest.raises(ValueError, match="looks like metres"):
        clean_profile(y / 1000.0, z / 1000.0)


def test_too_few_points_are_refused():
    y, z = _s1002(15)
    with pytest.raises(ValueError, match="at least"):
        clean_profile(y, z)


def test_profile_without_flange_is_refused():
    y, z = _s1002()
    tread = y > -30.0
    with pytest.raises(ValueError, match="misses the flange"):
        clean_profile(y[tread], z[tread])


def test_profile_without_tread_is_refused():
    y, z = _s1002()
    flange = y < -20.0
    with pytest.raises(ValueError, match="misses the tread"):
        clean_profile(y[flange], z[flange])


def test_mismatched_lengths_are_refused():
    with pytest.raises(ValueError, match="differ in length"):
        clean_profile(np.arange(30.0), np.arange(31.0))


def test_resample_is_exact_on_linear_pieces_and_nan_outside():
    y = np.array([-10.0, 0.0, 10.0, 30.0])
    z = np.array([1.0, 0.0, 2.0, 2.0])
    grid = np.array([-20.0, -5.0, 5.0, 20.0, 40.0])
    out = resample_profile(y, z, grid)
    np.testing.assert_array_equal(np.isnan(out), [True, False, False, False, True])
    np.testing.assert_allclose(out[1:4], [0.5, 1.0, 2.0])
    gapped = resample_profile(y, z, grid, max_gap_mm=15.0)
    assert np.isnan(gapped[3])  # 20 lies in the 20 mm gap between 10 and 30
    assert not np.isnan(gapped[2])


def test_resample_s1002_on_fine_grid():
    y, z = s1002_profile(0.1)
    grid = np.linspace(-58.0, 50.0, 217)
    # linear interpolation between 0.1 mm samples: error <= h^2 / (8 R_min) = 1e-4 mm
    np.testing.assert_allclose(resample_profile(y, z, grid), s1002_height_mm(grid), atol=1.5e-4)


def _read_miniprof_points(path):
    """Tiny local reader: numeric (X, Y) rows after the header's first blank line."""
    text = path.read_text(errors="replace")
    body = text.split("\n\n", 1)[1] if "\n\n" in text else text
    points = []
    for line in body.splitlines():
        parts = line.replace(",", " ").split()
        if len(parts) >= 2:
            try:
                points.append((float(parts[0]), float(parts[1])))
            except ValueError:
                continue
    return np.array(points)


def test_real_miniprof_wheels_clean_the_same_in_any_orientation(reference_dir):
    # Real MiniProf wheels (CONTACT test bank): back faces, chamfers, zig-zags and
    # overhanging field faces. Mirrored and z-downward copies must clean to the same profile.
    files = sorted((reference_dir / "miniprof").glob("*.whl"))
    assert files
    for path in files:
        points = _read_miniprof_points(path)
        y, z = points[:, 0] - 70.0, points[:, 1]  # MiniProf X from the back face, Y up
        straight = clean_profile(y, z)
        flipped = clean_profile(-y[::-1], -z[::-1])
        assert np.all(np.diff(straight.y_mm) > 0.0), path.name
        assert straight.y_mm[0] > -71.0 and straight.y_mm[-1] > 55.0, path.name
        # same points up to the lateral bin edges (bins start at each profile's first point)
        grid = np.linspace(-60.0, 50.0, 111)
        # Reversing the raw order keeps the other side of each zig-zag, so a few grid points
        # near the flange tip may differ by the zig-zag amplitude (up to ~0.2 mm in these files)
        diff = np.abs(
            resample_profile(flipped.y_mm, flipped.z_mm, grid)
            - resample_profile(straight.y_mm, straight.z_mm, grid)
        )
        assert np.nanmax(diff) < 0.25, path.name
        assert np.nanmean(diff < 0.05) > 0.95, path.name
