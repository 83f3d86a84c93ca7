"""Rail wear fed back into the contact (seed 003 §4.3, §6.1): worn rail, attribution, rail steps."""

from dataclasses import replace

import numpy as np
import pytest

from wearcast.physics.class_contacts import class_contacts_all_wheels
from wearcast.physics.curving import build_contact_table
from wearcast.physics.patch_wear import contact_volume_basis, law_coefficients, wheel_depth_basis
from wearcast.physics.profiles.rails import rail_profile
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.rail_feedback import simulate_rail_steps
from wearcast.physics.rail_head_wear import WornRail, wear_rail
from wearcast.physics.rail_wear_per_vehicle import rail_depth_per_vehicle_all_wheels
from wearcast.physics.vehicles import vehicle_preset
from wearcast.physics.vocabulary import CurveClass
from wearcast.physics.wear_distribution import Smoothing
from wearcast.physics.wear_laws import ArchardKTH, WearLaw
from wearcast.physics.wear_loop import RAIL_GRID_MM, WHEEL_GRID_MM, WearSteps, _grid, simulate_wear

INCLINATION = 1.0 / 40.0
GRID = _grid(RAIL_GRID_MM)
CURVES = [CurveClass(300.0, 100.0, None, "left", 0.15),
          CurveClass(300.0, 100.0, None, "right", 0.15), CurveClass(None, share=0.7)]


def _arc_integral(rail, depth_on_grid: np.ndarray) -> float:
    """Integral of a normal depth along the inclined head's arc [mm^2]."""
    y, z = rail_profile(rail, 0.05, INCLINATION)
    d = np.interp(y, GRID, depth_on_grid, left=0.0, right=0.0)
    ds = np.hypot(np.diff(y), np.diff(z))
    return float(np.sum(0.5 * (d[1:] + d[:-1]) * ds))


def test_an_unworn_worn_rail_is_the_named_rail_in_the_contact_table():
    r0 = wear_rail("60E1", GRID, np.zeros_like(GRID), INCLINATION)
    named = build_contact_table(None, "60E1", INCLINATION)
    worn = build_contact_table(None, r0, INCLINATION)
    # the table comes from the rigid geometry with an iterated roll: points equal to ~1e-8 mm
    # give gaps equal to ~1e-4 mm where the flange climbs (the roll is steep in the shift there)
    assert np.max(np.abs(named.gap_mm - worn.gap_mm)) < 1e-3
    assert worn.rail_offset_mm == pytest.approx(named.rail_offset_mm, abs=1e-6)
    hw = r0.head_wear()
    assert hw.reference_fits
    for m in (hw.vertical, hw.lateral, hw.corner_45):
        assert abs(m.value_mm) < 1e-3
    assert r0.area_loss_mm2() == pytest.approx(0.0, abs=1e-6)
    # Content identity: equal points, equal rail (contact-table caches key on it).
    assert r0 == wear_rail("60E1", GRID, np.zeros_like(GRID), INCLINATION)
    assert hash(r0) == hash(wear_rail("60E1", GRID, np.zeros_like(GRID), INCLINATION))


def test_wear_along_the_normal_removes_its_area_and_is_measured_where_it_is():
    # Crown: a uniform 1 mm over |y| < 20 lowers the top by 1 mm (W1), leaves the gauge face.
    top = np.where(np.abs(GRID) < 20.0, 1.0, 0.0)
    r_top = wear_rail("60E1", GRID, top, INCLINATION)
    hw = r_top.head_wear()
    assert hw.vertical.value_mm == pytest.approx(1.0, abs=0.01)
    assert abs(hw.lateral.value_mm) < 0.01
    # Gauge corner: a 0.8 mm bump at y = -31 wears W3 (45 deg) and not the crown.
    corner = 0.8 * np.exp(-0.5 * ((GRID + 31.0) / 2.0) ** 2)
    r_corner = wear_rail("60E1", GRID, corner, INCLINATION)
    hw = r_corner.head_wear()
    assert hw.corner_45.value_mm > 0.3
    assert abs(hw.vertical.value_mm) < 0.01
    # Area: removing d along the normal takes int d ds (to first order in d / radius; the
    # R13 gauge corner bends the offset curve, hence the 3 %).
    for rail, depth in ((r_top, top), (r_corner, corner)):
        assert rail.area_loss_mm2() == pytest.approx(_arc_integral("60E1", depth), rel=0.03)
    # Worn material is never added: the worn head lies inside the new one.
    y0, z0 = rail_profile("60E1", 0.05, 0.0)
    inside = np.interp(r_corner.y_mm, y0, z0, left=np.nan, right=np.nan)
    ok = np.isfinite(inside)
    assert np.all(r_corner.z_mm[ok] <= inside[ok] + 1e-3)
    with pytest.raises(ValueError, match="rail"):
        wear_rail("UIC54", GRID, top, INCLINATION)
    with pytest.raises(ValueError, match="ascending"):
        wear_rail("60E1", GRID[::-1], top, INCLINATION)


@pytest.fixture(scope="module")
def bogie_contacts():
    veh = vehicle_preset("metro_b")
    y = _grid(WHEEL_GRID_MM)
    out, _ = class_contacts_all_wheels(veh, CURVES, y, s1002_height_mm(y))
    return veh, out


@pytest.mark.parametrize("law,rail_share", [
    (WearLaw("usfd"), 1.0),                      # seed 003 §4.2: the same for wheel and rail
    (WearLaw("archard_kth"), 0.5),               # seed 004 §2.1: coefficients for both bodies
    (WearLaw("archard_kth", ArchardKTH(coefficient_scope="per_body")), 1.0),
])
def test_rail_takes_its_share_of_every_wheels_volume_per_law(bogie_contacts, law, rail_share):
    veh, contacts = bogie_contacts
    shares = np.array([c.share for c in CURVES])
    # Tangent track: contact angles of a few degrees, vertical and normal depth agree to 0.2 %.
    y = _grid(WHEEL_GRID_MM)
    straight, _ = class_contacts_all_wheels(veh, CURVES[2:], y, s1002_height_mm(y))
    d = rail_depth_per_vehicle_all_wheels(straight, law, CURVES[2:], np.ones(1), GRID)
    vol_per_m = sum(float(np.sum(contact_volume_basis(c, law) @ law_coefficients(law)))
                    for c in straight.values())
    # Two bogies per vehicle; the mean rail is the average of the two rails.
    expected_area_mm2 = rail_share * 2 * vol_per_m / 1000.0 / 2.0
    assert np.trapezoid(d["mean"], GRID) == pytest.approx(expected_area_mm2, rel=5e-3)
    assert np.allclose(d["high"], d["low"])  # tangent track: no high or low rail
    # Curves: the high rail is worn on its gauge corner by the flanging wheel, the low rail
    # on its crown; the mean rail is their average.
    full = rail_depth_per_vehicle_all_wheels(contacts, law, CURVES, shares, GRID)
    assert -36.0 < GRID[np.argmax(full["high"])] < -25.0
    assert abs(GRID[np.argmax(full["low"])]) < 15.0
    assert np.allclose(full["mean"], 0.5 * (full["high"] + full["low"]))


def test_local_rail_wear_removes_the_wheels_local_volume_per_passage(bogie_contacts):
    # Seed 003 §4.2: the element's specific volume is the same for wheel and rail. Locally,
    # one passage of a patch removes from the rail the volume per metre that the wheel loses
    # per metre rolled: the rail's area per passage = the wheel's area per metre rolled x
    # 2 pi R_cp / 1000 (a wheel point passes 1000 / (2 pi R_cp) times per metre).
    veh, _ = bogie_contacts
    y = _grid(WHEEL_GRID_MM)
    law = WearLaw("usfd")
    straight, _ = class_contacts_all_wheels(veh, CURVES[2:], y, s1002_height_mm(y))
    local = rail_depth_per_vehicle_all_wheels(straight, law, CURVES[2:], np.ones(1), GRID,
                                              application="local", friction=veh.friction)
    wheel_area_per_pass = 0.0
    for c in straight.values():
        for s in np.nonzero(c.in_contact[0])[0]:
            one = replace(c, in_contact=np.eye(c.in_contact.shape[1], dtype=bool)[s][None, :])
            per_m = wheel_depth_basis(one, law, y, "local", 20, veh.friction)[0, 0]
            wheel_area_per_pass += (np.trapezoid(per_m, y)
                                    * 2 * np.pi * c.rolling_radius_m[0, s] * 1000.0 / 1000.0)
    # two bogies per vehicle, the mean rail the average of the two rails (tread: cos ~ 1)
    assert np.trapezoid(local["mean"], GRID) == pytest.approx(wheel_area_per_pass, rel=5e-3)
    # local is not the global law: wear only where the elements slip
    glob = rail_depth_per_vehicle_all_wheels(straight, law, CURVES[2:], np.ones(1), GRID)
    assert not np.allclose(local["mean"], glob["mean"])
    with pytest.raises(ValueError, match="application"):
        rail_depth_per_vehicle_all_wheels(straight, law, CURVES[2:], np.ones(1), GRID,
                                          application="fine")


@pytest.fixture(scope="module")
def rail_steps():
    return simulate_rail_steps("metro_b", CURVES, n_rail_steps=2, law="usfd",
                               steps=WearSteps(n_steps=4, depth_per_step_mm=0.5),
                               feedback="mean")


@pytest.fixture(scope="module")
def high_low_steps():
    return simulate_rail_steps("metro_b", CURVES, n_rail_steps=2, law="usfd",
                               steps=WearSteps(n_steps=4, depth_per_step_mm=0.5),
                               feedback="high_low")


def test_rail_steps_wear_the_rail_by_d_step_and_feed_it_back(rail_steps):
    rs = rail_steps
    assert rs.feedback == "mean"
    assert len(rs.wheel_runs) == 2 and len(rs.rails) == 3
    assert rs.rails[0] == "60E1" and isinstance(rs.rails[1], WornRail)
    # Each wheel evolution ran on its rail step's rail (the contact table's rail).
    assert rs.wheel_runs[0].rail == "60E1" and rs.wheel_runs[1].rail == rs.rails[1]
    assert np.all(rs.km_tot > 0) and np.all(np.diff(rs.tonnage_mt) > 0)
    # Seed 003 §6.1 with eq. (4)-(5): each simulation (w_i, r_j) of the wheel evolution gives
    # a virtual rail worn to D_step^r at its peak; the next rail is their arithmetic mean, so
    # the step removes the mean of the scaled depths (peak <= D_step^r) with the mean N_i.
    smooth = Smoothing()
    for j in range(2):
        updates = rs.wheel_runs[j].rail_update_depths_mm
        assert updates.shape == (4, 3, GRID.size)  # 4 wheel steps, mean/high/low rail
        virtual = [smooth.apply(u[0], GRID) for u in updates]
        n_i = [rs.rail_step_depth_mm / v.max() for v in virtual]
        assert rs.vehicles_per_step[j] == pytest.approx(np.mean(n_i), rel=1e-12)
        scaled = rs.vehicles_per_step[j] * rs.rail_depth_per_vehicle_mm[j]
        virtual_mean = np.mean([n * v for n, v in zip(n_i, virtual, strict=True)], axis=0)
        assert np.allclose(scaled, virtual_mean, rtol=1e-12, atol=1e-15)
        assert 0.5 * rs.rail_step_depth_mm < scaled.max() <= rs.rail_step_depth_mm * (1 + 1e-12)
        # the virtual rails differ (the wheel wears between them): not one depth rescaled
        assert np.std(n_i) > 0
    # Material: the first rail step removes the scaled depth's area along the arc.
    first = rs.vehicles_per_step[0] * rs.rail_depth_per_vehicle_mm[0]
    assert rs.rails[1].area_loss_mm2() == pytest.approx(_arc_integral("60E1", first), rel=0.03)
    # The high rail wears on the gauge corner, the low rail on the crown.
    high, low = rs.head_wear(1, "high"), rs.head_wear(1, "low")
    assert high.corner_45.value_mm > 0.2 and high.corner_45.value_mm > 5 * high.vertical.value_mm
    assert low.vertical.value_mm > 0.2 and low.vertical.value_mm > 5 * abs(
        low.corner_45.value_mm)
    d = rs.to_dict()
    assert [r["rail_step"] for r in d["rail_steps"]] == [0, 1]
    assert [r["contact_fallbacks"] for r in d["rail_steps"]] == [
        run.contact_fallbacks for run in rs.wheel_runs]


def test_high_and_low_rails_are_worn_and_fed_back_each_under_its_own_wheels(rail_steps,
                                                                          high_low_steps):
    rs, mean = high_low_steps, rail_steps
    assert rs.feedback == "high_low"
    # Rail step 0 runs on new rails: one profile under both wheels, the same numbers as the
    # mean feedback's (the per-side contact with one rail twice is the mirrored one).
    a, b = rs.wheel_runs[0], mean.wheel_runs[0]
    assert np.array_equal(a.profiles_mm, b.profiles_mm) and np.array_equal(a.mileage_km,
                                                                          b.mileage_km)
    # Eq. (4) on the deeper of the two rails of each virtual rail: the deeper one's scaled
    # depth peaks at D_step^r, so their mean peaks at most there; the mean rail (tangent
    # track's) takes the mean of the two.
    smooth = Smoothing()
    for j in range(2):
        n = rs.vehicles_per_step[j]
        n_i = [rs.rail_step_depth_mm / max(smooth.apply(u[1], GRID).max(),
                                           smooth.apply(u[2], GRID).max())
               for u in rs.wheel_runs[j].rail_update_depths_mm]
        assert n == pytest.approx(np.mean(n_i), rel=1e-12)
        peaks = (n * rs.high_depth_per_vehicle_mm[j].max(),
                 n * rs.low_depth_per_vehicle_mm[j].max())
        assert 0.5 * rs.rail_step_depth_mm < max(peaks) <= rs.rail_step_depth_mm * (1 + 1e-12)
        assert np.allclose(rs.rail_depth_per_vehicle_mm[j], 0.5 * (
            rs.high_depth_per_vehicle_mm[j] + rs.low_depth_per_vehicle_mm[j]))
    first_high = rs.vehicles_per_step[0] * rs.high_depth_per_vehicle_mm[0]
    assert rs.high_rails[1].area_loss_mm2() == pytest.approx(_arc_integral("60E1", first_high),
                                                            rel=0.03)
    # the high rail wears on its gauge corner, the low rail on its crown (N_step is set by
    # the deeper one, so each is worn less than D_step^r where it is the shallower)
    high, low = rs.head_wear(1, "high"), rs.head_wear(1, "low")
    assert high.corner_45.value_mm > 0.1 and high.corner_45.value_mm > 5 * high.vertical.value_mm
    assert low.vertical.value_mm > 0.1 and low.vertical.value_mm > 5 * abs(low.corner_45.value_mm)
    # Fed back: each wheel evolution ran with its step's high rail outside and low rail
    # inside every curve, tangent track on the mean rail; the mean feedback's step 1 ran on
    # the mean rail alone and wore the wheel otherwise.
    for j, run in enumerate(rs.wheel_runs):
        assert run.rail == rs.rails[j]
        assert run.high_rail == rs.high_rails[j] and run.low_rail == rs.low_rails[j]
    assert mean.wheel_runs[1].high_rail is None
    assert rs.high_rails[1] != rs.low_rails[1]
    assert not np.array_equal(rs.wheel_runs[1].profiles_mm, mean.wheel_runs[1].profiles_mm)
    assert rs.to_dict()["feedback"] == "high_low"
    with pytest.raises(ValueError, match="feedback"):
        simulate_rail_steps("metro_b", CURVES, feedback="both")


def test_worn_rail_makes_the_flange_contact_milder(rail_steps):
    # Seed 003 §6.4: the mileage grows with the rail step "explained by a better conformity
    # between wheel and rail surfaces". On the new wheel in the 300 m curve, the leading outer
    # wheel's flange patch on the worn rail (one rail step) carries less of the load at a lower
    # contact angle, and its frictional power per area (the USFD wear index) and its total
    # frictional power are lower than on the new rail. Measured with the masked table and the
    # contact point's lead in the lateral creepage (stop 30): new / worn rail 43.4 / 34.2 deg,
    # Fn 48.8 / 30.2 kN, T-gamma 221 / 103 N, per area 2.45 / 2.27 N/mm^2; with the contact
    # angle from the wheel's slope averaged with the gap's own masked weights (helper
    # flange11) 44.0 / 36.9 deg, 48.9 / 32.9 kN, 222 / 118 N, 2.43 / 2.32 N/mm^2. (Averaged
    # with the plain Gaussian, which mixes in the flank beyond the worn rail's gauge corner
    # that the gap does not see, the worn rail's patch came out 2.31 mm wide at 2.83 N/mm^2;
    # with the former Gaussian table, whose flange-root patch was ~10x too narrow, the worn
    # rail's patch came out wider and at a lower mean pressure instead.)
    veh = vehicle_preset("metro_b")
    y = _grid(WHEEL_GRID_MM)
    z = s1002_height_mm(y)
    patch = {}
    for label, rail in (("new", "60E1"), ("worn", rail_steps.rails[1])):
        out, fb = class_contacts_all_wheels(replace(veh, rail_profile=rail), CURVES[:1], y, z)
        assert fb == 0
        c = out[(1, "right")]
        i = int(np.argmax(c.normal_force_n[0]))
        assert np.degrees(c.contact_angle_rad[0, i]) > 30.0  # the flange patch
        area = np.pi * c.a_mm[0, i] * c.b_mm[0, i]
        patch[label] = (c.contact_angle_rad[0, i], c.normal_force_n[0, i], c.t_gamma_n[0, i],
                        c.t_gamma_n[0, i] / area)
    assert patch["worn"][0] < patch["new"][0] - np.radians(4.0)
    assert patch["worn"][1] < 0.85 * patch["new"][1]
    assert patch["worn"][2] < 0.75 * patch["new"][2]
    assert patch["worn"][3] < patch["new"][3]


def test_a_vehicle_on_a_worn_rail_and_bad_options():
    rail = wear_rail("60E1", GRID, np.where(np.abs(GRID) < 20.0, 0.5, 0.0), INCLINATION)
    sim = simulate_wear(replace(vehicle_preset("metro_b"), rail_profile=rail), CURVES[2:],
                        law="usfd", steps=WearSteps(n_steps=1), rail_from_all_wheels=True)
    assert sim.rail == rail and sim.rail_high_depth_per_vehicle_mm is not None
    with pytest.raises(ValueError, match="rail_step_depth_mm"):
        simulate_rail_steps("metro_b", CURVES, rail_step_depth_mm=0.0)
    with pytest.raises(ValueError, match="all wheels"):
        simulate_rail_steps("metro_b", CURVES, rail_from_all_wheels=False)


def test_the_mean_wheel_wears_by_the_mean_of_the_four_wheels_depths():
    # Seed 003 §4.3: the average over the wheel-rail pairs gives one mean wheel profile, whose
    # maximum depth sets the step (eq. 2-3, km_tot of Tables 5 and 8). All four wheels run on
    # the same profile, so the mean wheel's first step is the mean of the four wheels' steps.
    steps = WearSteps(mode="fixed", n_steps=1, step_km=200.0, max_depth_per_step_mm=50.0)
    kw = {"law": "usfd", "steps": steps, "rail_from_all_wheels": True}
    veh = vehicle_preset("metro_b")
    per_wheel = [simulate_wear(veh, CURVES, axle=a, side=s, **kw).step_basis_mm[0, 0]
                 for a, s in ((1, "left"), (1, "right"), (2, "left"), (2, "right"))]
    mean = simulate_wear(veh, CURVES, mean_wheel=True, **kw)
    expected = np.mean(per_wheel, axis=0)
    # (step_basis_mm is the finite-difference Jacobian of the normal update: linear to ~1e-4)
    assert np.max(np.abs(mean.step_basis_mm[0, 0] - expected)) < 1e-3 * expected.max()
    # the leading outer wheel wears deepest: the mean wheel is not any one wheel
    assert mean.step_max_depth_mm[0] < 0.9 * max(w.max() for w in per_wheel)
    with pytest.raises(ValueError, match="rail_from_all_wheels"):
        simulate_wear(veh, CURVES, law="usfd", mean_wheel=True)


def test_the_whole_vehicle_runs_on_a_given_rail(rail_steps):
    from wearcast.physics.vehicle_wear_simulation import (
        VehicleWearOptions,
        simulate_vehicle_wear,
        vehicle_bogies,
    )

    rail = rail_steps.rails[1]
    kwargs = {"law": "usfd", "mileage_km": 100.0, "depth_per_step_mm": 1.0}
    new = simulate_vehicle_wear("metro_b", CURVES[:2], **kwargs)
    worn = simulate_vehicle_wear("metro_b", CURVES[:2], options=VehicleWearOptions(rail=rail),
                                 **kwargs)
    # The option puts the rail under every bogie, as bogies built on that rail do.
    direct = simulate_vehicle_wear(
        [(replace(b, rail_profile=rail), n) for b, n in vehicle_bogies("metro_b")],
        CURVES[:2], **kwargs)
    assert np.array_equal(worn.profiles_mm, direct.profiles_mm)
    assert np.max(np.abs(worn.profiles_mm - new.profiles_mm)) > 1e-3
    with pytest.raises(ValueError, match="rail_profile"):
        simulate_vehicle_wear("metro_b", CURVES[:2], mileage_km=10.0,
                              options=VehicleWearOptions(rail="UIC54"))


#: Tolerance on km_tot^j / km_tot^0 against seed 003 Tables 5/8 [-]: the spread of the seed's
#: own descriptions of the same line at rail steps 1-2 (complete line and n_class = 4, 6, 8, 10:
#: 1.027-1.051 at step 1, 1.115-1.154 at step 2), rounded up. The ratio, not km_tot itself: the
#: loop's mean wheel is that of one (trailer) bogie type on seed 003's Table 3 classes, and its
#: absolute wear rate is not the seed's (1,716 against 3,047 km at rail step 0).
SEED_RATIO_TOLERANCE = 0.05


@pytest.mark.slow
def test_rail_steps_lengthen_the_wheel_life_as_seed_003_tables_5_and_8(reference_dir):
    import pandas as pd

    table = pd.read_csv(reference_dir / "published" / "aosta_statistical_track_nclass7.csv",
                        comment="#")
    from wearcast.statistics.generators.scenarios import seed003_classes

    classes = seed003_classes(table)
    ref = pd.read_csv(reference_dir / "published" / "aosta_full_vs_statistical_mileage.csv",
                      comment="#")
    seed = ref[ref.description == "complete"].sort_values("rail_step").km_tot.to_numpy(float)
    # seed 003's km_tot: the mean wheel (§4.3, eq. 2), the law applied locally (§4.2)
    # with seed 003's own definitions (km_tot of the mean wheel of the bogie's four, §4.3 and
    # eq. 2, D_step bounding the normal depth; the wear law per FASTSIM element on wheel and
    # rail, §4.2; the next rail the mean of the virtual rails each worn to D_step^r, §6.1) and
    # the table's contact angle from the kernel-averaged slope (stop 33): measured ratios 1.062
    # and 1.129 at rail steps 1-2 against the seed's 1.038 and 1.154
    # (benchmarks/reproduce_seed003.py --rail-steps). Steps 3-4 (1.148, 1.116 against 1.238,
    # 1.339) are not reproduced: README, seed reproduction table
    rs = simulate_rail_steps("minuetto", classes, n_rail_steps=3, law="usfd",
                             steps=WearSteps(n_steps=20, depth_per_step_mm=0.2),
                             unbalanced_acceleration_m_s2=0.8, mean_wheel=True,
                             application="local")
    for j in (1, 2):
        assert rs.km_tot[j] / rs.km_tot[0] == pytest.approx(seed[j] / seed[0],
                                                             abs=SEED_RATIO_TOLERANCE), j
