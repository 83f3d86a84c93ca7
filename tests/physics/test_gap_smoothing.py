"""Smoothing of the contact table's gap (physics/gap_smoothing.py)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from wearcast.physics import curving as cv
from wearcast.physics.gap_smoothing import check_gap_smoothing, masked_gaussian


def test_masked_gaussian_ignores_the_samples_off_the_mask():
    y = np.arange(200) * 0.2
    values = 0.01 * (y - 20.0) ** 2
    full = np.ones_like(y, dtype=bool)
    s0, s2 = masked_gaussian(values, full.astype(float), 10.0)
    # the whole kernel on the mask: the plain Gaussian filter and its second derivative
    np.testing.assert_allclose(s0, gaussian_filter1d(values, 10.0, mode="nearest"), atol=1e-12)
    np.testing.assert_allclose(s2, gaussian_filter1d(values, 10.0, order=2, mode="nearest"),
                               atol=1e-12)
    mask = y < 30.0
    a0, a2 = masked_gaussian(np.where(mask, values, 0.0), mask.astype(float), 10.0)
    # next to the mask's edge the smoothed parabola is not pulled up by what lies beyond it:
    # it differs from the plain filter of the parabola continued by the one-sided average's
    # lag only (0.30 mm at the edge, where the parabola rises 0.2 mm per mm); a 100 mm fill
    # smoothed in raises it by tens of millimetres
    plain = gaussian_filter1d(values, 10.0, mode="nearest")
    assert np.max(np.abs(a0[mask] - plain[mask])) < 0.35
    filled = gaussian_filter1d(np.where(mask, values, 100.0), 10.0, mode="nearest")
    assert np.max(np.abs(filled[mask] - plain[mask])) > 10.0
    # a constant stays constant up to the mask's edge (normalised convolution), its second
    # derivative the plain filter's of a constant (the truncated kernel's sum, ~3e-5 here),
    # and the second derivative is the numerical one of the smoothed values
    const = np.full_like(y, 3.0)
    c0, c2 = masked_gaussian(np.where(mask, const, 0.0), mask.astype(float), 10.0)
    np.testing.assert_allclose(c0[mask], 3.0, rtol=1e-12)
    assert np.max(np.abs(c2[mask])) < 6e-5
    inner = np.nonzero(mask)[0][5:-5]
    numeric = np.gradient(np.gradient(a0))
    np.testing.assert_allclose(a2[inner], numeric[inner], atol=5e-5)


def test_an_unknown_method_is_refused_by_name():
    with pytest.raises(ValueError, match="gap_smoothing"):
        check_gap_smoothing("median")
    with pytest.raises(ValueError, match="gap_smoothing"):
        cv.build_contact_table(None, "60E1", 1 / 40, 0.46, gap_smoothing="median")


def test_the_masked_smoothing_keeps_the_tread_and_is_continuous_in_the_shift():
    # On the tread, far from the rail's ends, both methods are the same filter; the masked
    # table's candidates move continuously with the shift on the flange too (no jump of the
    # deepest candidate's gap between neighbouring shifts of the table's 0.1 mm grid).
    plain = cv.build_contact_table(None, "60E1", 1 / 40, 0.46)
    masked = cv.build_contact_table(None, "60E1", 1 / 40, 0.46, gap_smoothing="masked")
    tread = (plain.wheel_y_mm > -10.0) & (plain.wheel_y_mm < 20.0)
    centred = np.abs(plain.shift_mm) < 3.0
    np.testing.assert_allclose(masked.gap_mm[np.ix_(centred, tread)],
                               plain.gap_mm[np.ix_(centred, tread)], atol=1e-6)
    shifts = np.arange(6.0, 9.5, 0.01)
    deepest = np.array([np.min(masked.candidates(s)["gap_mm"]) for s in shifts])
    assert np.all(np.abs(np.diff(deepest)) < 0.05)


def test_the_rail_edge_ramp_acts_on_the_masked_table_only(monkeypatch):
    # RAIL_EDGE_RAMP_MM is a module setting read at table build: the Gaussian method ignores
    # it bit for bit; the default 3 mm ramp (loop-robust) puts the masked flange contact
    # root-wards (towards +y) of a 1 mm ramp's but keeps it on the flank, short of the 3-6 mm
    # of the Gaussian method (measured 1.3-1.8 mm at 1:40;
    # tests/physics/test_curving_flange_contact.py holds both ramps' accuracy)
    from wearcast.physics import gap_smoothing as gs

    def flange_y(method: str) -> float:
        table = cv.build_contact_table(None, "60E1", 1 / 40, 0.43, gap_smoothing=method)
        cand = table.candidates(8.0)
        return float(cand["wheel_y_mm"][int(np.argmin(cand["gap_mm"]))])

    def gaussian_gap() -> np.ndarray:
        return cv.build_contact_table(None, "60E1", 1 / 40, 0.43,
                                      gap_smoothing="gaussian").gap_mm

    assert gs.RAIL_EDGE_RAMP_MM == 3.0
    wide_masked, wide_gauss = flange_y("masked"), gaussian_gap()
    monkeypatch.setattr(gs, "RAIL_EDGE_RAMP_MM", 1.0)
    narrow_masked, narrow_gauss = flange_y("masked"), gaussian_gap()
    np.testing.assert_array_equal(wide_gauss, narrow_gauss)
    assert 0.5 < wide_masked - narrow_masked < 3.0
    assert wide_masked < flange_y("gaussian") - 1.0



def test_the_slope_averaged_like_the_gap_is_the_rate_its_minimum_closes_with_the_shift():
    # g(y, s) = A(y) + B(y + s), the rail's coverage moving with it (rail below y + s > -6 mm):
    # at the masked smoothed gap's minimum (on full coverage), d S_min / d s = -(A' averaged
    # with the gap's weights) (envelope theorem, ``curving_table.ContactTable``). The minimum
    # lies 4-5 mm inside the rail's edge, where the 2 mm kernel reaches past it: measured
    # within 1e-4 (a central difference in s), the plain Gaussian average of A' 0.001-0.006
    # off, A' at the point 0.03.
    from wearcast.physics.gap_smoothing import smooth_gap, smooth_like_gap

    step = 0.05
    y = np.arange(-20.0, 20.0 + 1e-9, step)
    a = 0.02 * y**2 + 0.002 * y**3 + 0.25 * y
    a1 = 0.04 * y + 0.006 * y**2 + 0.25
    scales = ((1.0, 2.0),)

    def smoothed(s):
        raw = (a + 0.03 * (y + s - 3.0) ** 2)[None, :]
        inside = (y + s + 6.0)[None, :]
        return smooth_gap(raw, inside, scales, step, "masked")[0][0], inside

    def minimum(s):
        g, _ = smoothed(s)
        i = int(np.argmin(g))
        den = g[i - 1] - 2.0 * g[i] + g[i + 1]
        frac = 0.5 * (g[i - 1] - g[i + 1]) / den
        return y[i] + frac * step, g[i] - 0.125 * (g[i - 1] - g[i + 1]) * frac

    h = 0.02
    plain_off = []
    for s in (-1.0, 0.0, 1.0):
        yc, _ = minimum(s)
        assert yc + s + 6.0 > 3.5  # on full coverage, the kernel reaching past the edge
        rate = (minimum(s + h)[1] - minimum(s - h)[1]) / (2.0 * h)
        _, inside = smoothed(s)
        mean = np.interp(yc, y, smooth_like_gap(a1, 1, inside, scales, step, "masked")[0])
        assert rate == pytest.approx(-mean, abs=3e-4), (s, yc)
        plain = np.interp(yc, y, smooth_like_gap(a1, 1, None, scales, step, "gaussian")[0])
        plain_off.append(abs(rate + plain))
    assert max(plain_off) > 5e-3
