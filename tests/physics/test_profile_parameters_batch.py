"""The batched Sd/Sh/qR (``flange_parameters_batch``) against the one-profile definition."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wearcast.physics.profiles.parameters import flange_parameters, flange_parameters_batch
from wearcast.physics.profiles.s1002 import s1002_height_mm, s1002_profile

# The hybrid model's lateral grid (statistics.wear_curves.DEFAULT_GRID_Y_MM) [mm].
DEFAULT_GRID_Y_MM = np.linspace(-58.0, 50.0, 217)


def _worn_profiles(y: np.ndarray, n: int, seed: int) -> np.ndarray:
    """S1002 with random flange-face and tread wear bumps and, on some rows, noise [mm]."""
    rng = np.random.default_rng(seed)
    flange = rng.uniform(0.0, 4.0, (n, 1)) * np.exp(
        -0.5 * ((y - rng.uniform(-45.0, -33.0, (n, 1))) / rng.uniform(1.0, 6.0, (n, 1))) ** 2)
    tread = rng.uniform(0.0, 3.0, (n, 1)) * np.exp(-0.5 * (y / 14.0) ** 2)
    noise = rng.normal(0.0, 0.02, (n, y.size)) * (rng.uniform(size=(n, 1)) < 0.3)
    return s1002_height_mm(y) - flange - tread + noise


def _scalar(y: np.ndarray, z: np.ndarray) -> np.ndarray:
    out = []
    for row in z:
        p = flange_parameters(y, row)
        out.append((p.sd_mm, p.sh_mm, p.qr_mm))
    return np.asarray(out)


@pytest.mark.parametrize("y", [np.asarray(DEFAULT_GRID_Y_MM), np.linspace(-70.0, 60.0, 1301),
                               np.linspace(-60.3, 40.1, 300)], ids=["model", "0.1mm", "odd"])
def test_batch_equals_the_one_profile_definition(y):
    # the batch runs the one computation of the one-profile definition (sampled tip,
    # quadratic flank crossings, tape-circle interpolation) on all rows at once: the same
    # numbers to the bit
    z = _worn_profiles(y, 300, seed=int(y.size))
    z[3, 40] = np.nan  # a gap: that row goes through the one-profile path
    batch = flange_parameters_batch(y, z).stacked()
    scalar = _scalar(y, z)
    assert np.isfinite(batch).sum() > 800
    assert np.array_equal(batch, scalar, equal_nan=True)


def test_s1002_new_gives_the_published_parameters_in_a_batch():
    # docs/conventions.md / reference README: S1002 new has Sd 32.50, Sh 28.00, qR 10.80 mm (the
    # exact
    # analytic qR is 10.794, hence 0.01 mm as in test_profile_parameters)
    y, z = s1002_profile(0.5)
    p = flange_parameters_batch(y, np.vstack([z, z]))
    np.testing.assert_allclose(p.sd_mm, 32.50, atol=0.01)
    np.testing.assert_allclose(p.sh_mm, 28.00, atol=0.01)
    np.testing.assert_allclose(p.qr_mm, 10.80, atol=0.01)


def test_undefined_points_give_nan_and_shapes_are_checked():
    y = np.linspace(-58.0, -5.0, 107)  # no tape circle: nothing is defined
    p = flange_parameters_batch(y, s1002_height_mm(y)[None, :])
    assert np.isnan(p.stacked()).all()
    with pytest.raises(ValueError, match="z_mm"):
        flange_parameters_batch(np.linspace(-58, 50, 10), np.zeros((2, 11)))
    one = flange_parameters_batch(DEFAULT_GRID_Y_MM, s1002_height_mm(DEFAULT_GRID_Y_MM))
    assert one.sd_mm.shape == (1,)


@settings(max_examples=40, deadline=None)
@given(dz=st.floats(-5.0, 5.0), flange=st.floats(0.0, 5.0), tread=st.floats(0.0, 4.0),
       centre=st.floats(-46.0, -32.0))
def test_batch_matches_scalar_for_any_wear(dz, flange, tread, centre):
    y = np.asarray(DEFAULT_GRID_Y_MM)
    z = (s1002_height_mm(y) + dz - flange * np.exp(-0.5 * ((y - centre) / 3.0) ** 2)
         - tread * np.exp(-0.5 * (y / 14.0) ** 2))
    batch = flange_parameters_batch(y, z[None, :]).stacked()[0]
    assert np.array_equal(batch, _scalar(y, z[None, :])[0], equal_nan=True)
