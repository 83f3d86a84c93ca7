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
from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.physics.vehicles import vehicle_preset


def _rippled(amplitude_mm: float, wavelength_mm: float, lo_mm: float, hi_mm: float):
    """S1002 with a cosine ripple on wheel y lo..hi [mm] (3 mm ramps at both ends): after the
    table's 2 mm smoothing, a tread with several gap minima, like a loop-worn one."""
    def height(y):
        y = np.asarray(y, dtype=float)
        window = np.clip((y - lo_mm) / 3.0, 0.0, 1.0) * np.clip((hi_mm - y) / 3.0, 0.0, 1.0)
        return s1002_height_mm(y) + amplitude_mm * window * np.cos(
            2.0 * np.pi * (y - lo_mm) / wavelength_mm)
    return height


#: Four gap minima at most (a worn tread's count) and seven (more than the slots).
PROFILES = {"four_minima": (0.1, 7.0, 0.0, 40.0), "seven_minima": (0.3, 6.0, -20.0, 40.0)}


@pytest.fixture(scope="module")
def trailer():
    return vehicle_preset("minuetto", "trailer")


@pytest.fixture(scope="module")
def tables(trailer):
    return {name: cv.build_contact_table(_rippled(*p), trailer.rail_profile,
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


def _largest_jump(f, x0: float, x1: float, n: int = 4001, candidates: int = 40
                  ) -> tuple[float, float]:
    """The largest increment of f (vector valued) left after bisecting the sweep's steepest and
    most isolated steps down to 1e-12 mm, and where: a discontinuity keeps its size, a
    continuous function's increment vanishes."""
    x = np.linspace(x0, x1, n)
    v = f(x)
    inc = np.max(np.abs(np.diff(v, axis=0)), axis=1)
    neighbours = np.array([np.median(inc[max(0, k - 5):k + 6]) for k in range(inc.size)])
    picks = set(np.argsort(inc)[-candidates:]) | set(
        np.argsort(inc / (neighbours + 1e-300))[-candidates:])
    worst = (0.0, float("nan"))
    for k in picks:
        a, b, va, vb = x[k], x[k + 1], v[k], v[k + 1]
        while b - a > 1e-12:
            m = 0.5 * (a + b)
            vm = f(np.array([m]))[0]
            if np.max(np.abs(vm - va)) > np.max(np.abs(vb - vm)):
                b, vb = m, vm
            else:
                a, va = m, vm
        worst = max(worst, (float(np.max(np.abs(vb - va))), float(a)))
    return worst


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

    jump, where = _largest_jump(forces, -15.0, 15.0)
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

        jump, where = _largest_jump(residual, 3.0, 6.8)
        assert jump < 1e-6, (d, jump, where)
        ys = np.linspace(3.0, 6.8, 381)
        q = np.repeat(q0[None], ys.size, axis=0)
        q[:, 0] = ys
        q[:, 3] += d
        _, c = bogie_residual(q, trailer, table, 0.0, 0.0, 0.0, return_contacts=True)
        most_loaded = max(most_loaded, int(np.max(np.sum(c.normal_force_n[:, 0, 0] > 0,
                                                         axis=-1))))
    assert most_loaded == 4
