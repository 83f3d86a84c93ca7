"""A lathe plan: the week each wheelset is turned, the cut, and the cost against
fixed-mileage turning.

**Deadlines.** A wheelset (the two wheels of an axle, turned together) is due before the
earliest P10 date at which one of its wheels reaches a limit. Week w of the plan runs from
``start + 7 w`` for seven days and a wheelset turned in it is counted as turned on the
week's last day, so week w is in time for a deadline D iff ``start + 7 w + 6 < D``: the
latest such week is ``floor((D - start) / 7) - 1``.

**Schedule** (unit jobs with deadlines, ``capacity`` wheelsets a week):

1. wheelsets whose deadline leaves no week (already crossed, or crossing in the first week)
   are at risk and take the earliest free weeks, most urgent first;
2. the others, latest deadline first, take the latest free week in time (turning as late as
   allowed keeps the most kilometres of each wheel); this finds a schedule meeting every
   deadline whenever one exists (exchange argument for unit jobs);
3. a wheelset that finds no week in time is at risk and is named, and takes the earliest
   free week left (late) if any.

Wheelsets whose deadline is beyond the horizon are not turned in this plan.

**Cut.** Each wheel's options at its turning (the worn profile projected to the kilometres
it will have run since its last turning, :func:`turning.projected_profile`) give the
economic target (:func:`turning.economic_choice`); both wheels of the axle are turned to
the same final diameter, the smaller of the two wheels' diameters after their cuts.

**Bogie and vehicle diameter differences.** A turning lowers a wheelset's diameter, and the
wheelsets of a bogie (or a vehicle) must stay within the fleet's limit of each other
(``DiameterGroup``). After the schedule, each group is checked at every week in which one of
its wheelsets is turned, with every wheelset's diameter at that week's end (turned ones at
their final diameter, the others worn on at their diameter rate): where a wheelset stands more
than the limit above the lowest,

* if it is turned in that week, its cut is deepened to the lowest diameter plus the limit;
* if it is not turned yet (later, or not in this plan), it is brought into that week as a
  companion turning cut to that diameter, when the week has lathe capacity left; else the
  week's turnings of the group and the companion move together to the latest earlier week
  with room for all of them (earlier is always in time);
* if it was turned in an earlier week, the wheelsets turned in this week move to that earlier
  week (earlier is always in time), when it has capacity left;

otherwise the wheelset is named at risk with the difference it would leave. A difference
that already exceeds the limit at the plan's start makes the wheelsets above the lowest plus
the limit due at once (like an axle's), cut down to it. Rounds repeat until nothing changes.

**Cost against fixed-mileage turning.** Per wheel, one cycle of each policy: the plan turns
at the kilometres since turning of its planned week, to the economic target; fixed-mileage
turning turns every ``fixed_interval_km`` (or at the P10 crossing when that comes first) to
the reference profile. Each cycle costs its cut (with what matching the diameters within
the axle, bogie and vehicle adds) plus the tread's diameter wear over the cycle; the fleet's
diameter per 1,000 km and the kilometres from new to scrap diameter follow.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from wearcast.statistics.maintenance.turning import TurningOption, economic_choice

#: Options for a wheel at a given number of kilometres since its last turning.
OptionsAt = Callable[[float], Sequence[TurningOption]]


@dataclass
class PlanWheel:
    """What the plan needs of one wheel (mileages [km], diameters [mm], rates [mm/km])."""

    wheel_id: str
    wheelset: str
    measured_on: dt.date
    km_per_day: float
    km_since_turning: float
    remaining_p10_km: float
    remaining_p50_km: float
    diameter_mm: float | None
    options_at: OptionsAt
    diameter_rate_mm_per_km: float = 0.0
    reference_target: str = "S1002"

    def date_after(self, km: float) -> dt.date | None:
        if not math.isfinite(km):
            return None
        return self.measured_on + dt.timedelta(days=km / self.km_per_day)

    def km_run_until(self, day: dt.date) -> float:
        return max((day - self.measured_on).days, 0) * self.km_per_day


@dataclass
class WheelsetTurning:
    """One wheelset's place in the plan."""

    wheelset: str
    wheel_ids: list[str]
    deadline: dt.date | None
    week: int | None = None
    turn_date: dt.date | None = None
    in_time: bool = False
    at_risk: bool = False
    action: str = "none"  # "turn", "replace" or "none"
    reason: str = ""
    cuts: dict[str, dict[str, Any]] = field(default_factory=dict)
    final_diameter_mm: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"wheelset": self.wheelset, "wheel_ids": self.wheel_ids,
                "deadline": _iso(self.deadline), "week": self.week,
                "turn_date": _iso(self.turn_date), "in_time": self.in_time,
                "at_risk": self.at_risk, "action": self.action, "reason": self.reason,
                "cuts": self.cuts, "final_diameter_mm": self.final_diameter_mm}


def _iso(value: dt.date | None) -> str | None:
    return None if value is None else value.isoformat()


def latest_week(deadline: dt.date, start: dt.date) -> int:
    """Latest plan week whose last day is before ``deadline`` (module docstring)."""
    return (deadline - start).days // 7 - 1


def schedule(deadlines: dict[str, dt.date | None], start: dt.date, weeks: int,
             capacity_per_week: int) -> dict[str, tuple[int | None, bool]]:
    """Week (or None) and whether it is in time, per wheelset (module docstring, 1-3)."""
    if weeks < 1:
        raise ValueError("horizon_weeks: must be >= 1")
    if capacity_per_week < 0:
        raise ValueError("capacity_per_week: must be >= 0")
    free = [capacity_per_week] * weeks
    out: dict[str, tuple[int | None, bool]] = {}
    due = {k: latest_week(d, start) for k, d in deadlines.items() if d is not None}
    due = {k: w for k, w in due.items() if w < weeks}
    late = sorted((k for k, w in due.items() if w < 0), key=lambda k: (due[k], k))
    timely = sorted((k for k, w in due.items() if w >= 0), key=lambda k: (-due[k], k))

    def earliest(key: str) -> None:
        for w in range(weeks):
            if free[w] > 0:
                free[w] -= 1
                out[key] = (w, False)
                return
        out[key] = (None, False)

    for key in late:
        earliest(key)
    missed = []
    for key in timely:
        for w in range(due[key], -1, -1):
            if free[w] > 0:
                free[w] -= 1
                out[key] = (w, True)
                break
        else:
            missed.append(key)
    for key in sorted(missed, key=lambda k: (due[k], k)):
        earliest(key)
    return out


@dataclass(frozen=True)
class DiameterGroup:
    """Wheelsets whose running diameters must stay within ``limit_mm`` of each other: the
    wheelsets of one bogie or of one vehicle (``scope``)."""

    scope: str
    key: str
    wheelsets: tuple[str, ...]
    limit_mm: float


@dataclass
class PolicyCost:
    """Diameter and kilometres of one policy, summed over the wheels it was computed for."""

    diameter_per_cycle_mm: float = 0.0
    km_per_cycle: float = 0.0
    wheels: int = 0

    @property
    def mm_per_1000km(self) -> float:
        return 1000.0 * self.diameter_per_cycle_mm / self.km_per_cycle \
            if self.km_per_cycle > 0 else math.nan

    def km_new_to_scrap(self, usable_diameter_mm: float) -> float:
        """Kilometres one wheel runs from new to scrap at this policy's rate."""
        rate = self.mm_per_1000km
        if math.isnan(rate):  # no wheel computed
            return math.nan
        return 1000.0 * usable_diameter_mm / rate if rate > 0 else math.inf

    def to_dict(self, usable_diameter_mm: float) -> dict[str, Any]:
        return {"wheels": self.wheels, "diameter_per_cycle_mm": self.diameter_per_cycle_mm,
                "km_per_cycle": self.km_per_cycle, "mm_per_1000km": self.mm_per_1000km,
                "km_new_to_scrap": self.km_new_to_scrap(usable_diameter_mm)}


@dataclass
class LathePlan:
    start: dt.date
    weeks: int
    capacity_per_week: int
    wheelsets: list[WheelsetTurning]
    plan_cost: PolicyCost
    fixed_cost: PolicyCost
    fixed_interval_km: float
    usable_diameter_mm: float

    @property
    def at_risk(self) -> list[WheelsetTurning]:
        return [w for w in self.wheelsets if w.at_risk]

    def by_week(self) -> list[dict[str, Any]]:
        out = []
        for w in range(self.weeks):
            sets = [t.wheelset for t in self.wheelsets if t.week == w]
            out.append({"week": w, "starts_on": (self.start + dt.timedelta(days=7 * w))
                        .isoformat(), "wheelsets": sets, "load": len(sets)})
        return out

    def to_dict(self) -> dict[str, Any]:
        plan = self.plan_cost.to_dict(self.usable_diameter_mm)
        fixed = self.fixed_cost.to_dict(self.usable_diameter_mm)
        return {
            "start": self.start.isoformat(), "horizon_weeks": self.weeks,
            "capacity_per_week": self.capacity_per_week,
            "wheelsets": [w.to_dict() for w in self.wheelsets],
            "weeks": self.by_week(),
            "at_risk": [{"wheelset": w.wheelset, "wheel_ids": w.wheel_ids,
                         "deadline": _iso(w.deadline), "reason": w.reason}
                        for w in self.at_risk],
            "cost": {"plan": plan, "fixed_mileage": fixed,
                     "fixed_interval_km": self.fixed_interval_km,
                     "saving_mm_per_1000km": fixed["mm_per_1000km"] - plan["mm_per_1000km"],
                     "extra_km_new_to_scrap": plan["km_new_to_scrap"]
                     - fixed["km_new_to_scrap"]},
        }


def _pick(options: Sequence[TurningOption], name: str | None) -> TurningOption | None:
    if name is None:
        return economic_choice(options)[0]
    return next((o for o in options if o.cut.target == name), None)


def _cycle(wheel: PlanWheel, km_since: float, target: str | None
           ) -> tuple[TurningOption | None, float]:
    """The option chosen at ``km_since`` km since turning and its cycle's diameter [mm]."""
    option = _pick(wheel.options_at(km_since), target)
    if option is None:
        return None, math.nan
    return option, option.cut.diameter_loss_mm + wheel.diameter_rate_mm_per_km * km_since


def lathe_plan(wheels: Sequence[PlanWheel], *, start: dt.date, horizon_weeks: int,
               capacity_per_week: int, fixed_interval_km: float, scrap_diameter_mm: float,
               new_diameter_mm: float, extra_due: dict[str, str] | None = None,
               groups: Sequence[DiameterGroup] = ()) -> LathePlan:
    """The plan (module docstring). ``extra_due`` names wheelsets due now for another
    reason (e.g. an axle's diameter difference), with the reason; ``groups`` are the bogies
    and vehicles whose diameter differences the plan keeps within their limits."""
    if not fixed_interval_km > 0:
        raise ValueError("fixed_interval_km: must be > 0")
    sets: dict[str, list[PlanWheel]] = {}
    for w in wheels:
        sets.setdefault(w.wheelset, []).append(w)
    deadlines: dict[str, dt.date | None] = {}
    reasons: dict[str, str] = {}
    for key, members in sets.items():
        dates = [(w.date_after(w.remaining_p10_km), w.wheel_id) for w in members]
        known = [(d, wid) for d, wid in dates if d is not None]
        deadlines[key] = min(known)[0] if known else None
        if known:
            reasons[key] = f"P10 limit of {min(known)[1]} on {min(known)[0].isoformat()}"
        if extra_due and key in extra_due:
            deadlines[key] = start
            reasons[key] = extra_due[key]
    caps: dict[str, float] = {}
    for key, reason, cap in _spreads_at_start(sets, groups):
        deadlines[key] = start
        reasons[key] = reason
        caps[key] = cap
    placed = schedule(deadlines, start, horizon_weeks, capacity_per_week)
    turnings: dict[str, WheelsetTurning] = {}
    for key in sorted(sets):
        members = sets[key]
        turning = WheelsetTurning(key, [w.wheel_id for w in members], deadlines[key],
                                  reason=reasons.get(key, "no limit predicted"))
        week, in_time = placed.get(key, (None, False))
        due = key in placed
        turning.at_risk = due and not in_time
        if due and week is None:
            turning.reason += "; no lathe capacity left in the horizon"
        elif turning.at_risk:
            turning.reason += "; not turnable before it with this capacity"
        if week is not None:
            turning.week, turning.in_time = week, in_time
            turning.turn_date = start + dt.timedelta(days=7 * week + 6)
            _cut_wheelset(turning, members, scrap_diameter_mm, caps.get(key))
        turnings[key] = turning
    if groups:
        _keep_groups_within(turnings, sets, groups, start, horizon_weeks, capacity_per_week,
                            scrap_diameter_mm)
    out = [turnings[key] for key in sorted(sets)]
    plan_cost, fixed_cost = PolicyCost(), PolicyCost()
    for turning in out:
        members = sets[turning.wheelset]
        for w in members:
            if turning.turn_date is not None:
                km_turn = w.km_since_turning + w.km_run_until(turning.turn_date)
            else:
                km_turn = w.km_since_turning + w.remaining_p10_km
            km_fixed = min(fixed_interval_km, w.km_since_turning + w.remaining_p10_km)
            if not (math.isfinite(km_turn) and math.isfinite(km_fixed)):
                continue
            chosen = turning.cuts.get(w.wheel_id, {}).get("target")
            p, p_mm = _cycle(w, km_turn, chosen)
            f, f_mm = _cycle(w, km_fixed, w.reference_target)
            if p is None or f is None or not (p_mm == p_mm and f_mm == f_mm):
                continue
            # the diameter matching within the axle, bogie and vehicle costs extra
            p_mm += turning.cuts.get(w.wheel_id, {}).get("matching_loss_mm", 0.0)
            plan_cost.diameter_per_cycle_mm += p_mm
            plan_cost.km_per_cycle += km_turn
            plan_cost.wheels += 1
            fixed_cost.diameter_per_cycle_mm += f_mm
            fixed_cost.km_per_cycle += km_fixed
            fixed_cost.wheels += 1
    return LathePlan(start, horizon_weeks, capacity_per_week, out, plan_cost, fixed_cost,
                     fixed_interval_km, new_diameter_mm - scrap_diameter_mm)


def _cut_wheelset(turning: WheelsetTurning, members: Sequence[PlanWheel],
                  scrap_diameter_mm: float, cap_mm: float | None = None) -> None:
    """Cuts of both wheels to one final diameter (module docstring, Cut), at most
    ``cap_mm`` when a bogie or vehicle diameter difference asks for it."""
    assert turning.turn_date is not None
    turning.cuts = {}
    turning.final_diameter_mm = None
    after: dict[str, float] = {}
    for w in members:
        km_since = w.km_since_turning + w.km_run_until(turning.turn_date)
        options = w.options_at(km_since)
        best, least = economic_choice(options)
        if best is None:
            turning.cuts[w.wheel_id] = {"target": None, "reason": "no target restores every "
                                        "limit"}
            continue
        d_now = None if w.diameter_mm is None else \
            w.diameter_mm - w.diameter_rate_mm_per_km * w.km_run_until(turning.turn_date)
        turning.cuts[w.wheel_id] = {
            "target": best.cut.target, "radial_mm": best.cut.radial_mm,
            "diameter_loss_mm": best.cut.diameter_loss_mm, "km_since_turning": km_since,
            "least_loss_target": least.cut.target if least else None,
            "diameter_before_mm": d_now}
        if d_now is not None:
            after[w.wheel_id] = d_now - best.cut.diameter_loss_mm
    turning.action = "turn"
    if after:
        final = min(after.values())
        if cap_mm is not None and final > cap_mm:
            final = cap_mm
        turning.final_diameter_mm = final
        for cut in turning.cuts.values():
            if cut.get("diameter_before_mm") is not None:
                loss = cut["diameter_before_mm"] - final
                # what matching the axle's (and the bogie's, vehicle's) diameters adds to
                # the target's own cut [mm of diameter]
                cut["matching_loss_mm"] = max(loss - cut["diameter_loss_mm"], 0.0)
                cut["diameter_loss_mm"] = loss
        if final < scrap_diameter_mm:
            turning.action = "replace"
            turning.reason += (f"; turning would leave {final:.1f} mm, below the scrap "
                               f"diameter {scrap_diameter_mm:g} mm")


def _wheelset_diameter(turning: WheelsetTurning, members: Sequence[PlanWheel],
                       day: dt.date) -> float | None:
    """The wheelset's running diameter [mm] at the end of ``day``: its final diameter after
    a turning on or before that day, else its measured one, worn on at the diameter rate
    (the smaller of its wheels'); None without a measured diameter."""
    values = []
    for w in members:
        if turning.turn_date is not None and turning.turn_date <= day \
                and turning.final_diameter_mm is not None:
            km = max((day - turning.turn_date).days, 0) * w.km_per_day
            values.append(turning.final_diameter_mm - w.diameter_rate_mm_per_km * km)
        elif w.diameter_mm is not None:
            values.append(w.diameter_mm - w.diameter_rate_mm_per_km * w.km_run_until(day))
    return min(values) if values else None


def _spreads_at_start(sets: dict[str, list[PlanWheel]], groups: Sequence[DiameterGroup]
                      ) -> list[tuple[str, str, float]]:
    """Wheelsets due at once because their group's difference already exceeds its limit at
    the latest measurements: (wheelset, reason, the diameter [mm] to cut down to)."""
    out = []
    for g in groups:
        diam = {k: min(d for w in sets[k] if (d := w.diameter_mm) is not None)
                for k in g.wheelsets if k in sets
                and any(w.diameter_mm is not None for w in sets[k])}
        if len(diam) < 2:
            continue
        floor = min(diam.values())
        for k, d in sorted(diam.items()):
            if d > floor + g.limit_mm + 1e-9:
                out.append((k, f"{g.scope} diameter difference {d - floor:.1f} mm > "
                            f"{g.limit_mm:g} mm in {g.key}", floor + g.limit_mm))
    return out


def _keep_groups_within(turnings: dict[str, WheelsetTurning], sets: dict[str, list[PlanWheel]],
                        groups: Sequence[DiameterGroup], start: dt.date, weeks: int,
                        capacity_per_week: int, scrap_diameter_mm: float) -> None:
    """Deepen cuts, add companion turnings or move turnings so that no bogie or vehicle
    exceeds its diameter difference (module docstring); name the rest at risk."""
    load = [0] * weeks
    for t in turnings.values():
        if t.week is not None:
            load[t.week] += 1
    flagged: set[tuple[str, str, int]] = set()

    def place(t: WheelsetTurning, week: int, cap: float | None, why: str) -> None:
        if t.week is not None:
            load[t.week] -= 1
        load[week] += 1
        t.week = week
        t.turn_date = start + dt.timedelta(days=7 * week + 6)
        t.in_time = t.deadline is None or t.turn_date < t.deadline
        t.at_risk = not t.in_time
        if why:
            t.reason = why if t.reason == "no limit predicted" else f"{t.reason}; {why}"
        _cut_wheelset(t, sets[t.wheelset], scrap_diameter_mm, cap)

    for _ in range(4 * len(turnings) + 4):
        changed = False
        for g in groups:
            keys = [k for k in g.wheelsets if k in turnings]
            for week in sorted({t.week for k in keys if (t := turnings[k]).week is not None}):
                day = start + dt.timedelta(days=7 * week + 6)
                diam = {k: d for k in keys
                        if (d := _wheelset_diameter(turnings[k], sets[k], day)) is not None}
                if len(diam) < 2:
                    continue
                floor = min(diam.values())
                cap = floor + g.limit_mm
                for k in sorted(diam, key=lambda k: -diam[k]):
                    if diam[k] <= cap + 1e-6:
                        continue
                    t = turnings[k]
                    why = (f"{g.scope} diameter difference in {g.key}: "
                           f"{diam[k] - floor:.1f} mm > {g.limit_mm:g} mm in week {week}")
                    if t.week == week:
                        _cut_wheelset(t, sets[k], scrap_diameter_mm, cap)
                        changed = True
                    elif (t.week is None or t.week > week) and load[week] < capacity_per_week:
                        place(t, week, cap, f"companion turning: {why}")
                        changed = True
                    elif (t.week is None or t.week > week) and (earlier := next(
                            (w for w in range(week - 1, -1, -1) if load[w] + len(
                                moving := [m for m in keys if turnings[m].week == week]) + 1
                             <= capacity_per_week), None)) is not None:
                        for m in moving:
                            place(turnings[m], earlier, None, f"moved earlier: {why}")
                        place(t, earlier, None, f"companion turning: {why}")
                        changed = True
                    elif t.week is not None and t.week < week and load[t.week] + len(
                            moving := [m for m in keys if turnings[m].week == week]) \
                            <= capacity_per_week:
                        for m in moving:
                            place(turnings[m], t.week, None, f"moved earlier: {why}")
                        changed = True
                    elif (k, g.key, week) not in flagged:
                        flagged.add((k, g.key, week))
                        t.at_risk = True
                        t.reason = f"{t.reason}; {why}, no lathe capacity to keep it"
                    if changed:
                        break
                if changed:
                    break
            if changed:
                break
        if not changed:
            return
