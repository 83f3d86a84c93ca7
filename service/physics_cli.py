"""``wearcast physics ...``: physics models from the command line (the same store functions
as ``POST /v1/models`` with ``kind: physics`` and ``POST /v1/models/{id}/diagnose``).

``build`` validates the request like the API (exit 2 naming the field), queues the build job
and runs it in this process; ``diagnose`` runs the physical catalogue's diagnosis of a stored
physics model the same way. Both store their job like an API one and print JSON (``--json``)
or a summary.
"""

from __future__ import annotations

import json
from typing import Annotated, Any

import typer

from wearcast.service.rail_cli import HighRailIdOption, LowRailIdOption, RailIdOption

physics_app = typer.Typer(help="physics models: the whole-vehicle wear loop with a fitted "
                          "wear-coefficient scale", no_args_is_help=True)


class _InProcess:
    """The job runner of the command line: nothing runs in the background; the command runs
    the job it queued itself (``job_store.run_job``). No API key, so no job quota."""

    def __init__(self) -> None:
        self.submitted: list[int] = []

    def check_quota(self, session: Any) -> None:
        return None

    def submit(self, job_id: int) -> None:
        self.submitted.append(job_id)


def _run(factory: Any, job_id: int) -> dict[str, Any]:
    """Run a queued job here; its result, or exit 1 with the job's error."""
    from wearcast.service import cli
    from wearcast.service import models_db as db
    from wearcast.service.job_store import run_job

    run_job(factory, job_id)
    with factory() as session:
        row = session.get(db.Simulation, job_id)
        assert row is not None
        status, error, result = row.status, row.error, row.result
    if status != "done":
        cli.err.print(f"[red]job {job_id} {status}[/red]: {error}")
        raise typer.Exit(1)
    return dict(result or {})


@physics_app.command("build")
def build(name: Annotated[str, typer.Option(help="model name")],
          route_id: Annotated[str, typer.Option("--route", help=(
              "stored route id or name (its curve classes are simulated)"))],
          vehicle: Annotated[str, typer.Option(help="vehicle preset (e.g. minuetto, metro_b)")],
          law: Annotated[str, typer.Option(help="usfd, archard_kth, krause_poll or tau_max")]
          = "usfd",
          filter: Annotated[str | None, typer.Option(help=(
              'JSON filter of the calibration measurements, e.g. \'{"vehicle_id": "DM061"}\' '
              "(default: all)"))] = None,
          simulation: Annotated[str | None, typer.Option(help=(
              'JSON simulation options, e.g. \'{"depth_per_step_mm": 0.8}\''))] = None,
          as_json: Annotated[bool, typer.Option("--json", help="print the model as JSON")]
          = False, rail_id: RailIdOption = None, high_rail_id: HighRailIdOption = None,
          low_rail_id: LowRailIdOption = None) -> None:
    """Build a physics model: the loop run, its wear scale fitted to the measurements."""
    from wearcast.service import cli, physics_model_store
    from wearcast.service.job_store import default_timeout, queue_job
    from wearcast.service.physics_schemas import PhysicsModelIn

    body = cli._validated(PhysicsModelIn, {
        "kind": "physics", "name": name, "vehicle": vehicle, "law": law,
        "route_id": cli._route_ref(route_id),
        "calibration": {"filter": cli._json_option(filter, "filter")},
        "simulation": cli._json_option(simulation, "simulation"), "rail_id": rail_id,
        "high_rail_id": high_rail_id, "low_rail_id": low_rail_id})
    with cli._session() as (database, session):
        spec = physics_model_store.prepare(session, body)
        row = queue_job(session, body.name, spec, timeout_s=default_timeout())
        with cli.console.status(f"building physics model {name!r} (job {row.id})"):
            result = _run(database.session_factory, row.id)
    model = result["model"]
    if as_json:
        typer.echo(json.dumps(model, indent=1))
        return
    p = model["physics"]
    cli.console.print(
        f"physics model {model['id']} ({model['name']!r}): {p['vehicle']}, {p['law']}, wear "
        f"scale {p['wear_scale']:.4g} (P10 {p['wear_scale_p10']:.4g}, P90 "
        f"{p['wear_scale_p90']:.4g}), RMS {p['rms_mm']:.3f} mm; run "
        f"{p['simulation']['mileage_km']:,.0f} km in {p['simulation']['steps']} steps, "
        f"{p['simulation']['elapsed_s']:.1f} s")
    for field, rail in p["rails"].items():
        cli.console.print(f"  {field.removesuffix('_id').replace('_', ' ')}: stored rail "
                          f"{rail['rail_id']} ({rail['name']})")
    for e in p["errors"]["overall"]:
        cli.console.print(f"  {e['quantity']}: bias {e['bias_mm']:+.3f} mm, RMS "
                          f"{e['rms_mm']:.3f} mm over {e['n']} points")
    for w in p["warnings"]:
        cli.console.print(f"  warning: {w}")


@physics_app.command("diagnose")
def diagnose(model_id: Annotated[int, typer.Argument(help="physics model id")],
             cause: Annotated[list[str] | None, typer.Option(help=(
                 "cause of the physical catalogue to try (repeatable; default: all)"))]
             = None,
             filter: Annotated[str | None, typer.Option(help=(
                 "JSON filter of measurements added to the calibration set"))] = None,
             save_as: Annotated[str | None, typer.Option(help=(
                 "store the model extended by the verdict's cause under this name"))] = None,
             seed: Annotated[int, typer.Option(help="seed of the folds and bootstrap")] = 0,
             as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False
             ) -> None:
    """What a physics model gets wrong: the physical catalogue scored out of sample."""
    from wearcast.service import cli, physics_diagnosis_store
    from wearcast.service.diagnosis_schemas import DiagnoseIn

    body = cli._validated(DiagnoseIn, {"filter": cli._json_option(filter, "filter"),
                                       "save_as": save_as, "causes": cause or None,
                                       "seed": seed})
    with cli._session() as (database, session):
        job_id = physics_diagnosis_store.submit(session, _InProcess(), model_id, body)
        with cli.console.status(f"diagnosing physics model {model_id} (job {job_id})"):
            result = _run(database.session_factory, job_id)
    if as_json:
        typer.echo(json.dumps(result, indent=1))
        return
    cli.console.print(f"model {model_id}: verdict {result['verdict']} "
                      f"({result['n_measurements']} points, {result['n_groups']} groups by "
                      f"{result['group_by']}); null scale "
                      f"{result['null_fit']['wear_scale']:.4g}")
    for f in result["findings"]:
        g = f["gain"]
        cli.console.print(f"  {f['cause']:26s} gain {g['relative']:+.3f} "
                          f"[{g['ci95_low']:+.3f}, {g['ci95_high']:+.3f}] at "
                          f"{f['extension']['parameter']} = {f['extension']['value']}")
    for code, why in result["skipped"].items():
        cli.console.print(f"  skipped {code}: {why}")
    if result.get("saved_model"):
        cli.console.print(f"saved the extended model as id {result['saved_model']['id']}")
    elif save_as is not None:
        cli.console.print(f"nothing saved: {result.get('save_reason')}")
