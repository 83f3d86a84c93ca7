"""Measured rails: rail frame, head wear W1/W2/W3 and use as the contact model's rail.

Synthetic: a 60E1 head cut by known planes (the worn shapes of a vertical, a gauge-face and a
45-degree wear) and shifted by known amounts gives those amounts back. Real: the MiniProf rail
files of the reference data (``reference_dir``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from wearcast.physics.profiles.measured_rail import (
    NOMINAL_GAUGE_POINT_Y_MM,
    MeasuredRail,
    orient,
    polyline_crossings,
    shape_facts,
    upper_envelope,
)
from wearcast.physics.profiles.rails import rail_profile
from wearcast.physics.rail_head_wear import (
    DATUM_TOLERANCE_MM,
    WornRail,
    rail_head_wear,
    reference_from_points,
)
from wearcast.physics.vehicles import vehicle_preset

#: 60E1 gauge corner point where the surface is at 45 deg: on the R13 arc centred at
#: (-23.0160, -14.9491) (the 60E1 arc chain of EN 13674-1), centre + 13 (-1, 1)/sqrt(2).
P45_60E1 = (-23.0160 - 13 / math.sqrt(2), -14.9491 + 13 / math.sqrt(2))


def _head(step: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    return rail_profile("60E1", step_mm=step, inclination=0.0)


def _clip(y: np.ndarray, z: np.ndarray, a: tuple[float, float], c: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """Sutherland-Hodgman: keep the part of the closed head polygon with a . p <= c."""
    pts = np.stack([y, z], axis=1)
    out = []
    n = len(pts)
    for i in range(n):
        p, q = pts[i], pts[(i + 1) % n]
        fp, fq = a[0] * p[0] + a[1] * p[1] - c, a[0] * q[0] + a[1] * q[1] - c
        if fp <= 0:
            out.append(p)
        if fp * fq < 0:
            out.append(p + fp / (fp - fq) * (q - p))
    arr = np.asarray(out)
    return arr[:, 0], arr[:, 1]


def _worn_60e1(top_cut: float | None = None, gauge_cut: float | None = None,
               corner_cut: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """60E1 with metal removed: the top down to z = -top_cut, the gauge face back to
    y = -35.981 + gauge_cut... (a vertical plane), the corner along the 45-degree line
    corner_cut deep; returned as an open outline gauge side first (bottom edge dropped)."""
    y, z = _head(0.05)
    if top_cut is not None:
        y, z = _clip(y, z, (0.0, 1.0), -top_cut)
    if gauge_cut is not None:
        y, z = _clip(y, z, (-1.0, 0.0), -(-36.0 + gauge_cut))
    if corner_cut is not None:
        n = np.array([1.0, -1.0]) / math.sqrt(2.0)  # inward normal at the corner point
        p = np.array(P45_60E1) + corner_cut * n
        # keep points on the inner side: (x - p) . n >= 0  <=>  (-n) . x <= -n . p
        y, z = _clip(y, z, (-n[0], -n[1]), float(-n @ p))
    # open the closed polygon at its bottom edge (field-side foot -> gauge-side foot)
    bottom = np.nonzero((z[:-1] <= z.min() + 1e-9) & (z[1:] <= z.min() + 1e-9)
                        & (y[:-1] > y[1:]))[0]
    if bottom.size:
        start = int(bottom[0]) + 1
        y, z = np.roll(y, -start), np.roll(z, -start)
    return y, z


def test_unworn_60e1_has_zero_wear_and_its_gauge_point() -> None:
    y, z = _head()
    facts = shape_facts(y, z)
    assert facts.gauge_point_mm is not None
    assert facts.gauge_point_mm[0] == pytest.approx(NOMINAL_GAUGE_POINT_Y_MM, abs=0.01)
    assert facts.head_width_mm == pytest.approx(2 * 35.981, abs=0.02)
    wear = rail_head_wear(y, z, "60E1")
    assert wear.reference_fits and not wear.placement.fitted
    for m in (wear.vertical, wear.lateral, wear.corner_45):
        assert m.status == "ok"
        assert m.value_mm == pytest.approx(0.0, abs=0.01)
    assert wear.corner_45.reference_point_mm == pytest.approx(P45_60E1, abs=0.05)


def test_known_cuts_give_known_wear() -> None:
    y, z = _worn_60e1(top_cut=2.0, gauge_cut=3.0, corner_cut=1.5)
    wear = rail_head_wear(y, z, "UIC60")
    assert wear.reference_fits, wear.mismatch
    assert wear.vertical.value_mm == pytest.approx(2.0, abs=0.01)
    # gauge face at z = -14: reference 60E1 at y = -35.981, cut plane at y = -33
    assert wear.lateral.value_mm == pytest.approx(35.981 - 33.0, abs=0.02)
    assert wear.corner_45.value_mm == pytest.approx(1.5, abs=0.02)
    assert not wear.placement.fitted  # the field side is untouched: datum confirmed
    assert wear.placement.flank_offset_mm == pytest.approx(0.0, abs=0.01)


@pytest.mark.parametrize("cut", [0.3, 1.0, 2.5, 5.0])
def test_wear_follows_the_cut_depth(cut: float) -> None:
    """Property: each measure equals the depth of metal removed where it is taken, whatever
    the depth, and the other measures do not see a cut elsewhere."""
    top = rail_head_wear(*_worn_60e1(top_cut=cut), "60E1")
    assert top.vertical.value_mm == pytest.approx(cut, abs=0.01)
    assert abs(top.lateral.value_mm) < 0.01
    corner = rail_head_wear(*_worn_60e1(corner_cut=cut), "60E1")
    assert corner.corner_45.value_mm == pytest.approx(cut, abs=0.02)
    assert abs(corner.vertical.value_mm) < 0.01
    face = rail_head_wear(*_worn_60e1(gauge_cut=cut), "60E1")
    assert face.lateral.value_mm == pytest.approx(cut - 0.019, abs=0.02)  # plane at -36 + cut
    assert abs(face.vertical.value_mm) < 0.01


def test_resampling_does_not_change_the_measures() -> None:
    y, z = _worn_60e1(top_cut=1.0, gauge_cut=2.0, corner_cut=1.0)
    dense = rail_head_wear(y, z, "60E1")
    from wearcast.physics.profiles.rails import resample_by_arc_length

    coarse = rail_head_wear(*resample_by_arc_length(y, z, 0.5), "60E1")
    for a, b in ((dense.vertical, coarse.vertical), (dense.lateral, coarse.lateral),
                 (dense.corner_45, coarse.corner_45)):
        assert a.value_mm == pytest.approx(b.value_mm, abs=0.03)


def test_vertical_shift_is_vertical_wear_and_small_lateral_shift_is_gauge_wear() -> None:
    y, z = _head()
    # the whole head 0.8 mm lower: the instrument's zero is the vertical datum
    wear = rail_head_wear(y, z - 0.8, "60E1")
    assert wear.vertical.value_mm == pytest.approx(0.8, abs=0.01)
    assert abs(wear.lateral.value_mm) < 0.1  # the 1:20 flank barely moves in 0.8 mm
    # within the datum tolerance a lateral offset is not fitted away
    shift = 0.6
    assert shift < DATUM_TOLERANCE_MM
    wear = rail_head_wear(y + shift, z, "60E1")
    assert not wear.placement.fitted
    assert wear.lateral.value_mm == pytest.approx(shift, abs=0.02)


def test_large_lateral_offset_is_fitted_on_the_field_flank_and_reported() -> None:
    y, z = _worn_60e1(gauge_cut=2.0)
    wear = rail_head_wear(y + 7.0, z, "60E1")  # instrument origin 7 mm off the centre
    assert wear.placement.fitted
    assert wear.placement.lateral_mm == pytest.approx(7.0, abs=0.02)
    assert "FITTED" in wear.placement.method
    assert wear.lateral.value_mm == pytest.approx(35.981 - 34.0, abs=0.03)


def test_a_wider_head_is_a_mismatch_not_negative_wear() -> None:
    y, z = _head()
    wide = np.where(y < 0, y * 1.08, y)  # gauge half stretched outwards by 8 %
    wear = rail_head_wear(wide, z, "60E1")
    assert not wear.reference_fits
    assert wear.lateral.status == "reference_mismatch"
    assert any("OUTSIDE" in reason for reason in wear.mismatch)


def test_60e2_and_uploaded_reference() -> None:
    y, z = rail_profile("60E2", step_mm=0.1, inclination=0.0)
    assert rail_head_wear(y, z, "60E2").lateral.value_mm == pytest.approx(0.0, abs=0.01)
    # 60E2 against 60E1: same width at the gauge point, a fuller corner (60E2's R16 corner
    # lies inside the 60E1 R13 one: the 45-degree measure is positive)
    against_e1 = rail_head_wear(y, z, "60E1")
    assert abs(against_e1.lateral.value_mm) < 0.05
    assert against_e1.corner_45.value_mm > 0.2
    ref = reference_from_points("my new rail", *_head())
    assert rail_head_wear(*_worn_60e1(top_cut=1.0), ref).vertical.value_mm == pytest.approx(
        1.0, abs=0.01)
    with pytest.raises(ValueError, match="reference"):
        rail_head_wear(y, z, "S49")


def test_orientation_mirrors_and_flips_only() -> None:
    y, z = _head()
    # an instrument writing X towards the gauge side and Y downwards
    x_file, y_file = -y[::-1], -z[::-1]
    yy, zz = orient(x_file, y_file, gauge_at_positive_x=True, y_down=True)
    np.testing.assert_array_equal(yy, y)
    np.testing.assert_array_equal(zz, z)


def test_upper_envelope_hides_an_undercut() -> None:
    # a gauge face that overhangs: the lower face (y = -34) sits inside the upper (y = -36)
    y = np.array([-34.0, -34.0, -36.0, -36.0, -30.0, 0.0, 30.0, 36.0, 36.0])
    z = np.array([-30.0, -20.0, -16.0, -10.0, -4.0, 0.0, -4.0, -10.0, -30.0])
    ye, ze = upper_envelope(y, z)
    assert np.all(np.diff(ye) > 0)
    assert -34.0 not in ye  # the undercut face is not reachable from above


def test_measured_60e1_points_reproduce_the_nominal_contact() -> None:
    """Property: the nominal head given as points is the nominal head to the contact model."""
    y, z = _head(0.1)
    rail = MeasuredRail("60E1 points", y, z)
    yc, zc = rail.contact_points(0.2, 1.0 / 40.0)
    yn, zn = rail_profile("60E1", 0.2, 1.0 / 40.0)
    zi = np.interp(yn, yc, zc)
    inside = (yn > yc.min() + 1) & (yn < yc.max() - 1) & (zn > -20)
    assert np.max(np.abs(zi[inside] - zn[inside])) < 0.02
    vehicle = vehicle_preset("manchester").with_(rail_profile=rail)
    assert vehicle.rail_profile == MeasuredRail("60E1 points", y.copy(), z.copy())
    assert hash(vehicle) == hash(vehicle_preset("manchester").with_(rail_profile=MeasuredRail(
        "60E1 points", y.copy(), z.copy())))
    with pytest.raises(ValueError, match="rail_profile"):
        vehicle_preset("manchester").with_(rail_profile="S49")


def test_real_rail_files_wear(reference_dir) -> None:
    from wearcast.service.readers.miniprof_rail import read_rail_file

    folder = reference_dir / "miniprof"
    part = read_rail_file((folder / "SNX00500.mpt").read_bytes(), "SNX00500.mpt").parts[1]
    wear = rail_head_wear(*part.rail_frame(), "60E2")
    # a 60E2 drawing whose gauge side below 11 mm is the 1:4 face a switch blade lies on
    assert wear.reference_fits and not wear.placement.fitted
    assert wear.vertical.value_mm == pytest.approx(0.0, abs=0.01)
    assert wear.lateral.value_mm == pytest.approx(1.42, abs=0.02)
    assert wear.corner_45.value_mm == pytest.approx(0.11, abs=0.03)
    low = read_rail_file((folder / "avg_low2.ban").read_bytes(), "avg_low2.ban").parts[0]
    wear = rail_head_wear(*low.rail_frame(), "60E1")
    # a head 76.9 mm wide at the gauge depth: not a 60E1, flagged, the datum fitted and said
    assert wear.placement.fitted and abs(wear.placement.lateral_mm) > 10
    assert not wear.reference_fits
    assert wear.measured_head_width_mm == pytest.approx(76.9, abs=0.2)


def test_polyline_crossings_interpolate_and_count_vertices_once():
    # a zig-zag a = 0, 2, -2, 2, 0 against b = 0, 1, 2, 3, 4: the level a = 0 is met at the
    # first vertex, inside the two sign changes (b = 1.5, 2.5) and at the last vertex
    a = np.array([0.0, 2.0, -2.0, 2.0, 0.0])
    b = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(polyline_crossings(a, b), [0.0, 1.5, 2.5, 4.0])
    # a level between the vertices: a = 1 is crossed at b = 0.5, 1.25, 2.75 and 3.5
    np.testing.assert_allclose(polyline_crossings(a, b, 1.0), [0.5, 1.25, 2.75, 3.5])
    assert polyline_crossings(a, b, 5.0).size == 0


@pytest.mark.parametrize("make, what", [
    (lambda y, z: MeasuredRail("m", y, z), "measured rail"),
    (lambda y, z: WornRail("w", y, z), "worn rail"),
])
def test_measured_and_worn_rails_check_their_points_alike(make, what):
    y = np.linspace(-35.0, 35.0, 12)
    z = -0.01 * y**2
    with pytest.raises(ValueError, match=f"a {what} needs at least 10"):
        make(y[:9], z[:9])
    with pytest.raises(ValueError, match=f"a {what} needs at least 10"):
        make(y, z[:-1])
    z_nan = z.copy()
    z_nan[3] = np.nan
    with pytest.raises(ValueError, match=f"{what} points must be finite"):
        make(y, z_nan)
