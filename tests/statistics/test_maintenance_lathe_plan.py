"""Lathe plan: deadlines met whenever capacity allows, at-risk wheelsets named, costs."""

from __future__ import annotations

import datetime as dt
import itertools

import numpy as np
import pytest

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.statistics.maintenance.lathe_plan import (
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


def _wheel(wid, wheelset, p10_km, km_since=100_000.0, diameter=880.0):
    y = np.arange(-69.0, 58.0, 0.25)
    wear = 1.2 * np.exp(-((y + 42) / 4) ** 2) + 0.4 * np.exp(-((y - 5) / 15) ** 2)
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
