"""Vehicle presets: sources typed in, motor/trailer variants, validation."""

from __future__ import annotations

import csv

import pytest

from wearcast.physics.vehicles import (
    GRAVITY_M_S2,
    BogieVehicle,
    preset_names,
    vehicle_preset,
)


@pytest.mark.parametrize("name", ["manchester", "metro_b", "minuetto"])
def test_every_preset_has_motor_and_trailer_variants(name):
    motor = vehicle_preset(name, "motor")
    trailer = vehicle_preset(name, "trailer")
    assert motor.bogie_type == "motor" and trailer.bogie_type == "trailer"
    # motor bogies are heavier (motors, gearboxes) and stiffer in primary yaw
    assert motor.wheelset_mass_kg + motor.bogie_mass_kg > (trailer.wheelset_mass_kg
                                                           + trailer.bogie_mass_kg)
    assert (motor.primary_longitudinal_stiffness_n_per_m
            > trailer.primary_longitudinal_stiffness_n_per_m)
    assert motor.wheel_profile == "S1002"
    assert name in preset_names()


def test_metro_b_preset_carries_seed_000_table_1():
    # Seed 000 Table 1 (type B metro): wheelset 1018 kg + two axle boxes of 110 kg, frame
    # 2103 kg, wheelbase 2300 mm, wheel diameter 840 mm, mu 0.4, body load 25.3 t (line 1),
    # 60 kg/m rail inclined 1:40. Typed values, compared exactly.
    v = vehicle_preset("metro_b", "trailer")
    assert v.wheelset_mass_kg == 1018 + 2 * 110
    assert v.bogie_mass_kg == 2103
    assert v.wheelbase_m == 2.3
    assert v.wheel_radius_m == 0.42
    assert v.friction == 0.4
    assert v.body_mass_kg == 25_300 / 2
    assert v.bogie_centre_distance_m == 12.6
    assert v.rail_profile == "60E1" and v.rail_inclination == 1 / 40


def test_metro_b_preset_matches_the_published_csv(reference_dir):
    path = reference_dir / "published" / "metro_vehicle_type_b.csv"
    rows = {r["parameter"]: r for r in csv.DictReader(
        line for line in path.read_text().splitlines() if not line.startswith("#"))}
    v = vehicle_preset("metro_b", "trailer")
    assert v.wheelbase_m * 1000 == float(rows["bogie_wheelbase"]["value"])
    assert v.wheel_radius_m * 2000 == float(rows["wheel_diameter"]["value"])
    assert v.bogie_mass_kg == float(rows["frame_mass"]["value"])
    assert v.friction == float(rows["friction_coefficient"]["value"])
    assert v.bogie_centre_distance_m * 1000 == float(rows["bogie_centre_distance"]["value"])


def test_minuetto_masses_add_up_to_seed_003_vehicle_mass():
    # Seed 003 Table 1 and §5.2: M_v = 104 700 kg for three coaches on two motor bogies and two
    # intermediate trailer bogies (each wheelset, frame and body share counted once).
    motor = vehicle_preset("minuetto", "motor")
    trailer = vehicle_preset("minuetto", "trailer")
    total = sum(2 * (v.body_mass_kg + v.bogie_mass_kg + 2 * v.wheelset_mass_kg)
                for v in (motor, trailer))
    assert total == pytest.approx(104_700.0, abs=1.0)
    assert motor.rail_inclination == 1 / 20 and motor.friction == 0.28


def test_manchester_wheel_load_from_masses():
    # (32 000 kg body / 2 + 2615 kg frame + 2 x 1813 kg wheelsets) g / 4 per wheel
    v = vehicle_preset("manchester", "trailer")
    assert v.wheel_load_n == pytest.approx((16_000 + 2615 + 2 * 1813) * GRAVITY_M_S2 / 4)
    assert v.mass_per_wheelset_kg == pytest.approx(0.5 * (16_000 + 2615) + 1813)


def test_traction_torque_only_on_motor_bogies():
    assert vehicle_preset("metro_b", "motor", traction_torque_nm=2000.0).traction_torque_nm \
        == 2000.0
    assert vehicle_preset("metro_b", "trailer", traction_torque_nm=-500.0).traction_torque_nm \
        == -500.0
    with pytest.raises(ValueError, match="trailer"):
        vehicle_preset("metro_b", "trailer", traction_torque_nm=100.0)


def test_bad_inputs_are_refused():
    with pytest.raises(ValueError, match="unknown vehicle preset"):
        vehicle_preset("tgv")
    with pytest.raises(ValueError, match="bogie_type"):
        vehicle_preset("metro_b", "locomotive")
    base = vehicle_preset("metro_b")
    with pytest.raises(ValueError, match="wheelbase_m"):
        base.with_(wheelbase_m=0.0)
    with pytest.raises(ValueError, match="rail_profile"):
        base.with_(rail_profile="UIC54")
    assert isinstance(base.with_(friction=0.2), BogieVehicle)
