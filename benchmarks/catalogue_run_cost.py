"""Where one loop run of the Aosta diagnosis spends its steps and its time (issue 12 §6).

Run: .venv/bin/python benchmarks/catalogue_run_cost.py [--params '{"forward_share": 1.0}']
     [--km 8000] [--step 0.8] [--every 1000]

One run of ``benchmarks/diagnose_aosta_physics.py``'s catalogue (``--params``: the
``VehicleWearOptions`` of one catalogue value, ``law`` for the wear law; ``{}``: the null) on
seed 003's Table 3 classes, timed by wrapping (not changing) the loop's parts:

* Steps: the loop's step is D_step / the largest VERTICAL depth rate of any wheel (normal
  rate times sqrt(1 + z'^2), ``vehicle_wear_simulation``). Per ``--every`` km it prints the
  steps, their mean length, and the wheel, lateral position, slope factor sqrt(1 + z'^2) and
  normal rate of the step-setting point.
* Time: the contact tables (``curving_table.build_contact_table``), the curving solves from
  the last equilibrium (warm), the retries of the points that fail from it (continuation from
  the tangent track's equilibrium, ``class_contacts._solve_points``), the wear rates, and the rest.
* Retries: operating points retried, how many the retry solves, and the class fallbacks
  (classes and wheels that keep the previous update's contact).

Needs ../shared/reference.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

import wearcast.physics.class_contacts as class_contacts
import wearcast.physics.curving as curving
import wearcast.physics.equilibrium_solvers as solvers
import wearcast.physics.vehicle_wear_simulation as vehicle_wear
from wearcast.statistics.generators.scenarios import seed003_classes

ROOT = Path(__file__).resolve().parents[1]
TRACK_CSV = ROOT.parent / "shared" / "reference" / "published" / \
    "aosta_statistical_track_nclass7.csv"


#: The 12 unknowns and equations of the bogie equilibrium (``bogie_equations``), per wheelset
#: (axle 1, 2) then the bogie frame.
_UNKNOWNS = [f"{n}{a}" for a in (1, 2) for n in ("y", "psi", "e", "dL", "dR")] + ["yb", "psib"]
_EQUATIONS = [f"{n}{a}" for a in (1, 2) for n in ("Fy", "Mz", "My", "QL", "QR")] + ["Fyb",
                                                                                   "Mzb"]


def _beyond_stall(fun: Any, q: Any, t: float, p: Any, floor: float = 2.0 ** -10) -> dict:
    """From the continuation's last accepted state q at load fraction t, continue again with
    a step floor (``floor`` of the path; the solver's own budget counts failures) to where no
    step of the floor converges (t2, Newton's residual there), then the scaled residual along
    the Newton step of the floor from that state (401 points): its largest jump between
    neighbouring points against the median one (a discontinuity of the contacts, e.g. a
    contact-table slot switching, is a jump; a fold is a near-singular Jacobian)."""
    jac = fun.__self__.jacobian
    step, n_end = 1.0 / 64.0, 0.0
    while t < 1.0 - 1e-12 and step >= floor:
        t_try = min(t + step, 1.0)
        q_new, n_new, ok = solvers.newton_batch(fun, q[None, :], t_try * p, 1e-6, jac=jac)
        if ok[0]:
            q, t, step = q_new[0], t_try, min(2.0 * step, 1.0)
        else:
            step, n_end = step / 2.0, float(n_new[0])
    if t >= 1.0 - 1e-12:
        return {"t2": 1.0, "n2": 0.0, "jump": np.nan, "jump_med": np.nan}
    p2 = min(t + floor, 1.0) * p
    r0, jm = jac(q[None, :], p2, 1e-6 * np.maximum(1.0, np.abs(q))[None, :])
    dx = np.linalg.lstsq(jm[0], -r0[0], rcond=None)[0]
    s = np.linspace(0.0, 1.0, 401)
    r = fun(q[None, :] + s[:, None] * dx[None, :], np.repeat(p2, len(s), axis=0))
    jumps = np.linalg.norm(np.diff(r, axis=0), axis=1)
    return {"t2": t, "n2": n_end, "jump": float(jumps.max()),
            "jump_med": float(np.median(jumps))}


class _RetryFailures:
    """Why the retried operating points (continuation from the tangent equilibrium) fail: the stage
    (the saturation law's continuation, or Newton with FASTSIM's forces from its equilibrium),
    the load fraction t the continuation reached, the residual norm and its largest equation,
    and the state (contact-frame shifts y1, y2 [mm] against the contact table's range,
    approaches [mm]). Wraps, does not change, the solvers."""

    def __init__(self, state_km: Any) -> None:
        self.state_km = state_km
        self.rows: list[dict[str, Any]] = []
        self.call: dict[str, Any] | None = None

    def install(self) -> None:
        cont, newton = curving.continuation_batch, curving.newton_batch
        inner, polish = solvers.newton_batch, solvers.scipy_polish

        def reached(params: Any, ok: Any) -> None:
            c = self.call
            if c is None or c["p_end"] is None:
                return
            for row, good in zip(np.atleast_2d(params), np.atleast_1d(ok), strict=True):
                if not good:
                    continue
                for j in range(len(c["p_end"])):
                    pe = c["p_end"][j]
                    big = int(np.argmax(np.abs(pe)))
                    if pe[big] == 0:
                        continue
                    t = row[big] / pe[big]
                    if np.allclose(row, t * pe, rtol=1e-9, atol=1e-12):
                        c["t"][j] = max(c["t"][j], t)

        def inner_w(fun: Any, q0: Any, params: Any, tol: Any, *a: Any, **k: Any) -> Any:
            out = inner(fun, q0, params, tol, *a, **k)
            reached(params, out[2])
            return out

        def polish_w(fun: Any, q0: Any, param: Any, tol: Any, jac: Any = None) -> Any:
            out = polish(fun, q0, param, tol, jac=jac)
            reached(np.asarray(param)[None, :], [out[2]])
            return out

        def cont_w(fun: Any, q_start: Any, p_start: Any, p_end: Any, tol: Any,
                   *a: Any, **k: Any) -> Any:
            c = self.call
            if c is not None:
                c["p_end"], c["t"] = np.asarray(p_end), np.zeros(len(p_end))
            q, norm, ok = cont(fun, q_start, p_start, p_end, tol, *a, **k)
            if c is not None:
                c["sat"] = (q.copy(), norm.copy(), ok.copy(), fun)
                c["p_end"] = None
            return q, norm, ok

        def newton_w(fun: Any, q0: Any, params: Any, tol: Any, *a: Any, **k: Any) -> Any:
            out = newton(fun, q0, params, tol, *a, **k)
            if self.call is not None:
                self.call["fastsim"] = (out[0].copy(), out[1].copy(), fun)
            return out

        solvers.newton_batch, solvers.scipy_polish = inner_w, polish_w  # type: ignore
        curving.continuation_batch, curving.newton_batch = cont_w, newton_w  # type: ignore

    def begin(self, kind: str, vehicle: Any, cases: Any, table: Any, factor: float) -> None:
        self.call = None if kind != "retry" else {
            "vehicle": vehicle, "cases": cases, "table": table, "factor": factor,
            "p_end": None, "t": None, "sat": None, "fastsim": None}

    def end(self, out: Any) -> None:
        c, self.call = self.call, None
        if c is None or c["sat"] is None:
            return
        q_s, n_s, ok_s, fun_s = c["sat"]
        t_all = c["t"]
        table, v = c["table"], c["vehicle"]
        range_mm = float(np.max(np.abs(table.shift_mm)))
        rows_f = np.nonzero(ok_s)[0]
        for i, res in enumerate(out):
            case = c["cases"][i]
            p = np.array([[case.curvature_per_m, case.unbalanced_acceleration_m_s2,
                           case.torque_nm]])
            row = {"km": self.state_km(), "bogie": "motor" if v.traction_torque_nm else
                   "trailer", "radius_m": (np.inf if case.curvature_per_m == 0 else
                                           1.0 / case.curvature_per_m),
                   "a_unb": case.unbalanced_acceleration_m_s2, "factor": c["factor"],
                   "solved": res is not None, "range_mm": range_mm}
            if res is None and not ok_s[i]:
                q = q_s[i]
                r = fun_s(q[None, :], float(t_all[i]) * p)[0]
                row.update(stage="saturation", t=float(t_all[i]), norm=float(n_s[i]))
            elif res is None:
                m = int(np.nonzero(rows_f == i)[0][0])
                q_f, n_f, fun_f = c["fastsim"]
                q = q_f[m]
                r = fun_f(q[None, :], p)[0]
                row.update(stage="fastsim", t=1.0, norm=float(n_f[m]))
            else:
                q, r = np.asarray(res.state), np.zeros(12)
                row.update(stage="solved", t=1.0, norm=float(res.residual_norm))
                qs = np.asarray(res.saturation_state)[None, :]
                jm = fun_s.__self__.jacobian(qs, p, 1e-6 * np.maximum(1.0, np.abs(qs)))[1][0]
                row.update(cond=float(np.linalg.cond(jm)))
            worst = int(np.argmax(np.abs(r)))
            row.update(y1=float(q[0]), y2=float(q[5]), dmin=float(min(q[[3, 4, 8, 9]])),
                       worst_eq=_EQUATIONS[worst] if res is None else "")
            if res is None and row["stage"] == "saturation":
                # the last accepted state of the continuation: the Jacobian's condition number
                # (a fold of the load path: near-singular) and the patches of the wheel whose
                # vertical-load equation is worst (QR1: axle 1, right)
                p_t = float(t_all[i]) * p
                jm = fun_s.__self__.jacobian(q[None, :], p_t,
                                             1e-6 * np.maximum(1.0, np.abs(q))[None, :])[1][0]
                _, cts = curving.bogie_residual(q[None, :], v, table, p_t[:, 0], p_t[:, 1],
                                                p_t[:, 2], return_contacts=True)
                name = _EQUATIONS[worst]
                ax, sd = (int(name[-1]) - 1, 0 if "L" in name else 1) if name[0] == "Q" \
                    else (0, 1)
                fn = np.asarray(cts.normal_force_n)[0, ax, sd]
                ang = np.degrees(np.asarray(cts.contact_angle_rad)[0, ax, sd])
                loaded = fn > 0.01 * v.wheel_load_n
                row.update(cond=float(np.linalg.cond(jm)), patches=int(loaded.sum()),
                           angle_max=float(ang[loaded].max()) if loaded.any() else np.nan,
                           **_beyond_stall(fun_s, q, float(t_all[i]), p))
            self.rows.append(row)

    def report(self) -> None:
        if not self.rows:
            print("why: no retries")
            return
        d = pd.DataFrame(self.rows)
        for col in ("cond", "patches", "angle_max", "t2", "n2", "jump", "jump_med"):
            if col not in d:
                d[col] = np.nan
        d["|y|max"] = d[["y1", "y2"]].abs().max(axis=1)
        d["at_range"] = d["|y|max"] > d["range_mm"] - 0.5
        print("why the retries fail (per retried operating point; t: load fraction the "
              "continuation from the tangent equilibrium reached; |y|max: largest contact-frame "
              f"shift, table range +-{d['range_mm'].iloc[0]:g} mm; dmin: smallest approach):")
        g = d.groupby(["bogie", "radius_m", "stage"])
        pd.set_option("display.width", 200)
        print(g.agg(n=("km", "size"), km_first=("km", "min"), km_last=("km", "max"),
                    factor=("factor", "median"), t_med=("t", "median"),
                    norm_med=("norm", "median"), ymax_med=("|y|max", "median"),
                    at_range=("at_range", "mean"), dmin_med=("dmin", "median"),
                    cond_med=("cond", "median"), patches=("patches", "median"),
                    angle_max=("angle_max", "median"), t2_med=("t2", "median"),
                    n2_med=("n2", "median"), jump_med=("jump", "median"),
                    worst=("worst_eq", lambda s: s.value_counts().index[0] if len(s) else ""))
              .round(3).to_string())
        fails = d[d.stage != "solved"]
        print(f"failed {len(fails)} of {len(d)}: stage "
              f"{fails.stage.value_counts().to_dict()}, largest residual equation "
              f"{fails.worst_eq.value_counts().head(4).to_dict()}, at the table range "
              f"{int(fails.at_range.sum())}; Jacobian condition number median "
              f"{fails.cond.median():.3g} at the stalls (last accepted state), "
              f"{d[d.stage == 'solved'].cond.median():.3g} at the solved equilibria")
        sat = fails[fails.stage == "saturation"]
        if len(sat):
            print(f"saturation stalls continued again with a step floor of 2^-10: "
                  f"{int((sat.t2 >= 1.0).sum())} of {len(sat)} reach full load; the others "
                  f"stop at t2 median {sat[sat.t2 < 1].t2.median():.3f} (from t "
                  f"{sat[sat.t2 < 1].t.median():.3f}) with Newton's residual median "
                  f"{sat[sat.t2 < 1].n2.median():.2g}; along the last Newton step the "
                  f"residual jumps by up to {sat.jump.median():.3g} (median over points; "
                  f"median increment {sat.jump_med.median():.2g}): "
                  f"{int((sat.jump > 100 * sat.jump_med.clip(lower=1e-6)).sum())} points "
                  f"with a jump > 100 x the median increment")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--params", default='{"forward_share": 1.0}',
                        help="one catalogue value as JSON ({} for the null)")
    parser.add_argument("--km", type=float, default=8000.0, help="mileage [km]")
    parser.add_argument("--step", type=float, default=0.8, help="D_step [mm]")
    parser.add_argument("--every", type=float, default=1000.0, help="report interval [km]")
    parser.add_argument("--why", action="store_true",
                        help="also print why the retried operating points fail")
    args = parser.parse_args()
    if not TRACK_CSV.exists():
        print(f"skipped: {TRACK_CSV} not found")
        return
    params = json.loads(args.params)
    law = params.pop("law", "usfd")
    classes = seed003_classes(pd.read_csv(TRACK_CSV, comment="#"))
    clock: dict[str, float] = {"table": 0.0, "cold": 0.0, "warm": 0.0, "retry": 0.0,
                               "rates": 0.0}
    counts = {"retried": 0, "retry_solved": 0}

    def timed(name: str, fn: Any) -> Any:
        def wrapper(*a: Any, **k: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                clock[name] += time.perf_counter() - t0
        return wrapper

    # _solve_points' solves: cold (a first update, no last equilibrium: initial_states None),
    # warm (from the last equilibria), retry (the warm failures from the tangent equilibrium: a list
    # of None)
    solve = curving.solve_curving_cases_or_none

    def solve_counted(vehicle: Any, cases: Any, labels: Any, table: Any, **k: Any) -> Any:
        init = k.get("initial_states")
        kind = ("cold" if init is None else
                "retry" if all(s is None for s in init) else "warm")
        t0 = time.perf_counter()
        if why is not None:
            why.begin(kind, vehicle, cases, table, state["factor"])
        out = solve(vehicle, cases, labels, table, **k)
        if why is not None:
            why.end(out)
        clock[kind] += time.perf_counter() - t0
        if kind == "retry":
            counts["retried"] += len(cases)
            counts["retry_solved"] += sum(r is not None for r in out)
        return out

    why = _RetryFailures(state_km=lambda: state["km"]) if args.why else None
    if why is not None:
        why.install()

    class_contacts.solve_curving_cases_or_none = solve_counted  # type: ignore[assignment]
    class_contacts.build_contact_table = timed(  # type: ignore[assignment]
        "table", class_contacts.build_contact_table)
    vehicle_wear._wheel_rates = timed("rates", vehicle_wear._wheel_rates)  # type: ignore

    # the step-setting point: rates (before the update) and profiles (after the previous one)
    y = np.linspace(*vehicle_wear.WHEEL_GRID_MM[:2],
                    int(round((vehicle_wear.WHEEL_GRID_MM[1] - vehicle_wear.WHEEL_GRID_MM[0])
                              / vehicle_wear.WHEEL_GRID_MM[2])) + 1)
    state: dict[str, Any] = {"profiles": None, "rows": [], "km": 0.0, "factor": 1.0}
    check_rates, check_profiles = vehicle_wear._check_finite_rates, vehicle_wear._check_profiles

    def on_rates(rates: Any, labels: Any, mileage_km: float) -> None:
        prof = state["profiles"]
        if prof is None:
            prof = np.broadcast_to(vehicle_wear.s1002_height_mm(y), rates.shape)
        slope = np.gradient(prof, y, axis=-1)
        factor = np.sqrt(1.0 + slope * slope)
        i = np.unravel_index(int(np.argmax(rates * factor)), rates.shape)
        state["rows"].append((mileage_km, labels[i[0] * 4 + i[1]], float(y[i[2]]),
                              float(factor[i]), float(rates[i]) * 1000.0,
                              float(rates.max()) * 1000.0))
        check_rates(rates, labels, mileage_km)

    def on_profiles(y_mm: Any, z0: Any, profiles: Any, labels: Any, mileage_km: float) -> None:
        state["profiles"] = profiles.copy()
        state["km"] = mileage_km
        slope = np.gradient(profiles, y_mm, axis=-1)
        state["factor"] = float(np.sqrt(1.0 + slope * slope).max())
        check_profiles(y_mm, z0, profiles, labels, mileage_km)

    vehicle_wear._check_finite_rates = on_rates  # type: ignore[assignment]
    vehicle_wear._check_profiles = on_profiles  # type: ignore[assignment]

    t0, c0 = time.perf_counter(), time.process_time()
    sim = vehicle_wear.simulate_vehicle_wear(
        "minuetto", classes, law=law, mileage_km=args.km, depth_per_step_mm=args.step,
        options=vehicle_wear.VehicleWearOptions(**params))
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    km = sim.mileage_km
    print(f"run {params or 'null'} (law {law}), D_step {args.step:g} mm to {args.km:.0f} km: "
          f"{len(km) - 1} steps, {sim.contact_updates} bogie contact updates, "
          f"{sim.contact_fallbacks} class fallbacks; {wall:.1f} s wall, {cpu:.1f} s CPU; "
          f"FT {sim.mean('sd_mm')[-1]:.4f}, FH {sim.mean('sh_mm')[-1]:.4f}, "
          f"qR {sim.mean('qr_mm')[-1]:.4f} mm")
    print("time: " + ", ".join(f"{k} {v:.1f} s ({100 * v / wall:.0f} %)"
                               for k, v in clock.items())
          + f", rest {wall - sum(clock.values()):.1f} s")
    print(f"retries by continuation: {counts['retried']} operating points, "
          f"{counts['retry_solved']} solved")
    print("km range       steps  mean step km  step set by (wheel, y mm, sqrt(1+z'^2), "
          "normal rate mm/1000 km)  largest normal rate")
    lo = 0.0
    while lo < args.km - 1e-9:
        hi = min(lo + args.every, args.km)
        rows = [r for r in state["rows"] if lo <= r[0] < hi]
        if rows:
            worst = max(rows, key=lambda r: r[3] * r[4])
            print(f"{lo:6.0f}-{hi:6.0f}  {len(rows):6d}  {(hi - lo) / len(rows):12.1f}  "
                  f"{worst[1]}, {worst[2]:.1f}, {worst[3]:.1f}, {worst[4]:.2f}"
                  f"{'':>22}{max(r[5] for r in rows):.2f}")
        lo = hi
    if why is not None:
        why.report()


if __name__ == "__main__":
    main()
