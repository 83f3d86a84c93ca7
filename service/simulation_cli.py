"""``wearcast simulate`` and ``wearcast fit-coefficients``: the wear-loop jobs run in process
with progress (the same store functions as ``/v1/simulations`` and ``/v1/coefficient-fits``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from wearcast.service.rail_cli import HighRailIdOption, LowRailIdOption, RailIdOption

# Options shared by the wear-loop jobs (simulate, fit-coefficients).
VehicleOption = Annotated[str, typer.Option(help="vehicle preset (aln663, manchester, metro_b, "
                                            "minuetto)")]
JobRouteOption = Annotated[str | None, typer.Option("--route", help=(
    "stored route id or name (its curve classes)"))]
JobClassOption = Annotated[list[str] | None, typer.Option("--class", help=(
    "RADIUS_M:CANT_MM:SPEED_KMH:SHARE[:left|right] (repeatable; RADIUS 'tangent')"))]


def simulate(
        vehicle: VehicleOption,
        route_id: JobRouteOption = None,
        curve: JobClassOption = None,
        law: Annotated[str, typer.Option(help="archard_kth, krause_poll, usfd or tau_max")]
        = "archard_kth",
        application: Annotated[str, typer.Option(help="global or local")] = "global",
        patch_width: Annotated[str, typer.Option(help=(
            "hertz or kik_piotrowski (conformal flange-root patches widened)"))] = "hertz",
        steps: Annotated[int, typer.Option(help="number of wheel steps")] = 20,
        step_km: Annotated[float | None, typer.Option(help=(
            "fixed mileage per step [km] (default: adaptive steps by depth)"))] = None,
        depth_per_step_mm: Annotated[float | None, typer.Option(help=(
            "adaptive: maximum worn depth per step [mm] (seed 003: 0.2)"))] = None,
        bogie_type: Annotated[str, typer.Option(help="motor or trailer")] = "trailer",
        axle: Annotated[int, typer.Option(help="tracked wheel's axle (1 leads)")] = 1,
        side: Annotated[str, typer.Option(help="tracked wheel's side")] = "right",
        out: Annotated[Path | None, typer.Option(help="write the result (JSON) here")] = None,
        rail_id: RailIdOption = None, high_rail_id: HighRailIdOption = None,
        low_rail_id: LowRailIdOption = None) -> None:
    """Run the wear loop in process with a progress bar; the job is stored like an API one."""
    from wearcast.service import simulation_store
    from wearcast.service.cli import _num, _route_ref, _session, _validated, console, err
    from wearcast.service.simulation_schemas import SimulationIn

    body = _validated(SimulationIn, {
        "vehicle": vehicle, "route_id": None if route_id is None else _route_ref(route_id),
        "classes": None if not curve else [_loop_class(c) for c in curve], "law": law,
        "application": application, "patch_width": patch_width, "bogie_type": bogie_type,
        "axle": axle, "side": side, "rail_id": rail_id,
        "high_rail_id": high_rail_id, "low_rail_id": low_rail_id,
        "steps": {"mode": "fixed" if step_km is not None else "adaptive", "count": steps,
                  "step_km": step_km, "depth_per_step_mm": depth_per_step_mm}})
    with _session() as (database, session):
        row = simulation_store.create_simulation(session, body)
        columns = (TextColumn("[bold]simulation {task.fields[sim]}"), BarColumn(),
                   TextColumn("{task.completed}/{task.total} steps, {task.fields[km]} km"),
                   TimeElapsedColumn())
        with Progress(*columns, console=err) as bar:
            task = bar.add_task("wear loop", total=body.steps.count, sim=row.id, km="0")

            def advance(done: int, total: int, mileage_km: float) -> None:
                bar.update(task, completed=done, total=total, km=f"{mileage_km:,.0f}")

            simulation_store.run_simulation(database.session_factory, row.id, advance)
        session.expire_all()  # the job wrote its row through sessions of its own
        result = simulation_store.get_simulation(session, row.id)
    if result.status != "done":
        err.print(f"[red]simulation {row.id} failed[/red]: {result.error}")
        raise typer.Exit(1)
    data = result.result or {}
    table = Table(title=f"simulation {row.id}: {law}, {application}")
    for column in ("mileage [km]", "Sh (FH) [mm]", "Sd (FT) [mm]", "qR [mm]",
                   "worn volume [mm³]"):
        table.add_column(column, justify="right")
    for i, km in enumerate(data.get("mileage_km", [])):
        table.add_row(f"{km:,.0f}", _num(data["sh_mm"][i]), _num(data["sd_mm"][i]),
                      _num(data["qr_mm"][i]), _num(data["worn_volume_mm3"][i]))
    console.print(table)
    if out is not None:
        out.write_text(json.dumps(result.model_dump(mode="json")), encoding="utf-8")
        console.print(f"wrote {out}")


def fit_coefficients(
        vehicle: VehicleOption,
        route_id: JobRouteOption = None,
        curve: JobClassOption = None,
        wear_csv: Annotated[Path | None, typer.Option(help=(
            "measured wear curve: CSV with columns y_mm, wear_mm"))] = None,
        measurement_id: Annotated[int | None, typer.Option(
            "--measurement", help="stored measurement id (its wear curve vs S1002)")] = None,
        mileage_km: Annotated[float | None, typer.Option(help=(
            "mileage of the measured wear [km] (default: the measurement's)"))] = None,
        method: Annotated[list[str] | None, typer.Option(help=(
            "exact, GA, PSO, TS, SA or DE (repeatable; default exact)"))] = None,
        law: Annotated[str, typer.Option(help=(
            "fitted law: archard_kth (KTH zones) or tau_max (c_tau)"))] = "archard_kth",
        zone: Annotated[list[int] | None, typer.Option(help=(
            "archard_kth: fitted KTH zone 1-4 (repeatable; default 1 2 3, seed 000)"))] = None,
        tau_threshold_mpa: Annotated[float | None, typer.Option(help=(
            "tau_max: threshold tau_0 [MPa] (default 0)"))] = None,
        tau_coefficient_bounds: Annotated[tuple[float, float] | None, typer.Option(help=(
            "tau_max: LOWER UPPER of c_tau [mm/(m MPa)] (default 1e-8 1e-4)"))] = None,
        step_km: Annotated[float, typer.Option(help="loop step [km] (seed 000: 5000)")] = 5000.0,
        contact_update_depth_mm: Annotated[float, typer.Option(help=(
            "re-solve the contact after this much wear [mm] (0 = every step)"))] = 0.0,
        predict_km: Annotated[float | None, typer.Option(help=(
            "also predict the maximum depth at this mileage [km]"))] = None,
        bogie_type: Annotated[str, typer.Option(help="motor or trailer")] = "trailer",
        axle: Annotated[int, typer.Option(help="tracked wheel's axle (1 leads)")] = 1,
        side: Annotated[str, typer.Option(help="tracked wheel's side")] = "right",
        out: Annotated[Path | None, typer.Option(help="write the result (JSON) here")] = None
        ) -> None:
    """Fit a wear law's coefficients to measured wear (seed 000): the KTH zones, or c_tau of
    the tau_max law; stored like an API job."""
    import pandas as pd

    from wearcast.service import coefficient_fit_store as store
    from wearcast.service.cli import _route_ref, _session, _validated, console, err

    wear = None
    if wear_csv is not None:
        try:
            frame = pd.read_csv(wear_csv)
            wear = {"y_mm": frame["y_mm"].tolist(), "wear_mm": frame["wear_mm"].tolist()}
        except (OSError, KeyError, ValueError) as exc:
            err.print(f"[red]error[/red] wear-csv: cannot read y_mm, wear_mm ({exc})")
            raise typer.Exit(2) from exc
    data: dict[str, Any] = {
        "vehicle": vehicle, "route_id": None if route_id is None else _route_ref(route_id),
        "classes": None if not curve else [_loop_class(c) for c in curve], "wear": wear,
        "measurement_id": measurement_id, "mileage_km": mileage_km,
        "methods": method or ["exact"], "law": law, "step_km": step_km,
        "contact_update_depth_mm": contact_update_depth_mm, "bogie_type": bogie_type,
        "axle": axle, "side": side,
        "predict": None if predict_km is None else {"mileage_km": predict_km}}
    # Only the options given: the API refuses fields of another law than the chosen one.
    for key, value in (("zones", zone), ("tau_threshold_mpa", tau_threshold_mpa),
                       ("tau_coefficient_bounds", tau_coefficient_bounds)):
        if value is not None:
            data[key] = value
    body = _validated(store.CoefficientFitIn, data)
    from wearcast.service import simulation_store

    with _session() as (database, session):
        row = store.create_fit(session, body)
        with console.status(f"fitting (job {row.id})"):
            simulation_store.run_simulation(database.session_factory, row.id)
        session.expire_all()
        result = store.get_fit(session, row.id)
    if result.status != "done":
        err.print(f"[red]coefficient fit {row.id} failed[/red]: {result.error}")
        raise typer.Exit(1)
    res = result.result or {}
    table = Table(title=f"coefficient fit {row.id} (seed 000 Table 2), {res.get('law')}: best "
                  f"{res.get('best_method')}, identifiable "
                  f"{res.get('identifiable_coefficients')}")
    names = (["c_tau_mm_per_m_mpa"] if res.get("law") == "tau_max" else ["k1", "k2", "k3", "k4"])
    columns = (["method", "rmse_mm", "max_depth_mm", "re_max_depth_pct", "time_s"] + names
               + (["max_depth_predict_mm"] if predict_km is not None else []))
    for column in columns:
        table.add_column(column, justify="right")
    for r in res.get("table", []):
        table.add_row(*[str(r[c]) if isinstance(r.get(c), str) else
                        ("—" if r.get(c) is None else f"{r[c]:.4g}") for c in columns])
    console.print(table)
    if out is not None:
        out.write_text(json.dumps(result.model_dump(mode="json")), encoding="utf-8")
        console.print(f"wrote {out}")


def _loop_class(text: str) -> dict[str, Any]:
    from wearcast.service.cli import err

    parts = text.split(":")
    if not 4 <= len(parts) <= 5:
        err.print(f"[red]error[/red] class: {text!r} is not "
                  "RADIUS_M:CANT_MM:SPEED_KMH:SHARE[:DIRECTION]")
        raise typer.Exit(2)
    radius = parts[0].strip().lower()
    out: dict[str, Any] = {"radius_m": None if radius in ("tangent", "inf", "") else radius,
                           "cant_mm": parts[1], "speed_kmh": parts[2] or None,
                           "share": parts[3]}
    if len(parts) == 5:
        out["direction"] = parts[4]
    return out
