"""The rigid roll solve of the curving table (``contact.geometry._solve_roll`` through
``rigid_wheel_gap``): Newton with the exact roll rate of the parabola-refined minimum gap
(``min_gap_kernel.refined_minimum_rate``) finds the root a bisection finds, and the compiled gap
rows (``min_gap_kernel.gap_rows_no_yaw``) are ``geometry._gaps``'s, on S1002 and a measured
MiniProf wheel on 60E1."""

import numpy as np
import pytest

from wearcast.physics.contact import geometry as geo
from wearcast.physics.contact.min_gap_kernel import gap_rows_no_yaw
from wearcast.physics.contact.track_profiles import wheel_curve_from_height, wheelset_track
from wearcast.physics.profiles.s1002 import s1002_height_mm

#: The table's centre shifts (``curving_table._side_table``: +-16 mm by 0.1 mm).
CENTRE_SHIFTS_MM = np.arange(-16.0, 16.0 + 1e-9, 0.1)


def _tracks(reference_dir):
    from wearcast.physics.profiles.measured_wheel import MeasuredWheel
    from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame

    path = reference_dir / "miniprof" / "Car7216_0001r.whl"
    y, z = to_wheel_frame(parse_miniprof(path.read_bytes(), path.name))
    measured = MeasuredWheel(path.stem, y, z)
    return {
        "S1002": wheelset_track(wheel_curve_from_height(s1002_height_mm, (-55.0, 45.0)),
                                "60E1", 1.0 / 40.0, 460.0),
        # as the curving table builds a measured wheel's track (measured_wheel_table_for)
        path.stem: wheelset_track(wheel_curve_from_height(measured.height_mm,
                                                          measured.search_range_mm),
                                  "60E1", 1.0 / 40.0, 460.0),
    }


@pytest.fixture(scope="module")
def tracks():
    from tests.conftest import REFERENCE_DIR

    if not REFERENCE_DIR.is_dir():
        pytest.skip(f"reference data not found at {REFERENCE_DIR} (needs ../shared beside "
                    "the repo)")
    return _tracks(REFERENCE_DIR)


def _bisection_roll(sides, shift, iterations=70):
    """The root of g_left - g_right in the roll by bisection on [-0.1, 0.1] rad from the
    numpy minimum gaps (``_min_gap_numpy``; no derivative used)."""
    lo, hi = np.full(shift.size, -0.1), np.full(shift.size, 0.1)
    yaw = np.zeros(shift.size)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        f = (geo._min_gap_numpy(sides[0], shift, mid, yaw, 460.0)[0]
             - geo._min_gap_numpy(sides[1], shift, mid, yaw, 460.0)[0])
        lo, hi = np.where(f <= 0, mid, lo), np.where(f > 0, mid, hi)
    return 0.5 * (lo + hi)


def test_gap_rows_kernel_equals_the_numpy_gaps(tracks):
    rng = np.random.default_rng(3)
    shift = rng.uniform(-17.0, 17.0, 200)
    roll = rng.uniform(-0.02, 0.02, 200)
    for wt in tracks.values():
        for side in geo._prepare(wt):
            ref, _ = geo._gaps(side, shift, roll, np.zeros(200), 460.0)
            got, _ = gap_rows_no_yaw(side.y_ws, side.z_ws, side.rail_y, side.rail_z, shift,
                                     np.cos(roll), np.sin(roll), 460.0, np.zeros(200),
                                     (0.0, 0.0), False)
            assert np.isinf(ref).any() and np.isfinite(ref).any()
            np.testing.assert_array_equal(got, ref)


def test_roll_rate_is_the_derivative_of_the_refined_minimum(tracks):
    # central differences of the refined minimum over +-1e-8 rad (the minimum's samples and
    # rail intervals stay put for nearly every pose): the exact rate agrees to ~2e-9 (median
    # relative error); the former derivative, the rate of the minimum's sample alone (the
    # refined vertex lies between samples), is off by a median 3e-4 on these poses
    rng = np.random.default_rng(5)
    shift = rng.uniform(-12.0, 12.0, 400)
    roll = rng.uniform(-0.005, 0.005, 400)
    h = 1e-8
    yaw = np.zeros(400)
    for wt in tracks.values():
        for side in geo._prepare(wt):
            value, rate = geo._min_gap(side, shift, roll, yaw, 460.0)
            up = geo._min_gap(side, shift, roll + h, yaw, 460.0)[0]
            down = geo._min_gap(side, shift, roll - h, yaw, 460.0)[0]
            numeric = (up - down) / (2.0 * h)
            err = np.abs(rate - numeric) / np.maximum(np.abs(numeric), 1.0)
            assert np.median(err) < 1e-6
            assert np.mean(err < 1e-4) > 0.95
            # the numpy reference gives the same rate
            ref = geo._min_gap_numpy(side, shift, roll, yaw, 460.0)[1]
            np.testing.assert_allclose(rate, ref, rtol=1e-10, atol=1e-10)


def test_rigid_roll_is_the_bisection_root_and_the_gaps_follow(tracks):
    # the Newton solve (tol 1e-9 mm on g_left - g_right) lands within 1e-11 rad of the
    # bisection root on every table shift, so the table's gap rows differ from those at the
    # bisection root by < 1e-7 mm where the gap is below 5 mm (r x droll over the wheel);
    # the old Newton (the sample's rate) found the same root to the same tolerance
    sub = CENTRE_SHIFTS_MM[::4]
    for name, wt in tracks.items():
        sides = geo._prepare(wt)
        y, gap, roll = geo.rigid_wheel_gap(wt, CENTRE_SHIFTS_MM)
        ref = _bisection_roll(sides, sub)
        np.testing.assert_allclose(roll[::4], ref, rtol=0.0, atol=1e-11, err_msg=name)
        yaw = np.zeros(sub.size)
        g_l, _ = geo._min_gap_numpy(sides[0], sub, roll[::4], yaw, 460.0)
        g_r, _ = geo._min_gap_numpy(sides[1], sub, roll[::4], yaw, 460.0)
        assert np.max(np.abs(g_l - g_r)) < 1e-9
        ref_gap, _ = geo._gaps(sides[0], sub, ref, yaw, 460.0)
        g_ref_l = geo._min_gap_numpy(sides[0], sub, ref, yaw, 460.0)[0]
        g_ref_r = geo._min_gap_numpy(sides[1], sub, ref, yaw, 460.0)[0]
        ref_gap = ref_gap - 0.5 * (g_ref_l + g_ref_r)[:, None]
        near = np.isfinite(ref_gap) & (ref_gap < 5.0)
        assert near.sum() > 1000
        np.testing.assert_allclose(gap[::4][near], ref_gap[near], rtol=0.0, atol=1e-7,
                                   err_msg=name)


def test_roll_solve_newton_passes(tracks, monkeypatch):
    # with the exact rate the solve (coarse and fine) evaluates each shift's minimum gaps 3.3
    # times on S1002 and 3.1 on the MiniProf wheel (4.4 and 4.2 with the former derivative,
    # the rate of the minimum's sample): count the rows evaluated
    rows = []
    kernel = geo._min_gap

    def counting(side, shift, roll, yaw, r0):
        rows.append(shift.size)
        return kernel(side, shift, roll, yaw, r0)

    monkeypatch.setattr(geo, "_min_gap", counting)
    for name, wt in tracks.items():
        rows.clear()
        geo.rigid_wheel_gap(wt, CENTRE_SHIFTS_MM)
        per_shift = sum(rows[::2]) / CENTRE_SHIFTS_MM.size
        assert per_shift < 3.8, (name, per_shift)
