"""Turning depth against an independent geometric construction, variants, economic choice."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.maintenance.limits import FleetLimits
from wearcast.statistics.maintenance.turning import (
    economic_choice,
    projected_profile,
    s1002_targets,
    turning_cut,
    turning_options,
    wheel_life,
)

TARGETS = s1002_targets()


def _brute_force_cut(y_w: np.ndarray, z_w: np.ndarray, heights, step: float = 0.002) -> float:
    """Smallest cut c on a 0.002 mm ladder such that every point of the target, sampled on
    its own 0.013 mm grid and moved down by c, lies on or below the worn polyline."""
    z_rel = z_w - np.interp(0.0, y_w, z_w)
    ys = np.arange(max(y_w[0], -62.76), min(y_w[-1], 32.15), 0.013)
    zt = heights(ys)
    zw = np.interp(ys, y_w, z_rel)
    flat = np.abs(np.diff(zt, append=zt[-1]) / 0.013) <= 3.0  # the flange back is not cut
    for c in np.arange(-1.0, 12.0, step):
        if np.all((zt - c <= zw + 1e-9) | ~flat):
            return float(c)
    raise AssertionError("no cut found")


def _worn(layer, y=None):
    y = np.arange(-69.0, 58.0, 0.37) if y is None else y
    return y, s1002_height_mm(y) - layer(y)


@pytest.mark.parametrize("target", TARGETS, ids=lambda t: t.name)
def test_cut_matches_brute_force_on_flank_and_tread_wear(target):
    y, z = _worn(lambda y: 2.1 * np.exp(-((y + 43) / 5) ** 2)
                 + 0.6 * np.exp(-((y - 8) / 14) ** 2))
    cut = turning_cut(y, z, target)
    brute = _brute_force_cut(y, z, target.heights)
    assert cut.radial_mm == pytest.approx(brute, abs=0.004)
    assert cut.diameter_loss_mm == pytest.approx(2 * cut.radial_mm)


def test_known_uniform_layer_restored_by_that_layer():
    # a uniform vertical layer t removed everywhere on S1002, measured in its own frame:
    # the tape circle went down by t too, so restoring S1002 needs no cut beyond it: 0
    # (finely sampled: a polyline's chords lie below the convex flange by h^2 / 8R)
    fine = np.arange(-69.0, 58.0, 0.01)
    y, z = _worn(lambda y: np.full_like(y, 1.7), fine)
    assert turning_cut(y, z, TARGETS[0]).radial_mm == pytest.approx(0.0, abs=2e-4)
    # a layer on the flange only (tread intact): the cut is the layer's depth
    y, z = _worn(lambda y: np.where(y < -30, 1.3, 0.0), fine)
    assert turning_cut(y, z, TARGETS[0]).radial_mm == pytest.approx(1.3, abs=2e-4)


def test_thinner_flange_needs_less_diameter_and_cuts_only_the_tip_overhang():
    y, z = _worn(lambda y: 2.5 * np.exp(-((y + 42) / 4) ** 2))
    losses = {t.name: turning_cut(y, z, t).diameter_loss_mm for t in TARGETS}
    assert all(losses["S1002"] > loss + 1.0 for name, loss in losses.items() if name != "S1002")
    # A variant's flange is translated towards the back face with its tip (EN 13715, the
    # catalogue of physics.profiles.references), so its tip stands over the old flange back:
    # turning a new S1002 to it cuts exactly that overhang (0.32 to 0.48 mm), found here on a
    # 0.01 mm grid; the cut's own 0.1 mm sampling of the tip adds a chord sagitta < 2e-3 mm.
    yy = np.arange(-70, 60, 0.1)
    fine = np.arange(-70, 60, 0.01)
    for t in TARGETS:
        overhang = max(0.0, float(np.nanmax(t.heights(fine) - s1002_height_mm(fine))))
        assert overhang < 0.5
        cut = turning_cut(yy, s1002_height_mm(yy), t).radial_mm
        assert cut == pytest.approx(overhang, abs=2e-3)


def test_variant_flange_thickness():
    for t in TARGETS:
        assert t.sd_mm == pytest.approx(float(t.name.split("e")[-1]) if "/e" in t.name
                                        else 32.5, abs=0.01)
        assert 27.7 < t.sh_mm <= 28.0 + 1e-6
    with pytest.raises(ValueError, match="flange_thickness_mm"):
        s1002_targets((33.0,))


def test_profile_must_cover_flange_and_tread():
    y, z = _worn(lambda y: 0 * y, np.arange(-40.0, 50.0, 0.5))
    with pytest.raises(ValueError, match="profile"):
        turning_cut(y, z, TARGETS[0])


def test_economic_choice_and_life():
    y, z = _worn(lambda y: 2.0 * np.exp(-((y + 42) / 4) ** 2))
    rates = {"sd": 1e-5, "sh": 1e-6, "qr": 1e-6}  # mm per km
    options = turning_options(y, z, TARGETS, FleetLimits(), rates)
    best, least = economic_choice(options)
    assert least.cut.diameter_loss_mm == min(o.cut.diameter_loss_mm for o in options)
    assert best.km_per_mm == max(o.km_per_mm for o in options if o.restores_all)
    # Sd governs: km to the next limit is the restored Sd margin over the Sd rate
    ref = next(o for o in options if o.cut.target == "S1002")
    assert ref.km_to_next_limit == pytest.approx((32.5 - 22.0) / 1e-5, rel=1e-3)
    life = wheel_life(900.0, 840.0, 6.0, 200_000.0, 1e-5, 50_000.0)
    # 900 - 6k - 2(k-1) >= 840 -> k = 7
    assert life.turnings_left == 7
    assert life.km_to_scrap == pytest.approx(50_000 + 7 * 200_000)
    assert wheel_life(843.0, 840.0, 6.0, 1.0).turnings_left == 0


def test_projection_scales_wear():
    y, z = _worn(lambda y: 1.0 * np.exp(-((y + 42) / 4) ** 2))
    z2 = projected_profile(y, z, 2.0)
    c1 = turning_cut(y, z, TARGETS[0]).radial_mm
    c2 = turning_cut(y, z2, TARGETS[0]).radial_mm
    assert c2 == pytest.approx(2 * c1, rel=0.02)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.floats(0.0, 3.0), st.floats(-60.0, 30.0), st.floats(2.0, 20.0)),
                min_size=1, max_size=4))
def test_cut_restoring_s1002_is_the_layer_above_its_tape_circle_value(bumps):
    """Property: a wheel worn by a layer L(y) >= 0 from S1002 and measured in its own frame
    needs the cut max L - L(0) over the checked range to restore S1002 (and no more: the
    cut is the smallest; adding wear never lowers it)."""
    y = np.arange(-69.0, 58.0, 0.02)
    layer = sum(a * np.exp(-((y - c) / w) ** 2) for a, c, w in bumps)
    z = s1002_height_mm(y) - layer
    cut = turning_cut(y, z, TARGETS[0])
    inside = (y >= -62.76) & (y <= 32.15)
    expected = float(layer[inside].max() - np.interp(0.0, y, layer))
    assert cut.radial_mm == pytest.approx(expected, abs=2e-3)
    more = turning_cut(y, z - 0.3 * np.exp(-((y + 45) / 5) ** 2), TARGETS[0])
    assert more.radial_mm >= cut.radial_mm - 1e-9
