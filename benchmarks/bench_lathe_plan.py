"""Lathe plan on a fleet with known wear and turning history: deadlines met, diameter cost.

    .venv/bin/python benchmarks/bench_lathe_plan.py                 # 20 vehicles, 160 wheels
    .venv/bin/python benchmarks/bench_lathe_plan.py --vehicles 10 --seed 3

Generates a fleet (:mod:`wearcast.statistics.maintenance.synthetic`: each wheel's last
turning, its flange-face retreat and tread wear rates, its measurements since turning with
noise, one before its turning, dated at its vehicle's mileage per day), computes the fleet
state from the measurements alone (turnings detected, remaining km from each wheel's own
history), then the lathe plan over ``--weeks`` at the smallest weekly capacity that meets
every P10 deadline (and at half of it, to show the wheelsets at risk). Against the truth:

* every wheelset the plan turns is turned before the true crossing of its wheels' first
  limit, and every wheelset whose true crossing falls inside the horizon is turned;
* the diameter each policy costs, measured on the TRUE profiles: the plan turns at its
  week (wheelsets beyond the horizon at their P10 date) to its economic target,
  fixed-mileage turning every ``--fixed-km`` (or at the true crossing when that comes
  first, counted as an overrun) back to S1002; each cycle costs its cut plus the tread's
  diameter wear; printed as mm of diameter per 1,000 km and km from new to scrap diameter.

Prints the machine (CPU model from /proc/cpuinfo, cores) and the time the state and the
plan took.
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
import os
import time

import numpy as np

from wearcast.statistics.maintenance.fleet_state import fleet_state
from wearcast.statistics.maintenance.lathe_plan import latest_week, lathe_plan
from wearcast.statistics.maintenance.limits import FleetLimits
from wearcast.statistics.maintenance.plan_inputs import diameter_groups, plan_wheels
from wearcast.statistics.maintenance.synthetic import generate_fleet
from wearcast.statistics.maintenance.turning import (
    economic_choice,
    s1002_targets,
    turning_cut,
)

Y_TRUTH = np.arange(-68.0, 58.0, 0.1)


def machine() -> str:
    model = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores"


def min_capacity(deadlines: dict[str, dt.date | None], start: dt.date, weeks: int) -> int:
    """Smallest weekly capacity meeting every deadline in the horizon (Hall's condition)."""
    due = [latest_week(d, start) for d in deadlines.values() if d is not None]
    due = [w for w in due if w < weeks]
    cap = 0
    for t in range(weeks):
        n = sum(1 for w in due if w <= t)
        cap = max(cap, math.ceil(n / (t + 1)))
    return cap


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--vehicles", type=int, default=20)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--weeks", type=int, default=26)
    parser.add_argument("--no-diameter-groups", action="store_true",
                        help="plan each wheelset alone (no bogie/vehicle diameter differences)")
    parser.add_argument("--fixed-km", type=float, nargs="+",
                        default=[60_000.0, 100_000.0, 200_000.0])
    args = parser.parse_args()
    today = dt.date(2026, 6, 1)
    limits = FleetLimits()
    print(f"machine: {machine()}")
    fleet = generate_fleet(args.vehicles, seed=args.seed, today=today)
    truth = {w.wheel_id: w for w in fleet.wheels}
    print(f"fleet: {args.vehicles} vehicles, {len(fleet.wheels)} wheels, "
          f"{len(fleet.wheels) // 2} wheelsets, {len(fleet.measurements)} measurements")

    t0 = time.perf_counter()
    state = fleet_state(fleet.measurements, limits)
    profiles = {}
    for wid, g in fleet.measurements.groupby("wheel_id"):
        last = float(g["mileage_km"].max())
        y, z = fleet.profiles[(wid, last)]
        profiles[wid] = (y, z, last)
    targets = s1002_targets()
    wheels, unplanned = plan_wheels(state, profiles, targets)
    groups = () if args.no_diameter_groups else diameter_groups(state)
    t_state = time.perf_counter() - t0
    over = [s for s in state.diameter_spreads if s.scope != "axle"]
    print(f"bogie/vehicle diameter differences over their limits at the latest measurements: "
          f"{len(over)} ({', '.join(s.key for s in over[:6])}{' ...' if len(over) > 6 else ''})"
          f"; planned {'per wheelset alone' if args.no_diameter_groups else 'within them'}")
    start = today
    deadlines: dict[str, list[dt.date]] = {}
    for w in wheels:
        d = w.date_after(w.remaining_p10_km)
        if d is not None:
            deadlines.setdefault(w.wheelset, []).append(d)
    cap = max(min_capacity({k: min(v) for k, v in deadlines.items()}, start, args.weeks), 1)

    true_cross = {wid: w.true_crossing_km(limits, Y_TRUTH) for wid, w in truth.items()}

    def true_date(wid: str) -> dt.date:
        w = truth[wid]
        return w.date_at(true_cross[wid])

    runs = [(cap, f) for f in args.fixed_km] + [(max(cap // 2, 1), args.fixed_km[0])]
    for capacity, fixed_km in runs:
        if True:
            t1 = time.perf_counter()
            plan = lathe_plan(wheels, start=start, horizon_weeks=args.weeks,
                              capacity_per_week=capacity, fixed_interval_km=fixed_km,
                              scrap_diameter_mm=limits.scrap_diameter_mm,
                              new_diameter_mm=limits.new_diameter_mm,
                              groups=groups)
            t_plan = time.perf_counter() - t1
            report(plan, {w.wheel_id: w for w in wheels}, truth, true_cross, true_date,
                   start, args.weeks, capacity, fixed_km, targets, t_state, t_plan, unplanned)


def report(plan, plan_wheel, truth, true_cross, true_date, start, weeks, capacity, fixed_km,
           targets, t_state, t_plan, unplanned) -> None:
    end = start + dt.timedelta(days=7 * weeks)
    by_name = {t.name: t for t in targets}
    turned = [w for w in plan.wheelsets if w.turn_date is not None]
    # overdue: the P10 date leaves no week of the plan (crossed, or crossing in week 0)
    overdue = {w.wheelset for w in plan.wheelsets
               if w.deadline is not None and latest_week(w.deadline, start) < 0}
    late = [w.wheelset for w in turned
            if any(w.turn_date >= true_date(wid) for wid in w.wheel_ids)]
    crossing_inside = [w for w in plan.wheelsets
                       if min(true_date(wid) for wid in w.wheel_ids) < end]
    missed = [w.wheelset for w in crossing_inside if w.turn_date is None]
    already = [w.wheelset for w in crossing_inside
               if min(true_date(wid) for wid in w.wheel_ids) <= start]
    timely = [w for w in crossing_inside if w.wheelset not in overdue]
    in_time = [w for w in timely if w.turn_date is not None
               and all(w.turn_date < true_date(wid) for wid in w.wheel_ids)]
    print(f"\ncapacity {capacity} wheelsets/week, {weeks} weeks from {start}, fixed-mileage "
          f"policy every {fixed_km:,.0f} km")
    print(f"  plan: {len(turned)} wheelsets turned, {len(plan.at_risk)} named at risk "
          f"({', '.join(w.wheelset for w in plan.at_risk[:8])}"
          f"{' ...' if len(plan.at_risk) > 8 else ''}), of which {len(overdue)} overdue at the "
          f"start (P10 before the end of week 0); {len(unplanned)} wheels unplanned")
    companions = sum("companion turning" in w.reason or "moved earlier" in w.reason
                     for w in plan.wheelsets)
    kept = sum(w.at_risk and "no lathe capacity to keep it" in w.reason
               for w in plan.wheelsets)
    print(f"  bogie/vehicle diameter differences: {companions} wheelsets turned as companions "
          f"or moved earlier to keep them within the limits; {kept} of those at risk are named "
          f"for a diameter difference the capacity cannot keep")
    print(f"  truth: {len(crossing_inside)} wheelsets cross a limit inside the horizon "
          f"({len(already)} had crossed before its start); of the {len(timely)} not overdue, "
          f"{len(in_time)} turned before their true crossing; turned after it: {len(late)} "
          f"{late[:8]}; not turned although crossing inside: {len(missed)} {missed[:8]}")
    plan_mm = plan_km = fixed_mm = fixed_km_sum = 0.0
    overruns = 0
    for ws in plan.wheelsets:
        for wid in ws.wheel_ids:
            w = truth[wid]
            last = w.measured_km[-1]
            cut = ws.cuts.get(wid, {})
            if ws.turn_date is not None and cut.get("target"):
                km_since = last - w.turned_at_km + (ws.turn_date - w.date_at(last)).days \
                    * w.km_per_day
                target = by_name[cut["target"]]
            else:  # beyond the horizon: the plan turns it at its P10 to the economic target
                pw = plan_wheel.get(wid)
                if pw is None or not math.isfinite(pw.remaining_p10_km):
                    continue
                km_since = last - w.turned_at_km + pw.remaining_p10_km
                best, _ = economic_choice(pw.options_at(pw.km_since_turning
                                                        + pw.remaining_p10_km))
                if best is None:
                    continue
                target = by_name[best.cut.target]
            life = true_cross[wid] - w.turned_at_km
            km_since = min(km_since, life)
            c = turning_cut(Y_TRUTH, w.profile(Y_TRUTH, km_since), target).diameter_loss_mm
            c += cut.get("matching_loss_mm", 0.0)  # the plan's diameter matching
            plan_mm += c + 2 * w.tread_rate * km_since
            plan_km += km_since
            f_km = min(fixed_km, life)
            overruns += life < fixed_km
            cf = turning_cut(Y_TRUTH, w.profile(Y_TRUTH, f_km), by_name["S1002"])
            fixed_mm += cf.diameter_loss_mm + 2 * w.tread_rate * f_km
            fixed_km_sum += f_km
    usable = 920.0 - 840.0
    p_rate = 1000 * plan_mm / plan_km
    f_rate = 1000 * fixed_mm / fixed_km_sum
    est = plan.to_dict()["cost"]
    print(f"  diameter on the true profiles: plan {p_rate:.4f} mm/1000 km "
          f"({plan_km / max(len(truth), 1):,.0f} km per cycle per wheel), fixed "
          f"{f_rate:.4f} mm/1000 km ({fixed_km_sum / max(len(truth), 1):,.0f} km per cycle; "
          f"{overruns} wheels would cross a limit before their fixed turning)")
    print(f"  km from new to scrap diameter ({usable:g} mm): plan "
          f"{1000 * usable / p_rate:,.0f} km, fixed {1000 * usable / f_rate:,.0f} km "
          f"({100 * (f_rate - p_rate) / f_rate:+.1f} % diameter per km saved by the plan)")
    print(f"  the plan's own estimate (projected profiles): plan "
          f"{est['plan']['mm_per_1000km']:.4f}, fixed {est['fixed_mileage']['mm_per_1000km']:.4f}"
          f" mm/1000 km")
    print(f"  time: fleet state and plan inputs {t_state:.2f} s, plan {t_plan:.2f} s")


if __name__ == "__main__":
    main()
