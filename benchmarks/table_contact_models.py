"""Benchmark: the curve-radius tables' wear measures from the contact table's Hertz ellipses
against those from the one contact pipeline, at the table's curving equilibrium and at the
equilibrium of the pipeline's own forces (issue 11).

``wear_tables.wear_table_for_route(..., contact_model="table" | "pipeline" |
"pipeline_equilibrium")`` on the Aosta route
(seed 003 Table 3, Minuetto motor and trailer bogies) and the metro route (seed 000 Table 1,
metro B). Per curve class, bogie type, wheelset, wheel (rail) and region (tread, flange) it
compares tau_max [MPa] (largest of the region's patches) and T-gamma [N] (their sum), as
``wear_tables.table_from_contacts`` aggregates them, and prints: the relative differences
(pipeline - table) / table over the wheel regions loaded in both models (median and max of
the magnitude, median signed), split by region, rail and radius; the largest ones; the wheel
regions loaded in one model only; the same for the merged tables' rows; and the time of each
table (one core). With ``pipeline_equilibrium`` (the default ``--models``) also the pipeline's
equilibrium per operating point: the time per point and the residual reached
(``curving.solve_curving_cases`` with ``pipeline_equilibrium=True``, the solve the table makes).

The route's left and right halves of a curve class are solved alike (every class is solved
as a left curve, ``wear_tables``), so each distinct (radius, cant, speed) is counted once.

Run: ``.venv/bin/python benchmarks/table_contact_models.py`` (about 10 min, mostly the pipeline's
equilibria; ``--models pipeline`` about 30 s; ``--per-class`` also prints every class,
wheel and region of both models).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from wearcast.physics import curving  # noqa: E402
from wearcast.physics.vehicles import vehicle_preset  # noqa: E402
from wearcast.physics.wear_tables import (  # noqa: E402
    _add_indices,
    _contact_rows,
    _operating_points,
    table_from_contacts,
    wear_table_for_route,
)
from wearcast.statistics.generators.twin_routes import aosta_route, metro_route  # noqa: E402

#: Wheel-level keys of the comparison (the class's radius, cant and speed identify it).
KEYS = ["bogie_type", "radius_m", "cant_mm", "speed_kmh", "wheelset", "rail", "side", "region"]
MEASURES = {"tau_max": "tau_max_mpa", "t_gamma": "t_gamma_n"}


def per_wheel_region(contacts: pd.DataFrame) -> pd.DataFrame:
    """tau_max (largest) and T-gamma (sum) of each wheel's region over its loaded patches, and
    whether the region is loaded; one row per distinct class (left/right halves merged)."""
    df = contacts.copy()
    df["radius_m"] = df["radius_m"].fillna(np.inf)
    loaded = df["in_contact"].to_numpy()
    df["tau_max"] = np.where(loaded, df["tau_max_mpa"], 0.0)
    df["t_gamma"] = np.where(loaded, df["t_gamma_n"], 0.0)
    df["fn_region"] = np.where(loaded, df["normal_force_n"], 0.0)
    out = df.groupby(KEYS + ["class_index"], sort=False).agg(
        tau_max=("tau_max", "max"), t_gamma=("t_gamma", "sum"), loaded=("in_contact", "any"),
        normal_force_n=("fn_region", "sum")).reset_index()
    out["loaded"] = out["loaded"].astype(float)  # unstack fills the missing regions with 0
    full = out.set_index(KEYS + ["class_index"]).unstack("region", fill_value=0.0)
    full = full.stack("region", future_stack=True).fillna(0.0).reset_index()
    full["loaded"] = full["loaded"].astype(bool)
    return full.drop_duplicates(subset=KEYS).drop(columns="class_index")


def _summary(rel: pd.Series) -> str:
    if rel.empty:
        return "n    0"
    a = rel.abs()
    return (f"n {len(rel):4d}  median |d| {100 * a.median():6.2f} %  max |d| "
            f"{100 * a.max():7.2f} %  median d {100 * rel.median():+6.2f} %")


def compare(label: str, table_c: pd.DataFrame, pipe_c: pd.DataFrame, table_t: pd.DataFrame,
            pipe_t: pd.DataFrame, per_class: bool = False) -> None:
    """Print the differences of the per-wheel-region measures and of the merged tables
    (``per_class``: also every class, wheel and region)."""
    a, b = per_wheel_region(table_c), per_wheel_region(pipe_c)
    m = a.merge(b, on=KEYS, suffixes=("_table", "_pipe"))
    both = m[m["loaded_table"] & m["loaded_pipe"]].copy()
    print(f"  {label}: {len(m) // 2} wheels x 2 regions, {len(both)} wheel regions loaded in "
          "both models")
    for measure in MEASURES:
        both[f"d_{measure}"] = both[f"{measure}_pipe"] / both[f"{measure}_table"] - 1.0
    if per_class:
        shown = m.assign(radius_m=m.radius_m.replace(np.inf, np.nan)).sort_values(
            ["bogie_type", "radius_m", "cant_mm", "wheelset", "side", "region"])
        print(shown[KEYS + ["tau_max_table", "tau_max_pipe", "t_gamma_table", "t_gamma_pipe"]]
              .to_string(index=False, float_format=lambda v: f"{v:.4g}"))
    for measure in MEASURES:
        rel = both[f"d_{measure}"]
        print(f"    {measure:<8s} all        {_summary(rel)}")
        for region in ("tread", "flange"):
            print(f"    {measure:<8s} {region:<10s} {_summary(rel[both.region == region])}")
        for rail in ("high", "low", "tangent"):
            print(f"    {measure:<8s} {rail + ' rail':<10s} {_summary(rel[both.rail == rail])}")
    print("    by radius [m]: max |d| tau_max / T-gamma, tread | flange")
    for radius, part in both.groupby("radius_m"):
        cells = []
        for region in ("tread", "flange"):
            p = part[part.region == region]
            cells.append("      -        " if p.empty else
                         f"{100 * p['d_tau_max'].abs().max():6.1f} / "
                         f"{100 * p['d_t_gamma'].abs().max():6.1f} %")
        name = "tangent" if not np.isfinite(radius) else f"{radius:7.0f}"
        print(f"      {name:>7s}  {cells[0]} | {cells[1]}")
    for measure in MEASURES:
        worst = both.reindex(both[f"d_{measure}"].abs().sort_values(ascending=False).index)[:4]
        print(f"    largest {measure} differences:")
        for _, r in worst.iterrows():
            radius = "tangent" if not np.isfinite(r.radius_m) else f"R {r.radius_m:.0f} m"
            print(f"      {r.bogie_type:<7s} {radius:<9s} cant {r.cant_mm:5.0f} mm "
                  f"{r.wheelset:<8s} {r.side:<5s} {r.rail:<7s} {r.region:<6s} table "
                  f"{r[f'{measure}_table']:9.2f}  pipeline {r[f'{measure}_pipe']:9.2f}  "
                  f"({100 * r[f'd_{measure}']:+.1f} %)")
    wheel = [k for k in KEYS if k != "region"]
    n_patches = [c[c.in_contact].drop_duplicates(subset=wheel + ["patch"]).groupby(wheel).size()
                 for c in (table_c.fillna({"radius_m": np.inf}),
                           pipe_c.fillna({"radius_m": np.inf}))]
    counts = pd.concat(n_patches, axis=1, keys=["table", "pipe"]).fillna(0)
    fewer = int((counts["pipe"] < counts["table"]).sum())
    more = int((counts["pipe"] > counts["table"]).sum())
    print(f"    loaded patches per wheel: pipeline fewer (merged) on {fewer}, more on {more} of "
          f"{len(counts)} wheels")
    one = m[m["loaded_table"] != m["loaded_pipe"]]
    print(f"    wheel regions loaded in one model only: {len(one)}")
    for _, r in one.iterrows():
        radius = "tangent" if not np.isfinite(r.radius_m) else f"R {r.radius_m:.0f} m"
        who = "table" if r.loaded_table else "pipeline"
        fn = r.normal_force_n_table if r.loaded_table else r.normal_force_n_pipe
        tg = r.t_gamma_table if r.loaded_table else r.t_gamma_pipe
        tau = r.tau_max_table if r.loaded_table else r.tau_max_pipe
        print(f"      only {who:<8s} {r.bogie_type:<7s} {radius:<9s} cant {r.cant_mm:5.0f} mm "
              f"{r.wheelset:<8s} {r.rail:<7s} {r.region:<6s} Fn {fn:8.0f} N  tau_max "
              f"{tau:7.1f} MPa  T-gamma {tg:7.2f} N")
    keys = ["bogie_type", "wheelset", "rail", "radius_m", "region", "measure"]
    t = table_t.fillna({"radius_m": -1.0}).merge(pipe_t.fillna({"radius_m": -1.0}), on=keys,
                                                 suffixes=("_table", "_pipe"))
    nz = t[(t.value_table > 0) & (t.value_pipe > 0)]
    rel_t = nz.value_pipe / nz.value_table - 1.0
    print(f"    merged table rows (share-weighted), both nonzero: tau_max "
          f"{_summary(rel_t[nz.measure == 'tau_max'])}")
    print(f"    {'':48s}t_gamma {_summary(rel_t[nz.measure == 't_gamma'])}")
    print(f"    merged rows zero in one model only: "
          f"{int(((t.value_table > 0) != (t.value_pipe > 0)).sum())} of {len(t)}")


def pipeline_equilibria(vehicle: str, route):
    """Per bogie type: the pipeline's equilibrium at every distinct class of the route (its
    time per operating point, the scaled residual reached, ``PIPELINE_TOLERANCE``), and the
    (contacts, table) frames of the table's and of the pipeline's contacts at it over the
    classes where it was found (``wear_tables``' rows of ``contact_model="table"`` and
    ``"pipeline_equilibrium"``: what ``wear_table_for_route`` builds, without the classes
    whose pipeline equilibrium was not found, where it raises)."""
    distinct = {(c.radius_m, c.cant_mm, c.speed_kmh): c for c in route.classes}
    classes = list(distinct.values())
    rows: dict[str, list[dict]] = {"table": [], "pipeline_equilibrium": []}
    for bogie_type in ("motor", "trailer"):
        veh = vehicle_preset(vehicle, bogie_type)
        cases, labels, speeds = _operating_points(classes, 0.58, 100.0, None,
                                                  veh.traction_torque_nm)
        t0 = time.perf_counter()
        at_pose = np.array([r.pipeline_residual_norm for r in curving.solve_curving_cases(
            veh, cases, labels, contact_pipeline=True)])
        t_pose = time.perf_counter() - t0
        t0 = time.perf_counter()
        balanced = curving.solve_curving_cases(veh, cases, labels, contact_pipeline=True,
                                               pipeline_equilibrium=True)
        t_eq = time.perf_counter() - t0
        norms = np.array([r.pipeline_residual_norm for r in balanced])
        n = len(cases)
        ok = norms < curving.PIPELINE_TOLERANCE
        print(f"  {vehicle} {bogie_type}: {n} operating points, pipeline equilibrium "
              f"{t_eq / n:.2f} s per point (pipeline at the table's pose {t_pose / n:.2f} s), "
              f"found for {int(ok.sum())} of {n} (residual < {curving.PIPELINE_TOLERANCE:g}); "
              f"residual at the table's pose median {np.median(at_pose):.3f} max "
              f"{np.max(at_pose):.3f}, at the pipeline's equilibrium median "
              f"{np.median(norms):.1e} max {np.max(norms):.1e}")
        for k, c in enumerate(classes):
            if not ok[k]:
                print(f"    not found: R {c.radius_m} m cant {c.cant_mm:g} mm "
                      f"{speeds[k] * 3.6:.0f} km/h, residual {norms[k]:.3g}")
                continue
            for model in rows:
                rows[model].extend(_contact_rows(bogie_type, k, c, balanced[k], speeds[k],
                                                 model))
    out = {}
    for model, r in rows.items():
        contacts = _add_indices(pd.DataFrame(r))
        out[model] = (table_from_contacts(contacts), contacts)
    return out


def route_tables(vehicle: str, route, per_class: bool, models: list[str]) -> None:
    radii = [c.radius_m for c in route.classes]
    cant = [c.cant_mm for c in route.classes]
    speed = [c.speed_kmh for c in route.classes]
    shares = [c.share for c in route.classes]
    args = (vehicle, radii, cant, speed, shares)
    wear_table_for_route(*args)  # warm the contact table and the compiled kernels
    out, seconds = {}, {}
    for model in ["table", "pipeline"]:
        t0 = time.perf_counter()
        out[model] = wear_table_for_route(*args, with_contacts=True, contact_model=model)
        seconds[model] = time.perf_counter() - t0
    n_distinct = len({(c.radius_m, c.cant_mm, c.speed_kmh) for c in route.classes})
    print(f"{route.name} route, {vehicle} ({len(radii)} classes, {n_distinct} distinct, motor "
          f"and trailer): table contacts {seconds['table']:.2f} s, pipeline contacts "
          f"{seconds['pipeline']:.2f} s (x{seconds['pipeline'] / seconds['table']:.0f})")
    if "pipeline" in models:
        compare(f"{route.name} / {vehicle}, pipeline at the table's pose vs table",
                out["table"][1], out["pipeline"][1], out["table"][0], out["pipeline"][0],
                per_class)
    if "pipeline_equilibrium" in models:
        balanced = pipeline_equilibria(vehicle, route)
        (t_t, t_c), (p_t, p_c) = balanced["table"], balanced["pipeline_equilibrium"]
        compare(f"{route.name} / {vehicle}, pipeline at its own equilibrium vs table (distinct "
                "classes where it was found, each with its own share)", t_c, p_c, t_t, p_t,
                per_class)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-class", action="store_true",
                        help="also print every class, wheel and region of both models")
    parser.add_argument("--models", nargs="+", default=["pipeline", "pipeline_equilibrium"],
                        choices=["pipeline", "pipeline_equilibrium"],
                        help="the pipeline's contact models compared with the table's")
    parsed = parser.parse_args()
    print("wear measures from the pipeline's contacts vs the contact table's: at the table's "
          "curving equilibrium (pipeline) and at the pipeline's own (pipeline_equilibrium); "
          "d = pipeline / table - 1")
    route_tables("minuetto", aosta_route(), parsed.per_class, parsed.models)
    route_tables("metro_b", metro_route(), parsed.per_class, parsed.models)


if __name__ == "__main__":
    main()
