"""``wearcast plan ...``: fleets, vehicle attributes, fleet state and lathe plans from the
command line (the same store functions as ``/v1/fleets``, ``/v1/fleet/state``, ``/v1/plans``).
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path
from typing import Annotated, Any

import typer

from wearcast.service.id_text import decimal_id

plan_app = typer.Typer(help="maintenance planning: fleet state and lathe plans",
                       no_args_is_help=True)
FleetOption = Annotated[str | None, typer.Option("--fleet", help="fleet id (default: all)")]
ModelOption = Annotated[int | None, typer.Option(help=(
    "calibrated model forecasting wheels with fewer than 2 measurements since turning"))]
RouteOption = Annotated[str | None, typer.Option("--route", help="the model's route id/name")]
FormatOption = Annotated[str, typer.Option("--format", help="json or csv")]
OutOption = Annotated[Path | None, typer.Option(help="write the answer to this file")]


def _route(value: str | None) -> int | str | None:
    number = None if value is None else decimal_id(value)
    return value if number is None else number


def _emit(data: Any, text: str | None, out: Path | None) -> None:
    from wearcast.service import cli

    if out is not None:
        out.write_text(text if text is not None else json.dumps(data, indent=1))
        cli.console.print(f"wrote {out}")
    elif text is not None:
        typer.echo(text, nl=False)
    else:
        cli._show(data)


def _check_format(fmt: str) -> None:
    if fmt not in ("json", "csv"):
        from wearcast.service import cli

        cli.err.print(f"[red]error[/red] format: {fmt!r} is not one of json, csv")
        raise typer.Exit(2)


@plan_app.command("fleet")
def fleet(fleet_id: Annotated[str, typer.Argument(help="fleet id")],
          limits: Annotated[str | None, typer.Option(help=(
              'limit overrides as JSON, e.g. \'{"sd_min_mm": 20, "scrap_diameter_mm": 850}\''
          ))] = None,
          vehicle: Annotated[list[str] | None, typer.Option(help="vehicle of the fleet")]
          = None) -> None:
    """Create or replace a fleet's limits and add vehicles to it."""
    from wearcast.service import cli, planning_store
    from wearcast.service.planning_schemas import FleetIn

    body = FleetIn(limits=cli._json_option(limits, "limits"), vehicles=vehicle or [])
    with cli._session() as (_, session):
        _emit(planning_store.put_fleet(session, fleet_id, body), None, None)


@plan_app.command("vehicle")
def vehicle(vehicle_id: Annotated[str, typer.Argument(help="vehicle id")],
            km_per_day: Annotated[float | None, typer.Option(help="mileage per day [km]")]
            = None, fleet_id: FleetOption = None) -> None:
    """Set a vehicle's mileage per day and fleet."""
    from wearcast.service import cli, planning_store
    from wearcast.service.planning_schemas import VehicleIn

    with cli._session() as (_, session):
        _emit(planning_store.put_vehicle(session, vehicle_id,
                                         VehicleIn(km_per_day=km_per_day, fleet_id=fleet_id)),
              None, None)


@plan_app.command("state")
def state(fleet_id: FleetOption = None, model_id: ModelOption = None,
          route_id: RouteOption = None, fmt: FormatOption = "json",
          out: OutOption = None) -> None:
    """Every wheel's latest state, remaining km to each limit (P10/P50/P90) and dates."""
    from wearcast.service import cli, planning_store

    _check_format(fmt)
    with cli._session() as (_, session):
        payload = planning_store.state_payload(session, fleet_id, model_id, _route(route_id))
    _emit(payload, planning_store.state_csv(payload) if fmt == "csv" else None, out)


@plan_app.command("create")
def create(capacity: Annotated[int, typer.Option(help="wheelsets the lathe turns a week")],
           weeks: Annotated[int, typer.Option(help="horizon [weeks]")] = 26,
           fleet_id: FleetOption = None,
           start: Annotated[str | None, typer.Option(help="first day (YYYY-MM-DD)")] = None,
           fixed_interval_km: Annotated[float, typer.Option(help=(
               "the fixed-mileage policy the plan is compared with [km]"))] = 150_000.0,
           model_id: ModelOption = None, route_id: RouteOption = None,
           keep_diameter_differences: Annotated[bool, typer.Option(help=(
               "keep bogie and vehicle diameter differences within the fleet's limits"))]
           = True,
           fmt: FormatOption = "json", out: OutOption = None) -> None:
    """Compute and store a lathe plan; print it (JSON) or its rows (CSV)."""
    from pydantic import ValidationError

    from wearcast.service import cli, planning_store
    from wearcast.service.planning_schemas import PlanIn

    _check_format(fmt)
    try:
        body = PlanIn(fleet_id=fleet_id, capacity_per_week=capacity, horizon_weeks=weeks,
                      start=dt.date.fromisoformat(start) if start else None,
                      fixed_interval_km=fixed_interval_km, model_id=model_id,
                      route_id=_route(route_id),
                      keep_diameter_differences=keep_diameter_differences)
    except (ValidationError, ValueError) as exc:
        cli.err.print(f"[red]error[/red] {exc}")
        raise typer.Exit(2) from exc
    with cli._session() as (_, session):
        plan = planning_store.create_plan(session, body)
    _emit(plan, planning_store.plan_csv(plan) if fmt == "csv" else None, out)


@plan_app.command("show")
def show(plan_id: Annotated[int, typer.Argument(help="plan id")], fmt: FormatOption = "json",
         out: OutOption = None) -> None:
    """A stored plan as JSON or CSV."""
    from wearcast.service import cli, planning_store

    _check_format(fmt)
    with cli._session() as (_, session):
        plan = planning_store.get_plan(session, plan_id)
    _emit(plan, planning_store.plan_csv(plan) if fmt == "csv" else None, out)
