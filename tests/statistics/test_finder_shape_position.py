"""The wheel position's shape removed from the instrument cause's coefficients
(``finder_shape_position``)."""

from __future__ import annotations

import numpy as np
import pytest

from wearcast.statistics import finder_shape_position as fsp


def _layout(seed: int, n_units: int = 8, wheels: int = 12, rows: int = 6):
    """Units of ``wheels`` wheels measured ``rows`` times; each unit one mode (mixed or lead)
    and one instrument, crossed; positions bogie x leading share as in the twin's layout."""
    rng = np.random.default_rng(seed)
    pos, inst, unit = [], [], []
    for u in range(n_units):
        mode = "mixed" if u % 2 == 0 else "lead"
        instrument = "MP-1" if (u // 2) % 2 == 0 else "MP-2"
        for w in range(wheels):
            bogie = "motor" if w < wheels // 2 else "trailer"
            share = 0.5 if mode == "mixed" else (1.0 if w % 2 == 0 else 0.0)
            pos += [f"{bogie}|{share}"] * rows
            inst += [instrument] * rows
            unit += [u] * rows
    return rng, np.array(pos, dtype=object), np.array(inst, dtype=object), np.array(unit)


def test_position_effects_that_stand_out_are_removed_and_the_signature_kept():
    rng, pos, inst, unit = _layout(0)
    levels = sorted(set(pos))
    effect = {p: rng.normal(0.0, 0.3, 3) for p in levels}
    signature = np.where((inst == "MP-2")[:, None], np.array([0.05, 0.1, -0.02]), 0.0)
    unit_level = rng.normal(0.0, 0.02, (unit.max() + 1, 3))[unit]
    coef = (np.array([effect[p] for p in pos]) + signature + unit_level
            + rng.normal(0.0, 0.05, (pos.size, 3)))
    p_value, dof_pos, dof_int = fsp.position_test(coef, pos, inst)
    assert p_value < 0.01 and dof_pos == len(levels) - 1 and dof_int >= 1
    out = fsp.without_position_shape(coef, pos, inst)
    # the positions' own shapes are gone ...
    for p in levels:
        assert np.allclose(out[pos == p].mean(axis=0) - out.mean(axis=0), 0.0, atol=0.05)
    # ... and the instrument's signature passes unchanged
    contrast = out[inst == "MP-2"].mean(axis=0) - out[inst == "MP-1"].mean(axis=0)
    assert np.allclose(contrast, [0.05, 0.1, -0.02], atol=0.03), contrast


def _four_units(rng: np.random.Generator, unit_sd: float):
    """The twin's and the loop's layout: units A (mixed, MP-1), B (mixed, MP-2), C (lead,
    MP-2), D (lead, MP-1), 3 vehicles of 8 wheels each, 6 measurements; coefficients with a
    level per unit (sd ``unit_sd``), per wheel (0.1) and per measurement (0.1), no position."""
    pos, inst, unit, wheel = [], [], [], []
    k = 0
    for u, (mode, instrument) in enumerate((("mixed", "MP-1"), ("mixed", "MP-2"),
                                            ("lead", "MP-2"), ("lead", "MP-1"))):
        for _ in range(3 * 8):
            bogie = "motor" if k % 8 < 4 else "trailer"
            share = 0.5 if mode == "mixed" else (1.0 if k % 2 == 0 else 0.0)
            pos += [f"{bogie}|{share}"] * 6
            inst += [instrument] * 6
            unit += [u] * 6
            wheel += [k] * 6
            k += 1
    unit_a, wheel_a = np.array(unit), np.array(wheel)
    coef = (rng.normal(0.0, unit_sd, (4, 3))[unit_a] + rng.normal(0.0, 0.1, (k, 3))[wheel_a]
            + rng.normal(0.0, 0.1, (unit_a.size, 3)))
    return coef, np.array(pos, dtype=object), np.array(inst, dtype=object)


@pytest.mark.parametrize("unit_sd", [0.02, 0.3])
def test_unit_levels_alone_are_not_taken_for_positions(unit_sd):
    # no position in the shapes, only each unit's own level (small as on the twin, or three
    # times the wheels' scatter): the positions do not stand out against their interaction
    # with the instrument, and the coefficients stay as they were (removing them named the
    # effect-free twin's instrument on 3 of 20 seeds); with the k x dof degrees of freedom
    # instead of the lower bound the large unit levels passed in about a quarter of layouts
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(60):
        coef, pos, inst = _four_units(rng, unit_sd)
        if fsp.position_test(coef, pos, inst)[0] < fsp.POSITION_ALPHA:
            hits += 1
        else:
            assert np.array_equal(fsp.without_position_shape(coef, pos, inst), coef)
    assert hits <= 8, hits


def test_positions_nested_in_the_instruments_leave_the_signature_alone():
    # every mixed-mode wheel measured by MP-1, every lead-mode one by MP-2: the mode's shape
    # and the instrument's signature cannot be told apart, and the instrument keeps it
    rng = np.random.default_rng(3)
    n = 600
    lead = rng.random(n) < 0.5
    pos = np.where(lead, "motor|1.0", "motor|0.5").astype(object)
    inst = np.where(lead, "MP-2", "MP-1").astype(object)
    coef = np.where(lead[:, None], 0.2, 0.0) + rng.normal(0.0, 0.05, (n, 3))
    out = fsp.without_position_shape(coef, pos, inst)
    assert np.allclose(out, coef)


def test_switch_off_returns_the_coefficients():
    rng, pos, inst, _ = _layout(1)
    coef = rng.normal(size=(pos.size, 3)) + (pos == "motor|0.5")[:, None]
    fsp.SHAPE_POSITION = "none"
    try:
        assert np.array_equal(fsp.without_position_shape(coef, pos, inst), coef)
    finally:
        fsp.SHAPE_POSITION = "position"
    with pytest.raises(ValueError):
        fsp.SHAPE_POSITION = "bogus"
        try:
            fsp.without_position_shape(coef, pos, inst)
        finally:
            fsp.SHAPE_POSITION = "position"
