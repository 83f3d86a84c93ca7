"""Lathe plan: deadlines met whenever capacity allows, at-risk wheelsets named, costs."""

from __future__ import annotations

import datetime as dt
import itertools

import numpy as np
import pytest

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.maintenance.lathe_plan import (
    DiameterGroup,
    PlanWheel,
    latest_week,
    lathe_plan,
    schedule,
)
from wearcast.statistics.maintenance.limits import FleetLimits
from wearcast.statistics.maintenance.turning import s1002_targets, turning_options

START = dt.date(2026, 3, 2)


def _feasible(due_weeks, weeks, cap):
    """Hall's condition for unit jobs with deadlines (independent of the scheduler)."""
    return all(sum(1 for d in due_weeks if d <= t) <= cap * (t + 1) for t in range(weeks)) \
        and all(d >= 0 for d in due_weeks)


def test_latest_week_is_before_the_deadline():
    for days in range(0, 40):
        w = latest_week(START + dt.timedelta(days=days), START)
        if w >= 0:
            assert START + dt.timedelta(days=7 * w + 6) < START + dt.timedelta(days=days)
            assert START + dt.timedelta(days=7 * (w + 1) + 6) >= START + dt.timedelta(days=days)


def test_schedule_meets_every_deadline_when_feasible():
    rng = np.random.default_rng(3)
    for _ in range(300):
        weeks, cap, n = int(rng.integers(1, 6)), int(rng.integers(0, 3)), int(rng.integers(1, 8))
        days = rng.integers(7, 7 * (weeks + 2), n)
        deadlines = {f"S{i}": START + dt.timedelta(days=int(d)) for i, d in enumerate(days)}
        out = schedule(deadlines, START, weeks, cap)
        due = {k: latest_week(d, START) for k, d in deadlines.items()}
        due = {k: w for k, w in due.items() if w < weeks}
        ok = _feasible(list(due.values()), weeks, cap)
        assert set(out) == set(due)
        if ok:
            assert all(in_time for _, in_time in out.values())
        else:
            assert not all(in_time for _, in_time in out.values())
        for k, (w, in_time) in out.items():
            if in_time:
                assert w <= due[k]
        load = [sum(1 for w, _ in out.values() if w == i) for i in range(weeks)]
        assert max(load, default=0) <= cap


def test_schedule_turns_as_late_as_capacity_allows():
    deadlines = {"A": START + dt.timedelta(days=30), "B": START + dt.timedelta(days=30)}
    out = schedule(deadlines, START, 8, 1)
    assert sorted(w for w, _ in out.values()) == [2, 3]


def _wheel(wid, wheelset, p10_km, km_since=100_000.0, diameter=880.0, wear_scale=1.0):
    y = np.arange(-69.0, 58.0, 0.25)
    wear = wear_scale * (1.2 * np.exp(-((y + 42) / 4) ** 2)
                         + 0.4 * np.exp(-((y - 5) / 15) ** 2))
    targets, limits = s1002_targets(), FleetLimits()
    rates = {"sd": 2e-5, "sh": 5e-6, "qr": 5e-6}

    def options_at(km):
        zz = s1002_height_mm(y) - wear * (km / km_since)
        return turning_options(y, zz, targets, limits, rates, 1e-5)

    return PlanWheel(wid, wheelset, START, 500.0, km_since, p10_km, p10_km * 1.2, diameter,
                     options_at, 1e-5)


def test_plan_turns_before_p10_and_names_wheelsets_at_risk():
    wheels = [_wheel(f"{k}{s}", k, p10) for k, p10 in
              (("X", 10_000), ("Y", 12_000), ("Z", 30_000), ("Far", 90_000)) for s in "LR"]
    plan = lathe_plan(wheels, start=START, horizon_weeks=12, capacity_per_week=1,
                      fixed_interval_km=80_000, scrap_diameter_mm=840, new_diameter_mm=920)
    sets = {w.wheelset: w for w in plan.wheelsets}
    far = sets.pop("Far")  # its P10 date is beyond the 12-week horizon: not turned
    assert far.week is None and not far.at_risk
    assert not plan.at_risk
    for w in sets.values():
        assert w.in_time and w.turn_date < w.deadline
        assert w.action == "turn"
        # both wheels end at one diameter
        cuts = list(w.cuts.values())
        assert cuts[0]["diameter_before_mm"] - cuts[0]["diameter_loss_mm"] == \
            pytest.approx(w.final_diameter_mm)
    tight = lathe_plan(wheels, start=START, horizon_weeks=12, capacity_per_week=0,
                       fixed_interval_km=80_000, scrap_diameter_mm=840, new_diameter_mm=920)
    assert {w.wheelset for w in tight.at_risk} == {"X", "Y", "Z"}
    assert "no lathe capacity" in tight.at_risk[0].reason
    # the plan turns later than a 80,000 km fixed interval: less diameter per km
    d = plan.to_dict()["cost"]
    assert d["plan"]["mm_per_1000km"] < d["fixed_mileage"]["mm_per_1000km"]


def test_replace_when_below_scrap():
    wheels = [_wheel("PL", "P", 5_000, diameter=840.05), _wheel("PR", "P", 5_000, diameter=840.05)]
    plan = lathe_plan(wheels, start=START, horizon_weeks=4, capacity_per_week=1,
                      fixed_interval_km=80_000, scrap_diameter_mm=840, new_diameter_mm=920)
    assert plan.wheelsets[0].action == "replace"
    assert list(itertools.chain(plan.by_week()))[0]["load"] == 1


# --------------------------------------------------------------------------- bogie/vehicle

BOGIE = DiameterGroup("bogie", "V/1", ("V/1/1", "V/1/2"), 5.0)


def _plan(wheels, capacity=2, groups=(BOGIE,), weeks=12):
    return lathe_plan(wheels, start=START, horizon_weeks=weeks, capacity_per_week=capacity,
                      fixed_interval_km=80_000, scrap_diameter_mm=840, new_diameter_mm=920,
                      groups=groups)


def _diameter_at(plan, wheels, wheelset, day):
    """Independent of the plan's code: final diameter after the turning, else measured, each
    worn on at the wheel's diameter rate (1e-5 mm/km at 500 km/day in ``_wheel``)."""
    t = next(t for t in plan.wheelsets if t.wheelset == wheelset)
    if t.turn_date is not None and t.turn_date <= day:
        return t.final_diameter_mm - 1e-5 * 500.0 * (day - t.turn_date).days
    d = min(w.diameter_mm for w in wheels if w.wheelset == wheelset)
    return d - 1e-5 * 500.0 * (day - START).days


def test_a_turning_that_would_leave_the_bogie_apart_brings_its_partner():
    wheels = [_wheel("AL", "V/1/1", 10_000), _wheel("AR", "V/1/1", 10_000),
              _wheel("BL", "V/1/2", 500_000, diameter=884.95),
              _wheel("BR", "V/1/2", 500_000, diameter=884.95)]
    alone = {t.wheelset: t for t in _plan(wheels, groups=()).wheelsets}
    assert alone["V/1/2"].week is None  # its own limit is years away
    a = alone["V/1/1"]
    d_b = 884.95 - 1e-5 * 500.0 * (a.turn_date - START).days
    assert d_b - a.final_diameter_mm > 5.0  # planned alone, the bogie ends 5 mm apart
    plan = {t.wheelset: t for t in _plan(wheels).wheelsets}
    a, b = plan["V/1/1"], plan["V/1/2"]
    assert b.week == a.week and b.in_time and not b.at_risk
    assert "companion turning" in b.reason and "bogie diameter difference" in b.reason
    assert b.final_diameter_mm <= a.final_diameter_mm + 5.0 + 1e-9
    assert b.final_diameter_mm >= a.final_diameter_mm - 5.0 - 1e-9
    for cut in (*a.cuts.values(), *b.cuts.values()):  # the cut = target's own + matching
        assert cut["matching_loss_mm"] >= 0.0
        assert cut["diameter_before_mm"] - cut["diameter_loss_mm"] == pytest.approx(
            a.final_diameter_mm if cut in a.cuts.values() else b.final_diameter_mm)


def test_a_difference_over_the_limit_at_the_start_is_due_at_once():
    wheels = [_wheel("AL", "V/1/1", 500_000), _wheel("AR", "V/1/1", 500_000),
              _wheel("BL", "V/1/2", 500_000, diameter=890.0),
              _wheel("BR", "V/1/2", 500_000, diameter=890.0)]
    plan = {t.wheelset: t for t in _plan(wheels).wheelsets}
    b = plan["V/1/2"]
    assert b.week == 0 and b.at_risk  # overdue: the limit is already exceeded
    assert "bogie diameter difference 10.0 mm > 5 mm" in b.reason
    assert plan["V/1/1"].week is None  # the smaller wheelset needs no turning
    assert _diameter_at(plan_obj := _plan(wheels), wheels, "V/1/2", b.turn_date) - \
        _diameter_at(plan_obj, wheels, "V/1/1", b.turn_date) <= 5.0 + 1e-6


def test_without_capacity_for_the_partner_it_is_named_at_risk():
    wheels = [_wheel("AL", "V/1/1", 10_000), _wheel("AR", "V/1/1", 10_000),
              _wheel("BL", "V/1/2", 500_000, diameter=884.95),
              _wheel("BR", "V/1/2", 500_000, diameter=884.95)]
    plan = {t.wheelset: t for t in _plan(wheels, capacity=1).wheelsets}
    b = plan["V/1/2"]
    assert b.week is None and b.at_risk
    assert "no lathe capacity to keep it" in b.reason and "V/1" in b.reason


def test_groups_stay_within_their_limits_whenever_capacity_allows():
    rng = np.random.default_rng(11)
    companions = 0
    for _ in range(10):
        wheels, groups = [], []
        for v in range(2):
            base = float(rng.uniform(870, 900))
            sets = []
            for bogie in (1, 2):
                for axle in (1, 2):
                    key = f"V{v}/{bogie}/{axle}"
                    sets.append(key)
                    p10 = float(rng.choice([6_000, 20_000, 40_000, 400_000]))
                    d = base + float(rng.choice([-2.45, 2.45]))  # spreads of 0 or 4.9 mm
                    scale = float(rng.uniform(0.5, 8.0))  # diameter cuts ~0.2 to 0.7 mm
                    wheels += [_wheel(key + s, key, p10, diameter=d, wear_scale=scale)
                               for s in "LR"]
                groups.append(DiameterGroup("bogie", f"V{v}/{bogie}",
                                            tuple(sets[-2:]), 5.0))
            groups.append(DiameterGroup("vehicle", f"V{v}", tuple(sets), 10.0))
        plan = _plan(wheels, capacity=8, groups=groups)
        assert not plan.at_risk
        companions += sum("companion turning" in t.reason or "moved earlier" in t.reason
                          for t in plan.wheelsets)
        for t in plan.wheelsets:
            if t.turn_date is None:
                continue
            for g in groups:
                d = [_diameter_at(plan, wheels, k, t.turn_date) for k in g.wheelsets]
                assert max(d) - min(d) <= g.limit_mm + 1e-6, (g, t.week)
    assert companions > 0  # the fleets do ask for companion turnings
