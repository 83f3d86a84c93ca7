"""The curving contact with a rail profile per side (a high and a low rail of their own)."""

from dataclasses import fields, replace

import numpy as np
import pytest

from wearcast.physics.bogie_equations import (
    bogie_contacts,
    bogie_residual,
    compiled_residual,
    initial_state,
    wheelset_roll,
)
from wearcast.physics.class_contacts import class_contacts_all_wheels
from wearcast.physics.curving import (
    build_contact_table,
    curve_case,
    solve_curving,
    solve_curving_cases_or_none,
)
from wearcast.physics.curving_table import track_rails, vehicle_contact_table
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.rail_head_wear import wear_rail
from wearcast.physics.vehicles import vehicle_preset
from wearcast.physics.vocabulary import CurveClass
from wearcast.physics.wear_loop import RAIL_GRID_MM, WHEEL_GRID_MM, _grid

INCLINATION = 1.0 / 40.0
GRID = _grid(RAIL_GRID_MM)
#: A high rail worn 1 mm on its gauge corner and a low rail worn 0.5 mm on its crown.
HIGH = wear_rail("60E1", GRID, 1.0 * np.exp(-0.5 * ((GRID + 31.0) / 3.0) ** 2), INCLINATION,
                 name="high")
LOW = wear_rail("60E1", GRID, np.where(np.abs(GRID) < 20.0, 0.5, 0.0), INCLINATION, name="low")
#: The result fields compared (per contact: wheelset, side, slot; per wheelset: wheelset).
CONTACT_FIELDS = ("normal_force_n", "contact_angle_rad", "xi", "eta", "phi_per_mm", "fx_n",
                  "fy_n", "mz_nmm", "a_mm", "b_mm", "rolling_radius_m", "wheel_y_mm",
                  "rail_y_mm", "tau_max_mpa", "t_gamma_n")


@pytest.fixture(scope="module")
def tables():
    r0 = vehicle_preset("metro_b").wheel_radius_m
    same = build_contact_table(None, "60E1", INCLINATION, r0)
    pair = build_contact_table(None, "60E1", INCLINATION, r0, rail_right=HIGH)
    return same, pair


def test_one_rail_on_both_sides_is_the_mirrored_table_bit_for_bit(tables):
    same, _ = tables
    given = build_contact_table(None, "60E1", INCLINATION, same.nominal_radius_m,
                                rail_right="60E1")
    assert given.right is None and same.right is None
    for f in ("gap_mm", "gap2_per_mm", "rigid_rise_mm", "hertz_a1"):
        assert np.array_equal(getattr(given, f), getattr(same, f))
    assert build_contact_table(None, HIGH, INCLINATION, rail_right=HIGH).right is None


def test_the_per_side_path_with_one_rail_twice_gives_the_same_numbers_bit_for_bit(tables):
    # A table pair whose right table is built separately from the same rail goes through
    # every per-side branch (candidates per side, rigid rise per side, the kernel's right
    # table and memory, the initial approaches) and must give today's numbers exactly.
    same, _ = tables
    veh = vehicle_preset("metro_b")
    pair = replace(same, right=build_contact_table(None, "60E1", INCLINATION,
                                                   veh.wheel_radius_m))
    rng = np.random.default_rng(12)
    q = initial_state(veh, same) + rng.normal(0.0, 0.3, (5, 12))
    kappa, a_unb, torque = 1.0 / 300.0, 0.4, 0.0
    assert np.array_equal(initial_state(veh, same), initial_state(veh, pair))
    for grid in (None, 8):
        assert np.array_equal(bogie_residual(q, veh, same, kappa, a_unb, torque,
                                             creep_grid=grid),
                              bogie_residual(q, veh, pair, kappa, a_unb, torque,
                                             creep_grid=grid))
        assert np.array_equal(compiled_residual(q, veh, same, kappa, a_unb, torque, grid),
                              compiled_residual(q, veh, pair, kappa, a_unb, torque, grid))
    cases = [curve_case(300.0, 60.0, direction="left"), curve_case(500.0, 0.0,
                                                                   direction="right"),
             curve_case(None)]
    a = solve_curving_cases_or_none(veh, cases, table=same)
    b = solve_curving_cases_or_none(veh, cases, table=pair)
    for ra, rb in zip(a, b, strict=True):
        assert ra is not None and rb is not None
        assert np.array_equal(ra.state, rb.state)
        for f in CONTACT_FIELDS:
            assert np.array_equal(getattr(ra, f), getattr(rb, f)), f


def _mirror(result, name):
    """A right curve's field seen as the mirrored left curve's: sides exchanged, lateral
    quantities of the wheelsets negated (the per-contact ones are in each wheel's own frame)."""
    v = np.asarray(getattr(result, name))
    if name in ("wheelset_shift_mm", "wheelset_yaw_rad", "wheelset_roll_rad",
                "contact_shift_mm"):
        return -v
    if name in ("bogie_shift_mm", "bogie_yaw_rad"):
        return -v
    return v[:, ::-1]


def test_a_left_curve_on_a_b_is_the_mirrored_right_curve_on_b_a(tables):
    _, pair = tables  # left rail 60E1, right rail HIGH
    veh = vehicle_preset("metro_b")
    left = solve_curving(veh, 300.0, 60.0, direction="left", table=pair)
    right = solve_curving(veh, 300.0, 60.0, direction="right", table=pair.mirrored())
    swapped = pair.mirrored()
    assert pair.right is not None and swapped.right is not None
    assert np.array_equal(swapped.gap_mm, pair.right.gap_mm)
    assert np.array_equal(swapped.side(1).gap_mm, pair.gap_mm)
    for f in ("wheelset_shift_mm", "wheelset_yaw_rad", "wheelset_roll_rad", "bogie_shift_mm",
              "bogie_yaw_rad"):
        assert np.allclose(getattr(left, f), _mirror(right, f), rtol=1e-6, atol=1e-9), f
    for f in CONTACT_FIELDS:
        scale = max(1.0, float(np.max(np.abs(getattr(left, f)))))
        assert np.allclose(getattr(left, f), _mirror(right, f), rtol=0, atol=1e-6 * scale), f
    # ... and the rail under the outer wheel matters: on the symmetric 60E1 track the outer
    # (right) wheel of the leading axle touches elsewhere on its rail.
    plain = solve_curving(veh, 300.0, 60.0, direction="left", table=tables[0])
    loaded = left.normal_force_n[0, 1] > 1.0
    assert np.max(np.abs(left.rail_y_mm[0, 1][loaded]
                         - plain.rail_y_mm[0, 1][plain.normal_force_n[0, 1] > 1.0][:1])) > 0.05
    assert not np.allclose(left.normal_force_n, plain.normal_force_n, rtol=1e-3)


def test_the_vehicle_puts_the_high_rail_outside_in_both_directions(tables):
    _, pair = tables
    veh = replace(vehicle_preset("metro_b"), high_rail_profile=HIGH)
    assert track_rails(veh, "left") == ("60E1", HIGH)
    assert track_rails(veh, "right") == (HIGH, "60E1")
    assert track_rails(veh, None) == ("60E1", "60E1")
    assert vehicle_contact_table(veh, None).right is None
    assert vehicle_contact_table(veh, "right").right is not None
    by_vehicle = solve_curving(veh, 300.0, 60.0, direction="left")
    by_table = solve_curving(veh, 300.0, 60.0, direction="left", table=pair)
    assert np.array_equal(by_vehicle.state, by_table.state)
    right = solve_curving(veh, 300.0, 60.0, direction="right")
    assert np.allclose(right.wheelset_shift_mm, -by_vehicle.wheelset_shift_mm, atol=1e-6)
    with pytest.raises(ValueError, match="high_rail_profile"):
        replace(vehicle_preset("metro_b"), high_rail_profile="UIC54")


def test_class_contacts_take_each_wheels_own_rail():
    veh = vehicle_preset("metro_b")
    y = _grid(WHEEL_GRID_MM)
    z = s1002_height_mm(y)
    curves = [CurveClass(300.0, 100.0, None, "left", 0.15),
              CurveClass(300.0, 100.0, None, "right", 0.15), CurveClass(None, share=0.7)]
    plain, _ = class_contacts_all_wheels(veh, curves, y, z)
    # the same rail named as high and low: one table, the same numbers
    named, _ = class_contacts_all_wheels(
        replace(veh, high_rail_profile="60E1", low_rail_profile="60E1"), curves, y, z)
    for w in plain:
        for f in fields(plain[w]):
            if f.name not in ("rail_axles", "states"):
                assert np.array_equal(getattr(plain[w], f.name), getattr(named[w], f.name))
    sided, fb = class_contacts_all_wheels(
        replace(veh, high_rail_profile=HIGH, low_rail_profile=LOW), curves, y, z,
        patch_width="kik_piotrowski")
    assert fb == 0
    # The high-rail wheel of the left curve is the right wheel, of the right curve the left
    # wheel: both see HIGH, so the mirror gives them the same contacts.
    for axle in (1, 2):
        a, b = sided[(axle, "right")], sided[(axle, "left")]
        assert np.allclose(a.normal_force_n[0], b.normal_force_n[1], rtol=1e-9)
        assert np.allclose(a.rail_y_mm[0], b.rail_y_mm[1], atol=1e-9)
    # tangent track stays on rail_profile on both sides: as without the high and low rails
    for w in plain:
        assert np.array_equal(plain[w].normal_force_n[2], sided[w].normal_force_n[2])
    # in the curves the worn rails change the contacts
    assert not np.allclose(plain[(1, "right")].normal_force_n[0],
                           sided[(1, "right")].normal_force_n[0], rtol=1e-3)


def test_each_wheel_takes_its_own_rails_table_in_numpy_and_in_the_kernel(tables):
    # The mirror test cannot tell a consistent swap of the two tables: here each wheel's
    # candidates are checked against its own table, and the compiled residual against numpy.
    _, pair = tables
    assert pair.right is not None
    assert not np.allclose(pair.gap_mm, pair.right.gap_mm, atol=0.05)
    veh = vehicle_preset("metro_b")
    rng = np.random.default_rng(11)
    q = initial_state(veh, pair) + rng.normal(0.0, 0.5, (4, 12))
    q[:, 0] = [-6.0, -3.0, 2.0, 5.0]  # leading wheelset shifts [mm] (+ left)
    y = q[:, [0, 5]]
    c = bogie_contacts(pair, y, q[:, [1, 6]] * 1e-3, q[:, [2, 7]] * 1e-3,
                       q[:, [3, 4, 8, 9]].reshape(4, 2, 2), np.full(4, 1.0 / 300.0),
                       pair.nominal_radius_m, veh.friction)
    left, right = pair.candidates(y[:, 0]), pair.right.candidates(-y[:, 0])
    assert np.array_equal(c.rail_y_mm[:, 0, 0], left["rail_y_mm"])
    assert np.array_equal(c.rail_y_mm[:, 0, 1], right["rail_y_mm"])
    assert np.array_equal(c.contact_angle_rad[:, 0, 1], right["angle_rad"])
    for grid in (None, 8):
        ref = bogie_residual(q, veh, pair, 1.0 / 300.0, 0.4, 0.0, creep_grid=grid)
        assert np.allclose(compiled_residual(q, veh, pair, 1.0 / 300.0, 0.4, 0.0, grid), ref,
                           rtol=1e-9, atol=1e-10)
    # the right wheel's rigid rise is its own table's
    d = q[:, 3:5]
    expected = (pair.rigid_rise(y[:, 0]) - d[:, 0] - pair.right.rigid_rise(-y[:, 0]) + d[:, 1]
                ) / 1500.0
    # to rounding (the sums are grouped differently); the two tables' rises differ by far more
    np.testing.assert_allclose(wheelset_roll(pair, y[:, 0], d), expected, rtol=1e-12, atol=0.0)


def test_the_whole_vehicle_runs_with_a_high_and_a_low_rail():
    from wearcast.physics.vehicle_wear_simulation import (
        VehicleWearOptions,
        simulate_vehicle_wear,
        vehicle_bogies,
    )

    curves = [CurveClass(300.0, 100.0, None, "left", 0.5),
              CurveClass(300.0, 100.0, None, "right", 0.5)]
    kwargs = {"law": "usfd", "mileage_km": 100.0, "depth_per_step_mm": 1.0}
    plain = simulate_vehicle_wear("metro_b", curves, **kwargs)
    same = simulate_vehicle_wear("metro_b", curves, options=VehicleWearOptions(
        high_rail="60E1", low_rail="60E1"), **kwargs)
    assert np.array_equal(plain.profiles_mm, same.profiles_mm)
    sided = simulate_vehicle_wear("metro_b", curves, options=VehicleWearOptions(
        high_rail=HIGH, low_rail=LOW), **kwargs)
    direct = simulate_vehicle_wear(
        [(replace(b, high_rail_profile=HIGH, low_rail_profile=LOW), n)
         for b, n in vehicle_bogies("metro_b")], curves, **kwargs)
    assert np.array_equal(sided.profiles_mm, direct.profiles_mm)
    assert np.max(np.abs(sided.profiles_mm - plain.profiles_mm)) > 1e-3
