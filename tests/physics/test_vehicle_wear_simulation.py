"""Whole-vehicle wear: every wheel, both running directions, averaged as measured."""

import numpy as np
import pandas as pd
import pytest

from wearcast.physics.step_convergence import converge_steps, relative_change
from wearcast.physics.vehicle_wear_simulation import (
    VehicleWearOptions,
    simulate_vehicle_wear,
    vehicle_bogies,
)
from wearcast.physics.vocabulary import CurveClass
from wearcast.statistics.physics_comparison import compare_with_measured

ROUTE = [CurveClass(250.0, 100.0, None, "left", 0.15),
         CurveClass(250.0, 100.0, None, "right", 0.15), CurveClass(None, share=0.7)]
ONE_WAY = [CurveClass(250.0, 100.0, None, "left", 0.3), CurveClass(None, share=0.7)]
KM = 1500.0
STEP = 1.0


@pytest.fixture(scope="module")
def symmetric():
    return simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=KM,
                                 depth_per_step_mm=STEP)


def test_minuetto_has_two_motor_and_two_trailer_bogies():
    bogies = vehicle_bogies("minuetto")
    assert [(b.bogie_type, n) for b, n in bogies] == [("motor", 2), ("trailer", 2)]
    assert all(b.friction == 0.4 for b, _ in vehicle_bogies("minuetto", friction=0.4))


@pytest.mark.slow
def test_reversing_vehicle_on_a_symmetric_route_wears_all_wheels_of_a_bogie_alike(symmetric):
    sim = symmetric
    assert sim.mileage_km[-1] == pytest.approx(KM)
    assert len(sim.wheels) == 8 and sim.weights.sum() == pytest.approx(1.0)
    for bogie in range(2):
        ft = sim.sd_mm[-1, 4 * bogie:4 * bogie + 4]
        assert np.ptp(ft) < 1e-9
    assert sim.mean("sd_mm")[-1] < sim.mean("sd_mm")[0] - 0.01  # the flange wears
    # The mean is the weighted average of the wheels.
    assert sim.mean("qr_mm")[-1] == pytest.approx(float(sim.qr_mm[-1] @ sim.weights))


@pytest.mark.slow
def test_one_direction_wears_the_leading_axle_more_and_the_outer_wheel_only():
    fwd = simulate_vehicle_wear("metro_b", ONE_WAY, law="usfd", mileage_km=KM,
                                depth_per_step_mm=STEP,
                                options=VehicleWearOptions(forward_share=1.0))
    loss = fwd.sd_mm[0] - fwd.sd_mm[-1]
    lab = {w: i for i, w in enumerate(fwd.wheels)}
    # Left curves only: the right wheel is the outer one; axle 1 leads.
    assert loss[lab["motor0-1R"]] > loss[lab["motor0-2R"]]
    assert loss[lab["motor0-1R"]] > loss[lab["motor0-1L"]] + 0.01
    back = simulate_vehicle_wear("metro_b", ONE_WAY, law="usfd", mileage_km=KM,
                                 depth_per_step_mm=STEP,
                                 options=VehicleWearOptions(forward_share=0.0))
    # Reversed: the physical axles swap roles (mirror in the axle index).
    assert back.sd_mm[-1, lab["motor0-2R"]] == pytest.approx(fwd.sd_mm[-1, lab["motor0-1R"]],
                                                             abs=0.02)


@pytest.mark.slow
def test_wear_scale_and_flange_lubrication_act_in_the_right_direction(symmetric):
    base_loss = symmetric.mean("sd_mm")[0] - symmetric.mean("sd_mm")[-1]
    lube = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=KM,
                                 depth_per_step_mm=STEP,
                                 options=VehicleWearOptions(flange_wear_factor=0.3))
    assert lube.mean("sd_mm")[0] - lube.mean("sd_mm")[-1] < 0.8 * base_loss
    with pytest.raises(ValueError, match="forward_share"):
        VehicleWearOptions(forward_share=1.5)


@pytest.mark.slow
def test_the_wear_scale_is_a_change_of_the_mileage_variable():
    # every wear rate x c: the run reaches at m what the scale-1 run reaches at c m, step for
    # step (the adaptive step bounds a depth, so both take the same steps; the physics
    # diagnosis runs its large flange factors at scale 1 / factor on this ground)
    options = {"flange_wear_factor": 2.0}
    plain = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=KM / 2,
                                  depth_per_step_mm=STEP, options=VehicleWearOptions(**options))
    slow = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=KM,
                                 depth_per_step_mm=STEP,
                                 options=VehicleWearOptions(**options, wear_scale=0.5))
    assert len(plain.mileage_km) == len(slow.mileage_km) > 2
    np.testing.assert_allclose(slow.mileage_km, 2.0 * plain.mileage_km, rtol=1e-9)
    np.testing.assert_allclose(slow.profiles_mm, plain.profiles_mm, atol=1e-9)
    np.testing.assert_allclose(slow.mean("sd_mm"), plain.mean("sd_mm"), atol=1e-9)


@pytest.mark.slow
def test_traction_torque_acts_on_the_motor_bogie_only():
    # 0.3 of metro_b's motor-axle adhesion torque (2 mu Q r = 16.0 kN m) over one 200 km step
    # (the same mileage for both runs, so the shared adaptive step does not enter): the motor
    # wheels wear more (the longitudinal creep force takes adhesion the steering needed;
    # measured worn area 2.575 -> 2.756 mm^2, +7.1 %, stop 30), the trailer's wear is bit for
    # bit the same. (Over 1,500 km in 1 mm steps the end Sd also moved the trailer's by up to
    # 0.05 mm through the shared step, and halving the step changed the motor's effect 5x:
    # the end Sd is not the measure to test this on.)
    runs = {torque: simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=200.0,
                                          depth_per_step_mm=STEP,
                                          options=VehicleWearOptions(traction_torque_nm=torque))
            for torque in (None, 4800.0)}
    plain, driven = runs[None], runs[4800.0]
    assert plain.mileage_km.tolist() == driven.mileage_km.tolist() == [0.0, 200.0]

    def worn_area(sim):
        return np.trapezoid(sim.initial_profile_mm - sim.profiles_mm, sim.y_mm, axis=1)

    motor = [i for i, w in enumerate(driven.wheels) if w.startswith("motor")]
    trailer = [i for i, w in enumerate(driven.wheels) if w.startswith("trailer")]
    assert np.all(worn_area(driven)[motor] > 1.03 * worn_area(plain)[motor])
    np.testing.assert_array_equal(driven.profiles_mm[trailer], plain.profiles_mm[trailer])
    with pytest.raises(ValueError, match="traction_torque_nm"):
        VehicleWearOptions(traction_torque_nm=float("nan"))


class _FakeSimulation:
    """A vehicle simulation's comparison interface with a linear FT loss of 1 mm/1000 km."""

    mileage_km = np.array([0.0, 4000.0])

    def mean(self, quantity):
        return np.array([32.5, 28.5]) if quantity == "sd_mm" else np.array([1.0, 1.0])

    def mean_at(self, quantity, km):
        return np.interp(km, self.mileage_km, self.mean(quantity))


def test_comparison_with_measured_series_per_vehicle():
    sim = _FakeSimulation()
    km = np.array([0.0, 1000.0, 2500.0, 0.0, 3000.0])
    ft = sim.mean_at("sd_mm", km)
    measured = pd.DataFrame({"vehicle": ["A", "A", "A", "B", "B"], "distance_km": km,
                             "FT_mm": ft + np.array([0, 0.1, 0.1, 0, -0.2])})
    comp = compare_with_measured(sim, measured)
    a = comp.per_vehicle.set_index("vehicle").loc["A"]
    assert a["bias_mm"] == pytest.approx(-0.2 / 3)
    assert a["rms_mm"] == pytest.approx(np.sqrt(0.02 / 3))
    assert a["simulated_loss_per_1000_km"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="beyond the simulated"):
        compare_with_measured(sim, measured.assign(distance_km=km * 10))


def test_step_convergence_halves_until_the_loss_settles():
    # A toy integration: the end value of x' = -x over 1 with Euler steps h converges as h -> 0.
    def run(h):
        n = int(round(1.0 / h))
        return (1.0 - h) ** n

    result, conv = converge_steps(run, lambda r: {"x": r}, {"x": 1.0}, 0.5, tolerance=0.02,
                                  max_halvings=8, min_loss=1e-3)
    assert conv.converged and conv.steps[0] == 0.5 and len(conv.steps) >= 3
    assert all(c["x"] >= 0 for c in conv.changes)
    assert conv.changes[-1]["x"] < 0.02 <= conv.changes[-2]["x"]
    assert result == pytest.approx(np.exp(-1.0), rel=0.05)
    _, once = converge_steps(run, lambda r: {"x": r}, {"x": 1.0}, 0.5, tolerance=1e-9,
                             max_halvings=1, min_loss=1e-3)
    assert not once.converged and "NOT converged" in once.summary()
    assert relative_change(0.5, 0.51, 1.0, 0.05) == pytest.approx(0.02)


@pytest.mark.slow
def test_converged_run_reports_its_step_check():
    from wearcast.physics.vehicle_wear_simulation import simulate_vehicle_wear_converged

    sim = simulate_vehicle_wear_converged("metro_b", ROUTE, law="usfd", mileage_km=KM,
                                          first_step_mm=2.0, max_halvings=1)
    conv = sim.convergence
    assert conv is not None and conv.steps == (2.0, 1.0)
    assert sim.depth_per_step_mm == 1.0
    assert set(conv.changes[0]) == {"FT", "qR"}
    assert sim.to_dict()["step_convergence"]["steps"] == [2.0, 1.0]


def test_a_run_continues_from_an_earlier_one():
    # metro_b, D_step 1 mm: 1,000 km, then on to 2,000 km. The first part is the short run as
    # it was; the rest goes on wearing. It is not the 2,000 km run step for step: the steps
    # fall elsewhere and the continuation starts its contacts cold (measured when written:
    # FT 32.03 at 2,000 km with 0 contact fallbacks against the direct run's 32.12 with 16
    # fallbacks that kept stale contacts), so only the size of the loss is compared.
    short = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=1000.0,
                                  depth_per_step_mm=1.0)
    longer = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=2000.0,
                                   depth_per_step_mm=1.0, continue_from=short)
    direct = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=2000.0,
                                   depth_per_step_mm=1.0)
    n = short.mileage_km.size
    np.testing.assert_array_equal(longer.mileage_km[:n], short.mileage_km)
    np.testing.assert_array_equal(longer.sd_mm[:n], short.sd_mm)
    assert longer.mileage_km[-1] == pytest.approx(2000.0) and longer.mileage_km.size > n
    assert longer.contact_updates > short.contact_updates
    for q in ("sd_mm", "qr_mm"):
        assert np.all(np.diff(longer.mean(q)[n - 1:]) < 0)
        loss = longer.mean(q)[0] - longer.mean(q)[-1]
        direct_loss = direct.mean(q)[0] - direct.mean(q)[-1]
        assert 0.5 * direct_loss < loss < 2.0 * direct_loss
    with pytest.raises(ValueError, match="continue_from"):
        simulate_vehicle_wear("metro_b", ROUTE, law="archard_kth", mileage_km=2000.0,
                              continue_from=short)


def test_runs_sharing_a_contact_cache_solve_the_new_profile_once(monkeypatch):
    # Two runs that differ only in the wear (flange factor): the second reuses the first's
    # first contact update of each bogie and ends exactly where it ends without the cache.
    from wearcast.physics import vehicle_wear_simulation as vws

    cache: dict = {}
    lube = VehicleWearOptions(flange_wear_factor=0.5)
    plain = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=500.0,
                                  depth_per_step_mm=STEP, contact_cache=cache)
    assert len(cache) == 2 and plain.contact_fallbacks == 0  # motor and trailer bogie
    solves = {"n": 0}
    real = vws.class_contacts_all_wheels

    def counted(*a, **k):
        solves["n"] += 1
        return real(*a, **k)

    monkeypatch.setattr(vws, "class_contacts_all_wheels", counted)
    cached = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=500.0,
                                   depth_per_step_mm=STEP, options=lube, contact_cache=cache)
    assert solves["n"] == cached.contact_updates - 2 and len(cache) == 2
    solves["n"] = 0
    fresh = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=500.0,
                                  depth_per_step_mm=STEP, options=lube)
    assert solves["n"] == fresh.contact_updates
    np.testing.assert_array_equal(cached.mileage_km, fresh.mileage_km)
    for q in ("sd_mm", "sh_mm", "qr_mm"):
        np.testing.assert_array_equal(getattr(cached, q), getattr(fresh, q))
    np.testing.assert_array_equal(cached.profiles_mm, fresh.profiles_mm)


@pytest.mark.parametrize("law", ["usfd", "archard_kth"])
def test_flange_factor_basis_from_one_spread_equals_the_per_slot_solves(law):
    # The flange-factor wear (_scaled_basis) takes every slot's depth from one volume basis
    # and one semi-elliptic spread (wheel_depth_basis_by_slot): bit for bit the depth of
    # wheel_depth_basis on the contacts with only that slot in contact, as it was computed.
    from dataclasses import replace

    from wearcast.physics import vehicle_wear_simulation as vws
    from wearcast.physics.patch_wear import wheel_depth_basis, wheel_depth_basis_by_slot
    from wearcast.physics.profiles.s1002 import s1002_height_mm
    from wearcast.physics.wear_laws import WearLaw

    bogie = vehicle_bogies("metro_b")[0][0]
    lo, hi, h = vws.WHEEL_GRID_MM
    y = np.linspace(lo, hi, int(round((hi - lo) / h)) + 1)
    # 150 m: flange patches; 1000 m: a two-point tread contact of the leading high-rail wheel
    sharp = [*ROUTE, CurveClass(150.0, 60.0, None, "left", 0.1),
             CurveClass(1000.0, 0.0, None, "left", 0.1)]
    contacts, _ = vws.class_contacts_all_wheels(bogie, sharp, y, s1002_height_mm(y))
    wl = WearLaw(name=law)
    # flange patches (the factor acts) and a two-point contact (several slots) among them
    assert any(np.any(c.in_contact & (c.contact_angle_rad > vws.FLANGE_ANGLE_RAD))
               for c in contacts.values())
    assert any(np.any(c.in_contact.sum(axis=1) > 1) for c in contacts.values())
    factor_of = {}
    for wheel, c in contacts.items():
        by_slot = wheel_depth_basis_by_slot(c, wl, y)
        for slot in range(c.in_contact.shape[1]):
            only = np.zeros_like(c.in_contact)
            only[:, slot] = c.in_contact[:, slot]
            np.testing.assert_array_equal(
                by_slot[slot], wheel_depth_basis(replace(c, in_contact=only), wl, y))
        factor_of[wheel] = np.where(c.contact_angle_rad > vws.FLANGE_ANGLE_RAD, 0.5, 1.0)
        scaled = vws._scaled_basis(c, wl, y, "global", 20, bogie.friction, factor_of[wheel])
        local = vws._scaled_basis(c, wl, y, "local", 20, bogie.friction, factor_of[wheel])
        assert np.all(np.isfinite(local)) and scaled.shape == local.shape
        np.testing.assert_array_equal(scaled, sum(
            by_slot[s] * factor_of[wheel][:, s][:, None, None]
            for s in range(c.in_contact.shape[1])))


def test_a_non_finite_contact_is_named_before_it_reaches_a_profile(monkeypatch):
    # A contact update whose patch is not finite (e.g. a NaN semi-axis of a failed solve)
    # must stop the run naming the wheels and the reason, not hand a NaN step to every wheel.
    from dataclasses import replace

    from wearcast.physics import vehicle_wear_simulation as vws
    from wearcast.physics.wear_loop import WearLoopDivergedError

    real = vws.class_contacts_all_wheels
    calls = {"n": 0}

    def broken_on_second_update(*args, **kwargs):
        out, fb = real(*args, **kwargs)
        calls["n"] += 1
        if calls["n"] == 3:  # the motor bogie's second update (one motor, one trailer)
            c = out[(1, "right")]
            out[(1, "right")] = replace(c, b_mm=np.where(c.in_contact, np.nan, c.b_mm))
        return out, fb

    monkeypatch.setattr(vws, "class_contacts_all_wheels", broken_on_second_update)
    with pytest.raises(WearLoopDivergedError, match=r"non-finite wear rate of motor0-1R"):
        simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=KM,
                              depth_per_step_mm=STEP, options=VehicleWearOptions(
                                  forward_share=1.0))


def test_a_wheel_worn_beyond_its_rim_is_named_with_where(monkeypatch):
    from wearcast.physics import vehicle_wear_simulation as vws
    from wearcast.physics.wear_loop import MAX_WHEEL_WEAR_MM, WearLoopDivergedError

    # on the tread (y -11..-9 mm, nearly flat) the depth normal to the new profile is the
    # vertical 41 mm; on the flange face the same vertical drop is a smaller normal depth
    # (wear_distribution.depth_below_mm), so a flank band would be named only later
    def runaway(y, z, depth):
        return z - np.where(np.abs(y + 10.0) < 1.0, MAX_WHEEL_WEAR_MM + 1.0, 0.0)

    monkeypatch.setattr(vws, "apply_normal_wear", runaway)
    with pytest.raises(WearLoopDivergedError, match=r"motor0-1L worn 4[01](\.\d)? mm below the new "
                                                     r"profile at y = -(9|10|11)\.\d mm"):
        simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=KM,
                              depth_per_step_mm=STEP)


def test_a_run_with_its_last_step_whole_is_the_first_part_of_a_longer_run():
    # cut_last_step=False: the run ends at the first step at or beyond its mileage, so it is
    # step for step the longer run up to there (the physics diagnosis reads runs to a mileage
    # and needs them to be the longer runs' there); the cut run's last point is not.
    whole = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=500.0,
                                  depth_per_step_mm=STEP, cut_last_step=False)
    longer = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=1500.0,
                                   depth_per_step_mm=STEP)
    n = whole.mileage_km.size
    assert whole.mileage_km[-1] >= 500.0 and whole.mileage_km[-2] < 500.0
    assert longer.mileage_km[-1] > whole.mileage_km[-1]
    np.testing.assert_array_equal(longer.mileage_km[:n], whole.mileage_km)
    for q in ("sd_mm", "sh_mm", "qr_mm"):
        np.testing.assert_array_equal(getattr(longer, q)[:n], getattr(whole, q))
    cut = simulate_vehicle_wear("metro_b", ROUTE, law="usfd", mileage_km=500.0,
                                depth_per_step_mm=STEP)
    assert cut.mileage_km[-1] == pytest.approx(500.0)
    np.testing.assert_array_equal(cut.mileage_km[:-1], whole.mileage_km[:-1])
