"""The bogie's equilibrium with the contact pipeline's own forces
(``pipeline_equilibrium.pipeline_force_equilibrium``: homotopy from the table's equilibrium) and
the wear tables built on it (``wear_tables``' ``contact_model="pipeline_equilibrium"``), issue 11.
"""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.physics import curving as cv
from wearcast.physics import wear_tables as wt
from wearcast.physics.curving_table import vehicle_contact_table
from wearcast.physics.pipeline_equilibrium import pipeline_residual
from wearcast.physics.vehicles import vehicle_preset

#: State entries mirrored by a left/right exchange: shift, yaw, (rolling ratio even),
#: approaches exchanged, bogie shift and yaw.
_MIRROR_SIGN = np.array([-1.0, -1.0, 1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0, 1.0, -1.0, -1.0])
_MIRROR_ORDER = [0, 1, 2, 4, 3, 5, 6, 7, 9, 8, 10, 11]


@pytest.fixture(scope="module")
def flanging():
    """The Manchester trailer at 150 m (left curve) and 200 m (left and right curves), the
    radii at which Broyden's method from the table's equilibrium ran off into flange climbing
    (residual 0.12-0.13 wheel loads after 40 iterations)."""
    trailer = vehicle_preset("manchester", "trailer")
    cases = [cv.curve_case(150.0, 0.0, None, "left", 0.58),
             cv.curve_case(200.0, 0.0, None, "left", 0.58),
             cv.curve_case(200.0, 0.0, None, "right", 0.58)]
    return trailer, cases, cv.solve_curving_cases(trailer, cases, contact_pipeline=True,
                                                  pipeline_equilibrium=True)


def test_pipeline_forces_balance_at_the_solution_on_tight_curves(flanging):
    trailer, cases, results = flanging
    table = vehicle_contact_table(trailer)
    for case, res in zip(cases, results, strict=True):
        assert res is not None and res.pipeline is not None
        assert res.pipeline_residual_norm < cv.PIPELINE_TOLERANCE, case
        # the residual evaluated afresh at the returned state, with the pipeline's forces
        params = np.array([[case.curvature_per_m, case.unbalanced_acceleration_m_s2,
                            case.torque_nm]])
        _, _, ok, _, res_p = pipeline_residual(res.pipeline["state"][None, :], trailer, table,
                                               params, cv.DEFAULT_CREEP_GRID,
                                               cv.DEFAULT_CREEP_GRID)
        assert ok[0] and np.linalg.norm(res_p[0]) < cv.PIPELINE_TOLERANCE
        # at the table's pose the same forces are far from balance (0.7-0.9 wheel loads)
        _, _, _, _, res_t = pipeline_residual(res.state[None, :], trailer, table, params,
                                              cv.DEFAULT_CREEP_GRID, cv.DEFAULT_CREEP_GRID)
        assert np.linalg.norm(res_t[0]) > 100 * cv.PIPELINE_TOLERANCE
        # the balanced flange patch of the leading high-rail wheel is centred near the root
        # (measured 47.7-50.8 deg, wheel y -35.4 to -36.0 mm), not up the flank where the
        # table's pose puts it (66-70 deg)
        high = cv.SIDES.index(res.high_rail_side)
        p = res.pipeline
        on = p["in_contact"][0, high] & (p["wheel_y_mm"][0, high] < cv.FLANGE_SPLIT_Y_MM)
        assert np.any(on)
        k = int(np.argmax(np.where(on, p["normal_force_n"][0, high], -1.0)))
        assert p["contact_angle_rad"][0, high, k] < np.radians(55.0)


def test_left_and_right_curves_give_mirrored_pipeline_equilibria(flanging):
    # The model is mirror symmetric: the 200 m right curve's equilibrium is the left curve's
    # with shifts and yaws negated and the wheels exchanged, to the solver's tolerance
    # (residual 1e-3 of the wheel load: measured differences 6e-4 mrad in yaw, 1e-5 in the
    # rolling ratio, 1e-4 mm in the shifts).
    _, _, (_, left, right) = flanging
    assert max(left.pipeline_residual_norm, right.pipeline_residual_norm) < cv.PIPELINE_TOLERANCE
    q_l, q_r = left.pipeline["state"], right.pipeline["state"]
    mirrored = _MIRROR_SIGN * q_r[_MIRROR_ORDER]
    tol = np.array([0.02, 0.05, 0.05, 0.002, 0.002] * 2 + [0.05, 0.05])
    assert np.all(np.abs(mirrored - q_l) < tol), mirrored - q_l
    # and the contacts: the left curve's right (high-rail) wheel is the right curve's left one
    p_l, p_r = left.pipeline, right.pipeline
    np.testing.assert_allclose(p_l["normal_force_n"][:, 1], p_r["normal_force_n"][:, 0],
                               rtol=2e-3, atol=50.0)
    np.testing.assert_allclose(p_l["wheel_y_mm"][:, 1], p_r["wheel_y_mm"][:, 0], atol=0.05)


@pytest.fixture(scope="module")
def metro_tables():
    """metro B on its 475 m class (seed 000 Table 1: 40 km/h, cant 40 mm) and tangent track,
    with the table's contacts and with the pipeline's at its own equilibrium."""
    args = ("metro_b", [None, 475.0], [0.0, 40.0], [70.0, 40.0])
    return (wt.wear_table_for_route(*args, with_contacts=True),
            wt.wear_table_for_route(*args, with_contacts=True,
                                    contact_model="pipeline_equilibrium"))


def test_balanced_pipeline_agrees_with_the_table_where_both_are_hertzian_on_the_tread(
        metro_tables):
    """The trailer's leading low-rail tread patch at 475 m is solved by Hertz in the pipeline
    (peak pressure = 3 Fn / (2 pi a b)) as in the table. At the pipeline's own equilibrium
    (wheelset shift 0.05 mm from the table's, pressure centre 0.35 mm field-wards of the
    table's patch) it agrees with the table's: measured Fn 0.02 %, a 0.4 %, b 1.2 %, p0 and
    tau_max 0.8 %, T-gamma 2.5 % (stop 33, the table's contact angle from the wheel's slope
    averaged over its 2 mm Gaussian, ``curving_table.ContactTable``: 0.54 against the
    pipeline's 0.50 deg; with the slope at the point, 0.50 deg: Fn 0.0 %, a 0.3 %, b 1.0 %,
    p0 and tau_max 0.7 %, T-gamma 0.7 %); tolerance 1.5 %, T-gamma 3 %."""
    (_, contacts), (table, pipe_contacts) = metro_tables
    assert list(table.columns) == wt.TABLE_COLUMNS
    assert np.isfinite(table["value"]).all() and (table["value"] >= 0).all()

    def patch(c):
        rows = c[(c.radius_m == 475.0) & (c.bogie_type == "trailer")
                 & (c.wheelset == "leading") & (c.rail == "low") & c.in_contact]
        assert len(rows) == 1
        return rows.iloc[0]

    t, p = patch(contacts), patch(pipe_contacts)
    assert t.region == p.region == "tread"
    assert p.p0_mpa == pytest.approx(1.5 * p.normal_force_n / (np.pi * p.a_mm * p.b_mm),
                                     rel=1e-3), "the pipeline's patch is Hertz"
    assert p.wheelset_shift_mm != t.wheelset_shift_mm  # the pipeline's own pose
    assert abs(p.wheelset_shift_mm - t.wheelset_shift_mm) < 0.3
    for col in ("normal_force_n", "a_mm", "b_mm", "p0_mpa", "tau_max_mpa"):
        assert p[col] == pytest.approx(t[col], rel=0.015), col
    assert p.t_gamma_n == pytest.approx(t.t_gamma_n, rel=0.03)


def test_balanced_pipeline_flange_patch_is_on_the_root(metro_tables):
    # At 475 m the leading high-rail wheel flanges in both models; with the pipeline's forces
    # balanced its flange patch lies at the root (wheel y within 0.5 mm of the table's patch),
    # and every wheel carries its vertical load.
    (_, contacts), (_, pipe_contacts) = metro_tables
    for bogie in ("motor", "trailer"):
        sel = [(c.radius_m == 475.0) & (c.bogie_type == bogie) & (c.wheelset == "leading")
               & (c.rail == "high") & c.in_contact & (c.region == "flange")
               for c in (contacts, pipe_contacts)]
        t, p = contacts[sel[0]], pipe_contacts[sel[1]]
        assert len(t) == len(p) == 1, bogie
        assert abs(p.wheel_y_mm.iloc[0] - t.wheel_y_mm.iloc[0]) < 0.5, bogie
        assert p.contact_angle_rad.iloc[0] < np.radians(50.0), bogie


def test_balanced_pipeline_on_tangent_track_is_centred_and_symmetric(metro_tables):
    # tangent track: the pipeline's equilibrium keeps the wheelsets centred, and the left and
    # right wheels' contacts are the same
    _, (_, pipe_contacts) = metro_tables
    tangent = pipe_contacts[pipe_contacts.radius_m.isna()]
    assert len(tangent) > 0
    assert (tangent.wheelset_shift_mm.abs() < 1e-6).all()
    assert (tangent.wheelset_yaw_rad.abs() < 1e-9).all()
    cols = ["normal_force_n", "wheel_y_mm", "contact_angle_rad", "xi", "tau_max_mpa",
            "t_gamma_n"]
    for (_, _), wheelset in tangent.groupby(["bogie_type", "axle"]):
        left = wheelset[wheelset.side == "left"].sort_values("patch")[cols].to_numpy()
        right = wheelset[wheelset.side == "right"].sort_values("patch")[cols].to_numpy()
        np.testing.assert_allclose(left, right, rtol=1e-6, atol=1e-9)
