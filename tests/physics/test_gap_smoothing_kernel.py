"""The gap smoothing's compiled Gaussian filters (physics/gap_smoothing_kernel.py) against scipy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from wearcast.physics import gap_smoothing as gs
from wearcast.physics.gap_smoothing_kernel import gaussian_rows, gaussian_taps


def _assert_same(got, ref):
    """Equal to rounding (bit for bit on x86-64, where neither side fuses a multiply-add; a
    compiler that fuses them, as on aarch64, may round the last bit differently)."""
    np.testing.assert_allclose(got, ref, rtol=0.0, atol=1e-13 * max(1.0, np.max(np.abs(ref))))


@pytest.mark.parametrize("sigma", [10.0, 12.5, 2.5, 1.0])
def test_gaussian_rows_are_scipys_filters(sigma):
    # orders 0, 1, 2 with mode nearest: the same numbers as scipy's gaussian_filter1d (rows
    # shorter than the kernel too, where the ends' extension reaches across the whole row)
    rng = np.random.default_rng(7)
    for shape in ((301, 501), (3, 7), (1, 1)):
        values = 10.0 * rng.normal(size=shape) + np.linspace(0.0, 50.0, shape[1])
        got = gaussian_rows(values, *(gaussian_taps(sigma, o) for o in (0, 1, 2)))
        for order in (0, 1, 2):
            ref = gaussian_filter1d(values, sigma, axis=-1, order=order, mode="nearest")
            _assert_same(got[order], ref)


def test_gaussian_taps_are_the_truncated_kernel():
    # radius int(4 sigma + 0.5); the order-0 taps sum to 1 over both sides, the odd order's
    # centre tap is zero
    taps = gaussian_taps(10.0, 0)
    assert taps.size == 41
    assert taps[0] + 2.0 * taps[1:].sum() == pytest.approx(1.0, abs=1e-15)
    assert gaussian_taps(10.0, 1)[0] == 0.0
    with pytest.raises(ValueError, match="order"):
        gaussian_taps(10.0, 3)


def _masked_gaussian_scipy(weighted_values, mask, sigma_samples):
    """``gap_smoothing.masked_gaussian`` as it was written with scipy's filter (the reference)."""
    m = np.asarray(mask, dtype=float)
    n0, n1, n2 = (gaussian_filter1d(weighted_values, sigma_samples, axis=-1, order=o,
                                    mode="nearest") for o in (0, 1, 2))
    full = np.ones(m.shape[-1])
    d0, d1, d2 = (gaussian_filter1d(m, sigma_samples, axis=-1, order=o, mode="nearest")
                  - (0.0 if o == 0 else gaussian_filter1d(full, sigma_samples, order=o,
                                                          mode="nearest"))
                  for o in (0, 1, 2))
    d0 = np.where(d0 > 1e-12, d0, 1.0)
    s0 = n0 / d0
    s1 = (n1 - s0 * d1) / d0
    s2 = (n2 - 2.0 * s1 * d1 - s0 * d2) / d0
    return s0, s2


def test_masked_gaussian_equals_its_scipy_form():
    # a table-like row set: a parabola over a rail whose edge moves with the row, the
    # certainty a C1 ramp over 3 mm (0.2 mm samples)
    y = np.arange(-55.0, 45.0 + 1e-9, 0.2)
    edge = np.linspace(-45.0, -30.0, 151)[:, None]
    values = 0.01 * (y[None, :] + 5.0) ** 2 + 0.1 * edge
    mask = gs.smoothstep((y[None, :] - edge) / 3.0)
    got = gs.masked_gaussian(mask * values, mask, 10.0)
    ref = _masked_gaussian_scipy(mask * values, mask, 10.0)
    for a, b in zip(got, ref, strict=True):
        _assert_same(a, b)
