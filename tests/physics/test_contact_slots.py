"""Which gap minima get a contact slot (``contact_candidates_kernel``'s selection rule).

A worn tread has more gap minima than the three slots the curving model used to keep: when a
deeper minimum overtook a loaded one the loaded one lost its slot and the bogie residual jumped
by ~0.27 wheel loads (README, stop 25), so the curving equilibrium failed. The rule now: enough
slots for every minimum of a worn tread (``N_SLOTS``), and beyond them a rank fade that makes a
minimum's weight vanish where it exchanges its slot with the best minimum left out. These tests
check the properties, not figures: the compiled kernel equals its numpy reference at every slot
count; with no more minima than slots, no minimum is dropped or faded; whatever the number of
minima, the candidates' normal forces and the bogie residual are continuous in the shift
(bisected down to 1e-12 mm: a jump does not shrink, a steep slope does).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from wearcast.physics import curving as cv
from wearcast.physics.bogie_equations import bogie_residual, compiled_residual, initial_state
from wearcast.physics.contact_candidates_kernel import N_SLOTS, candidate_slots
from wearcast.physics.curving_table import (
    _NO_CONTACT_GAP_MM,
    PROMINENCE_MM,
    SEPARATION_MM,
    SHARE_GAP_MM,
    SLOT_FADE_MM,
)
from wearcast.physics.vehicles import vehicle_preset

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from residual_continuity import RIPPLED, largest_jump, rippled  # noqa: E402

#: Four gap minima at most (a worn tread's count) and seven (more than the slots).
PROFILES = {"four_minima": RIPPLED["rippled, 4 minima"],
            "seven_minima": RIPPLED["rippled, 7 minima"]}


@pytest.fixture(scope="module")
def trailer():
    return vehicle_preset("minuetto", "trailer")


@pytest.fixture(scope="module")
def tables(trailer):
    return {name: cv.build_contact_table(rippled(*p), trailer.rail_profile,
                                         trailer.rail_inclination, trailer.wheel_radius_m)
            for name, p in PROFILES.items()}


def _minima_per_row(table, shifts):
    """Number of interior minima of the gap row at each shift (as the kernel interpolates)."""
    grid = table.shift_mm
    pos = np.clip((shifts - grid[0]) / (grid[1] - grid[0]), 0.0, len(grid) - 1.000001)
    k = np.floor(pos).astype(int)
    w = (pos - k)[:, None]
    g = (1.0 - w) * table.gap_mm[k] + w * table.gap_mm[k + 1]
    inner = g[:, 1:-1]
    return np.sum((inner < g[:, :-2]) & (inner <= g[:, 2:]), axis=1)


def test_the_profiles_have_the_minima_they_are_meant_to(tables):
    shifts = np.linspace(-15.0, 15.0, 3001)
    assert _minima_per_row(tables["four_minima"], shifts).max() == 4
    assert _minima_per_row(tables["seven_minima"], shifts).max() == 7 > N_SLOTS
    # the five minima of a loop-worn tread (8,000 km) fit the slots
    assert N_SLOTS >= 5


@pytest.mark.parametrize("n_slots", [1, 2, 3, N_SLOTS, N_SLOTS + 3])
@pytest.mark.parametrize("name", sorted(PROFILES))
def test_compiled_slots_equal_the_numpy_reference_at_every_slot_count(tables, name, n_slots):
    table = tables[name]
    shifts = np.random.default_rng(5).uniform(-16.0, 16.0, 600)
    ref = table._candidate_slots_numpy(shifts, n_slots)
    new = candidate_slots(table.gap_mm, table.gap2_per_mm, table.smoothing_mm,
                          float(table.shift_mm[0]), float(table.shift_mm[1] - table.shift_mm[0]),
                          table.wheel_y_mm, shifts, n_slots, PROMINENCE_MM, SEPARATION_MM,
                          SHARE_GAP_MM, _NO_CONTACT_GAP_MM, SLOT_FADE_MM)
    for label, r, c in zip(("wheel y", "gap", "g''", "weight"), ref, new, strict=True):
        assert c.shape == (shifts.size, n_slots)
        assert np.allclose(c, r, rtol=1e-9, atol=1e-9), label
    cols = table.candidates(shifts, n_slots)
    assert all(v.shape == (shifts.size, n_slots) for v in cols.values())


def test_no_minimum_is_dropped_or_faded_when_they_fit_the_slots(tables):
    # four minima at most: the N_SLOTS candidates are exactly those of a selection without a
    # cap (more slots than minima), with the same weights
    table = tables["four_minima"]
    shifts = np.linspace(-15.0, 15.0, 1501)
    capped = table.candidates(shifts)
    free = table.candidates(shifts, N_SLOTS + 5)
    n_min = _minima_per_row(table, shifts)
    found = np.sum(capped["gap_mm"] < _NO_CONTACT_GAP_MM, axis=1)
    assert np.array_equal(found, n_min)
    for name in ("wheel_y_mm", "gap_mm", "weight", "approach1_mm"):
        assert np.array_equal(capped[name], free[name][:, :N_SLOTS]), name
    assert np.all(free["weight"][:, N_SLOTS:] == 0.0)


@pytest.mark.parametrize("n_slots", [2, 3, N_SLOTS])
@pytest.mark.parametrize("name", sorted(PROFILES))
def test_candidate_normal_forces_are_continuous_whatever_the_number_of_minima(tables, name,
                                                                               n_slots):
    # the Hertz force of every candidate at an approach d above the deepest minimum,
    # w (d - gap)^1.5 / approach1^1.5 (``bogie_equations``), summed per wheel: with more minima
    # than slots the selection changes along the shift, and the sum must not jump
    table = tables[name]

    def forces(shift):
        c = table.candidates(shift, n_slots)
        out = []
        for d in (0.05, 0.2, 0.5):
            out.append(np.sum(c["weight"] * np.clip(d - c["gap_mm"], 0.0, None) ** 1.5
                              / c["approach1_mm"] ** 1.5, axis=-1))
        return np.stack(out, axis=-1) / 1e5  # about wheel loads

    jump, where, _ = largest_jump(forces, -15.0, 15.0)
    assert jump < 1e-6, (jump, where)


def test_bogie_residual_is_continuous_where_a_fourth_minimum_is_loaded(trailer, tables):
    # the leading wheelset swept across the tread of the four-minima wheel, the left wheel
    # pressed d mm beyond the centred static approach: somewhere four minima of that wheel
    # carry load at once (three slots dropped one, and the residual jumped by 0.06-0.2 wheel
    # loads at y 6.15 mm); now the residual is continuous. The sweep stops before y 6.9 mm,
    # where the saturation creep law has a jump of its own on a flange patch (not a slot).
    table = tables["four_minima"]
    q0 = initial_state(trailer, table)
    most_loaded = 0
    for d in (0.0, 0.1, 0.3):
        def residual(y, d=d):
            q = np.repeat(q0[None], np.size(y), axis=0)
            q[:, 0] = y
            q[:, 3] += d
            return compiled_residual(q, trailer, table, 0.0, 0.0, 0.0)

        jump, where, _ = largest_jump(residual, 3.0, 6.8)
        assert jump < 1e-6, (d, jump, where)
        ys = np.linspace(3.0, 6.8, 381)
        q = np.repeat(q0[None], ys.size, axis=0)
        q[:, 0] = ys
        q[:, 3] += d
        _, c = bogie_residual(q, trailer, table, 0.0, 0.0, 0.0, return_contacts=True)
        most_loaded = max(most_loaded, int(np.max(np.sum(c.normal_force_n[:, 0, 0] > 0,
                                                         axis=-1))))
    assert most_loaded == 4


@pytest.mark.slow
def test_every_gap_minimum_of_loop_worn_wheels_has_a_slot():
    # the Minuetto's wheels worn by the whole-vehicle loop, every trip forward on the example
    # fleet's Aosta route to 8,000 km (the catalogue run of README stop 25): four or five gap
    # minima in one row, every one kept with the weight of an uncapped selection
    import json

    from wearcast.physics.vehicle_wear_simulation import (
        VehicleWearOptions,
        simulate_vehicle_wear,
    )

    root = Path(__file__).resolve().parents[2]
    routes = json.loads((root / "service" / "example_fleet" / "routes.json").read_text())
    classes = next(r for r in routes if r["name"] == "aosta")["classes"]
    sim = simulate_vehicle_wear("minuetto", classes, mileage_km=8000.0, depth_per_step_mm=0.8,
                                options=VehicleWearOptions(forward_share=1.0))
    shifts = np.linspace(-15.0, 15.0, 1501)
    most = 0
    for b, label in enumerate(sim.wheels[::4]):
        vehicle = vehicle_preset("minuetto", "motor" if label.startswith("motor") else "trailer")
        z = sim.profiles_mm[4 * b:4 * b + 4].mean(axis=0)
        table = cv.build_contact_table(lambda y, z=z: np.interp(y, sim.y_mm, z),
                                       vehicle.rail_profile, vehicle.rail_inclination,
                                       vehicle.wheel_radius_m)
        capped = table.candidates(shifts)
        free = table.candidates(shifts, N_SLOTS + 5)
        for name in ("wheel_y_mm", "gap_mm", "weight"):
            assert np.array_equal(capped[name], free[name][:, :N_SLOTS]), (label, name)
        assert np.all(free["weight"][:, N_SLOTS:] == 0.0)
        most = max(most, int(_minima_per_row(table, shifts).max()))
    assert 4 <= most <= N_SLOTS
