"""The ``wearcast`` command line: serve the API, import, compute or upload tables, calibrate,
predict, reprofile, diagnose, simulate, demo.

Every command works on the database named by ``WEARCAST_DATABASE_URL`` (default a SQLite file
in ``WEARCAST_DATA_DIR``, default ``./data``), migrates it first, and calls the same service
layer as the HTTP routes (no HTTP in between). Errors a user can fix print the field and the
reason and exit with status 2.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, Literal, TypeVar

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from wearcast.service.db import Database
from wearcast.service.errors import ApiError
from wearcast.service.settings import Settings

app = typer.Typer(help="wearcast: wheel-profile wear and reprofiling-mileage prediction",
                  no_args_is_help=True, add_completion=False)
console = Console()
err = Console(stderr=True)
T = TypeVar("T")


def _database() -> Database:
    database = Database(Settings())
    database.migrate()
    return database


@contextmanager
def _session() -> Iterator[tuple[Database, Session]]:
    database = _database()
    try:
        with database.session_factory() as session:
            yield database, session
    except ApiError as exc:
        extra = "".join(f", {k} {v}" for k, v in exc.extra.items() if v is not None)
        err.print(f"[red]error[/red] ({exc.status}) {exc.field}{extra}: {exc.reason}")
        raise typer.Exit(2) from exc
    finally:
        database.dispose()


def _show(data: Any) -> None:
    if hasattr(data, "model_dump"):
        data = data.model_dump(mode="json")
    console.print_json(json.dumps(data))


def _json_option(text: str | None, name: str) -> dict[str, Any]:
    if not text:
        return {}
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        err.print(f"[red]error[/red] {name}: not valid JSON ({exc.msg})")
        raise typer.Exit(2) from exc
    if not isinstance(value, dict):
        err.print(f"[red]error[/red] {name}: must be a JSON object")
        raise typer.Exit(2)
    return value


def _route_ref(value: str) -> int | str:
    return int(value) if value.isdigit() else value


@app.command()
def serve(host: Annotated[str, typer.Option(help="interface to bind")] = "127.0.0.1",
          port: Annotated[int, typer.Option(help="TCP port")] = 8000,
          load_example: Annotated[bool, typer.Option(
              help="load the bundled example fleet when the database is empty")] = False,
          workers: Annotated[int, typer.Option(
              min=1, help="uvicorn worker processes (e.g. one per CPU core)")] = 1,
          access_log: Annotated[bool, typer.Option(
              help="log every request (uvicorn's access log); off spares each request "
                   "a formatted log line")] = True,
          ) -> None:
    """Migrate the database, optionally load the example fleet, and serve the /v1 API.

    With ``--workers N`` > 1 uvicorn runs N processes, each building the app with
    :func:`serve_app` (the database is migrated once, here, before they start).
    """
    import uvicorn

    from wearcast.service import models_db as db
    from wearcast.service.app import create_app

    settings = Settings()
    database = Database(settings)
    database.migrate()
    if load_example:
        with database.session_factory() as session:
            empty = not session.scalar(select(func.count()).select_from(db.Measurement))
        if empty:
            try:
                from wearcast.service.demo import load_example_fleet
            except ImportError:
                err.print("example fleet not available (wearcast.service.demo missing)")
            else:
                ids = load_example_fleet(database.session_factory, settings.raw_dir)
                console.print(f"example fleet loaded: {ids}")
        else:
            console.print("database not empty: example fleet not loaded")
    from wearcast.service.auth import bootstrap_admin_key
    from wearcast.service.jobs import JobRunner

    bootstrap_admin_key(database.session_factory, settings)  # printed once, on a first start
    console.print(f"serving {settings.resolved_database_url} on http://{host}:{port}/v1"
                  + (f" with {workers} workers" if workers > 1 else ""))
    if workers > 1:
        # jobs the last run left running are queued again; worker processes import the app:
        # same settings (from the environment), no migration, lost jobs found by heartbeat
        JobRunner(database, settings).recover(all_running=True, dispatch_all=False)
        database.dispose()
        uvicorn.run("wearcast.service.cli:serve_app", factory=True, host=host, port=port,
                    workers=workers, timeout_graceful_shutdown=10, access_log=access_log)
    else:
        database.dispose()
        # migrate=True: the one process serving recovers the jobs of the last run
        uvicorn.run(create_app(settings, migrate=True), host=host, port=port,
                    timeout_graceful_shutdown=10, access_log=access_log)


@app.command()
def worker(processes: Annotated[int, typer.Option(min=1, help="worker processes")] = 1,
           threads: Annotated[int, typer.Option(min=1, help="threads per process")] = 1,
           ) -> None:
    """Run jobs from the queue (``WEARCAST_JOB_QUEUE=dramatiq`` on the API): Dramatiq worker
    processes on ``WEARCAST_BROKER_URL`` and the API's database."""
    import os
    import sys

    database = _database()  # migrated before any job runs
    database.dispose()
    os.execvp(sys.executable, [sys.executable, "-m", "dramatiq", "wearcast.service.job_queue",
                               "--processes", str(processes), "--threads", str(threads)])


def serve_app() -> Any:
    """The app of one ``serve --workers N`` worker process (database already migrated)."""
    from wearcast.service.app import create_app

    return create_app(Settings(), migrate=False)


@app.command()
def migrate() -> None:
    """Bring the database schema to the newest migration (and make sure an admin API key
    exists: ``WEARCAST_API_KEY``, or one created and printed on the first run)."""
    from wearcast.service.auth import bootstrap_admin_key

    database = _database()
    bootstrap_admin_key(database.session_factory, database.settings)
    console.print(f"migrated {database.settings.resolved_database_url}")
    database.dispose()


@app.command("import")
def import_(file: Annotated[Path, typer.Argument(exists=True, dir_okay=False,
                                                 help="long CSV, parameter CSV, MiniProf, zip")],
            manifest: Annotated[Path | None, typer.Option(exists=True, dir_okay=False,
                                                          help="manifest CSV")] = None,
            idempotency_key: Annotated[str | None, typer.Option(help="Idempotency-Key")]
            = None) -> None:
    """Import measurements (one transaction; a repeated file creates nothing)."""
    from wearcast.service import importing

    with _session() as (database, session), file.open("rb") as stream, Progress(
            TextColumn("[bold]importing {task.description}"), BarColumn(),
            TextColumn("{task.completed} measurements"), TimeElapsedColumn(),
            console=err, transient=True) as progress:
        task = progress.add_task(file.name, total=None)
        result = importing.import_upload(
            session, database.settings.raw_dir, stream, file.name,
            manifest=manifest.read_bytes() if manifest else None,
            manifest_name=manifest.name if manifest else None,
            idempotency_key=idempotency_key, chunk_size=database.settings.import_chunk_size,
            progress=lambda n: progress.advance(task, n))
    _show(result.as_dict())


@app.command()
def route(file: Annotated[Path, typer.Argument(exists=True, dir_okay=False,
                                               help="JSON: {name, classes|segments, ...}")]
          ) -> None:
    """Store a route from a JSON file (the POST /v1/routes body, or a list of them)."""
    from pydantic import ValidationError

    from wearcast.service import route_store
    from wearcast.service.route_schemas import RouteIn

    data = json.loads(file.read_text())
    with _session() as (_, session):
        for body in data if isinstance(data, list) else [data]:
            try:
                parsed = RouteIn.model_validate(body)
            except ValidationError as exc:
                first = exc.errors()[0]
                raise ApiError(422, ".".join(map(str, first["loc"])), first["msg"]) from exc
            _show(route_store.route_out(route_store.create_route(session, parsed)))


@app.command("wear-table")
def wear_table(file: Annotated[Path, typer.Argument(exists=True, dir_okay=False,
                                                    help="curve-radius table CSV")],
               name: Annotated[str | None, typer.Option(help="table name")] = None) -> None:
    """Store a curve-radius wear table (CSV)."""
    from wearcast.service import wear_table_store

    with _session() as (_, session):
        row = wear_table_store.upload_wear_table(session, file.read_bytes(), file.name, name)
        _show(wear_table_store.wear_table_out(session, row, with_rows=False))


RailIdOption = Annotated[int | None, typer.Option("--rail-id", help=(
    "stored measured rail (wearcast rails) in place of the nominal rail, both sides"))]


@app.command("rail-import")
def rail_import(
        file: Annotated[Path, typer.Argument(exists=True, dir_okay=False,
                                             help="MiniProf rail file (.ban, .mpt)")],
        name: Annotated[str | None, typer.Option(help="rail name")] = None,
        gauge_side: Annotated[str | None, typer.Option(help=(
            "negative_x or positive_x: instrument-X side of the gauge face"))] = None,
        inclination: Annotated[str | None, typer.Option(help="laying slope, e.g. 1/40")]
        = None,
        reference: Annotated[str, typer.Option(help="60E1, UIC60, 60E2 or rail:<id>")]
        = "60E1") -> None:
    """Import the rail profiles of a MiniProf file (a repeated file creates nothing)."""
    from wearcast.service import rail_store

    if gauge_side not in (None, "negative_x", "positive_x"):
        raise_field("gauge_side", "must be negative_x or positive_x")
    with _session() as (database, session):
        result = rail_store.import_rail_file(
            session, file.read_bytes(), file.name, name=name,
            gauge_side=gauge_side,  # type: ignore[arg-type]
            inclination=rail_store.parse_inclination(inclination), reference=reference,
            raw_dir=database.settings.raw_dir)
        _show({"file_name": result.file_name,
               "created": [_rail_summary(r) for r in result.created],
               "duplicates": [_rail_summary(r) for r in result.duplicates],
               "skipped": [s.model_dump() for s in result.skipped],
               "warnings": result.warnings})


@app.command()
def rails(reference: Annotated[str | None, typer.Option(help=(
              "take the head wear against this head (60E1, UIC60, 60E2, rail:<id>)"))] = None
          ) -> None:
    """List the stored rails with their head wear (W1 vertical, W2 gauge face, W3 45 deg)."""
    from wearcast.service import rail_store

    with _session() as (_, session):
        items = rail_store.list_rails(session, limit=1000, reference=reference)
    table = Table(title="measured rails: head wear \\[mm] (+ = metal lost)")
    for column in ("id", "name", "kind", "reference", "datum", "W1 vertical", "W2 gauge face",
                   "W3 45°", "fits"):
        table.add_column(column, justify="right" if column.startswith("W") else "left")
    for r in items:
        w = r.wear
        table.add_row(str(r.id), r.name, r.kind, w.reference,
                      "fitted" if w.placement.fitted else "instrument", _num(w.vertical.value_mm),
                      _num(w.lateral.value_mm), _num(w.corner_45.value_mm),
                      "yes" if w.reference_fits else "NO")
    console.print(table)
    for r in items:
        for reason in r.wear.mismatch:
            console.print(f"rail {r.id}: {reason}")


def _r3(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_r3(v) for v in value]
    return None if value is None else round(float(value), 3)


def _rail_summary(rail: Any) -> dict[str, Any]:
    w = rail.wear
    return {"id": rail.id, "name": rail.name, "kind": rail.kind, "part": rail.part,
            "top_mm": _r3(rail.frame.top_mm), "gauge_point_mm": _r3(rail.frame.gauge_point_mm),
            "head_width_mm": _r3(rail.frame.head_width_mm),
            "wear": {"reference": w.reference, "placement": w.placement.method,
                     "W1_vertical_mm": _r3(w.vertical.value_mm),
                     "W2_gauge_face_mm": _r3(w.lateral.value_mm),
                     "W3_45deg_mm": _r3(w.corner_45.value_mm),
                     "reference_fits": w.reference_fits, "mismatch": w.mismatch}}


def raise_field(field: str, reason: str) -> None:
    err.print(f"[red]error[/red] {field}: {reason}")
    raise typer.Exit(2)


@app.command("wear-table-compute")
def wear_table_compute(
        name: Annotated[str, typer.Option(help="table name")],
        vehicle: Annotated[str, typer.Option(help=(
            "vehicle preset (aln663, manchester, metro_b, minuetto) or MOTOR,TRAILER presets"))],
        route_id: Annotated[str | None, typer.Option("--route", help=(
            "stored route id or name whose curve classes give the radii"))] = None,
        radius: Annotated[list[str] | None, typer.Option(help=(
            "RADIUS_M[:CANT_MM[:SPEED_KMH]] (repeatable; 'tangent' for straight track)"))]
        = None,
        unbalanced_acceleration: Annotated[float, typer.Option(
            help="a_nc for radii without a speed [m/s²]")] = 0.58,
        friction: Annotated[float | None, typer.Option(help="wheel-rail friction")] = None,
        csv: Annotated[Path | None, typer.Option(help="also write the table here (CSV)")]
        = None,
        rail_id: RailIdOption = None) -> None:
    """Compute a curve-radius wear table with the physics core (quasi-static curving)."""
    from wearcast.service import wear_table_store
    from wearcast.service.wear_table_schemas import WearTableComputeIn

    motor, _, trailer = vehicle.partition(",")
    body = _validated(WearTableComputeIn, {
        "name": name, "vehicle": {"motor": motor, "trailer": trailer} if trailer else vehicle,
        "route_id": None if route_id is None else _route_ref(route_id),
        "radii": None if not radius else [_radius(r) for r in radius],
        "unbalanced_acceleration_m_s2": unbalanced_acceleration, "friction": friction,
        "rail_id": rail_id})
    with _session() as (_, session), console.status("solving the curving equilibria"):
        row = wear_table_store.compute_wear_table(session, body)
        if csv is not None:
            frame = wear_table_store.table_frame(session, row.id)
            csv.write_bytes(wear_table_store.canonical_csv(frame))
        _show(wear_table_store.wear_table_out(session, row, with_rows=False))


def _radius(text: str) -> dict[str, Any]:
    parts = text.split(":")
    if len(parts) > 3:
        err.print(f"[red]error[/red] radius: {text!r} is not RADIUS_M[:CANT_MM[:SPEED_KMH]]")
        raise typer.Exit(2)
    head = parts[0].strip().lower()
    out: dict[str, Any] = {"radius_m": None if head in ("tangent", "inf", "") else head}
    if len(parts) > 1:
        out["cant_mm"] = parts[1]
    if len(parts) > 2:
        out["speed_kmh"] = parts[2]
    return out


@app.command()
def diagnose(model_id: Annotated[int, typer.Argument(help="model id")],
             filter: Annotated[str | None, typer.Option(
                 help='JSON filter of the measurements to diagnose, e.g. \'{"route_id": '
                      '"metro"}\' (default: all)')] = None,
             report: Annotated[Path | None, typer.Option(
                 help="write the HTML report (with the figures) here")] = None,
             save_as: Annotated[str | None, typer.Option(
                 help="store the model extended by the verdict's cause under this name")]
             = None,
             cause: Annotated[list[str] | None, typer.Option(
                 help="cause code to try (repeatable; default: the whole catalogue)")] = None
             ) -> None:
    """What the model gets wrong, the named cause, the extended model and its gain."""
    from wearcast.service import diagnosis_store
    from wearcast.service.diagnosis_schemas import DiagnoseIn
    from wearcast.statistics import discrepancy_report

    body = _validated(DiagnoseIn, {"filter": _json_option(filter, "filter"),
                                   "save_as": save_as, "causes": cause or None})
    with _session() as (_, session), console.status("diagnosing"):
        run = diagnosis_store.run_diagnosis(session, model_id, body)
        saved, reason = (None, None)
        if save_as is not None:
            saved, reason = diagnosis_store.save_extension(session, run, save_as)
        out = diagnosis_store.diagnosis_out(session, model_id, run, saved, reason)
        if report is not None:
            figures = discrepancy_report.diagnosis_figures(run.diagnosis)
            report.write_text(discrepancy_report.report_html(run.diagnosis, figures),
                              encoding="utf-8")
    table = Table(title=f"model {model_id}: verdict [bold]{out.verdict}[/bold] "
                  f"({out.n_measurements} measurements, {out.n_groups} groups)")
    for column in ("cause", "relative gain [95 % CI]", "p (max-T)", "reported", "summary"):
        table.add_column(column)
    for f in out.findings:
        g = f.gain
        gain = "—" if g.relative is None else (
            f"{100 * g.relative:.1f} % [{100 * (g.ci95_low or 0):.1f}, "
            f"{100 * (g.ci95_high or 0):.1f}]")
        p = f.evidence.get("p_value")
        table.add_row(f.cause, gain, "—" if p is None else f"{p:.2g}",
                      "yes" if f.significant and f.material else "no", f.summary)
    console.print(table)
    for code, why in out.skipped.items():
        console.print(f"skipped {code}: {why}")
    if out.saved_model is not None:
        console.print(f"saved the extended model as id {out.saved_model.id} "
                      f"({out.saved_model.name!r})")
    elif reason:
        console.print(f"nothing saved: {reason}")
    if report is not None:
        console.print(f"wrote {report}")


# Options shared by the wear-loop jobs (simulate, fit-coefficients).
VehicleOption = Annotated[str, typer.Option(help="vehicle preset (aln663, manchester, metro_b, "
                                            "minuetto)")]
JobRouteOption = Annotated[str | None, typer.Option("--route", help=(
    "stored route id or name (its curve classes)"))]
JobClassOption = Annotated[list[str] | None, typer.Option("--class", help=(
    "RADIUS_M:CANT_MM:SPEED_KMH:SHARE[:left|right] (repeatable; RADIUS 'tangent')"))]


@app.command()
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
        rail_id: RailIdOption = None) -> None:
    """Run the wear loop in process with a progress bar; the job is stored like an API one."""
    from wearcast.service import simulation_store
    from wearcast.service.simulation_schemas import SimulationIn

    body = _validated(SimulationIn, {
        "vehicle": vehicle, "route_id": None if route_id is None else _route_ref(route_id),
        "classes": None if not curve else [_loop_class(c) for c in curve], "law": law,
        "application": application, "patch_width": patch_width, "bogie_type": bogie_type,
        "axle": axle, "side": side, "rail_id": rail_id,
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


@app.command("fit-coefficients")
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


@app.command()
def calibrate(name: Annotated[str, typer.Option(help="model name")],
              wear_table_id: Annotated[int, typer.Option(help="stored wear table id")],
              route_id: Annotated[str, typer.Option("--route", help="calibration route")],
              measure: Annotated[str, typer.Option(help="tau_max or t_gamma")] = "tau_max",
              running_mode: Annotated[str, typer.Option(help="lead or mixed")] = "mixed",
              filter: Annotated[str | None, typer.Option(
                  help='JSON filter, e.g. \'{"bogie_type": "motor"}\'')] = None) -> None:
    """Calibrate a hybrid model (seed 001 eq. 3) on the filtered measurements."""
    from wearcast.service import model_store
    from wearcast.service.model_schemas import ModelIn

    body = _validated(ModelIn, {
        "name": name, "measure": measure, "running_mode": running_mode,
        "wear_table_id": wear_table_id,
        "calibration": {"route_id": _route_ref(route_id),
                        "filter": _json_option(filter, "filter")}})
    with _session() as (_, session), console.status("calibrating"):
        row = model_store.create_model(session, body)
        _show(model_store.model_out(session, row))


def _validated(model: Callable[..., T], data: dict[str, Any]) -> T:
    from pydantic import ValidationError

    try:
        return model.model_validate(data)  # type: ignore[attr-defined, no-any-return]
    except ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(p) for p in first["loc"]) or "input"
        err.print(f"[red]error[/red] {field}: {first['msg']}")
        raise typer.Exit(2) from exc


@app.command()
def predict(model_id: Annotated[int, typer.Argument(help="model id")],
            route_id: Annotated[str, typer.Option("--route", help="route id or name")],
            bogie_type: Annotated[str, typer.Option(help="motor or trailer")],
            axle: Annotated[int, typer.Option(help="1 or 2")],
            side: Annotated[str, typer.Option(help="left or right")],
            mileage_km: Annotated[list[float], typer.Option(help="mileage [km], repeatable")],
            picture: Annotated[Path | None, typer.Option(
                help="also write the wear-area picture here (.svg or .png)")] = None) -> None:
    """Predict wear areas, Sd/Sh/qR (and the worn profile) per mileage."""
    from wearcast.service import pictures, prediction_store
    from wearcast.service.prediction_schemas import PredictIn

    body = _validated(PredictIn, {"route_id": _route_ref(route_id), "bogie_type": bogie_type,
                                  "axle": axle, "side": side, "mileage_km": mileage_km})
    with _session() as (_, session):
        result = prediction_store.predict(session, model_id, body)
        table = Table(title=f"model {model_id} on {result.route}: {bogie_type} axle {axle} "
                      f"{side}")
        for column in ("mileage [km]", "flange A P10/P50/P90 [mm²]",
                       "tread A P10/P50/P90 [mm²]", "Sd", "Sh", "qR [mm]"):
            table.add_column(column, justify="right")
        for p in result.points:
            table.add_row(f"{p.mileage_km:,.0f}", _band(p.flange_area_mm2),
                          _band(p.tread_area_mm2), _num(p.sd_mm), _num(p.sh_mm), _num(p.qr_mm))
        console.print(table)
        if picture is not None:
            fmt: Literal["png", "svg"] = "png" if picture.suffix.lower() == ".png" else "svg"
            picture.write_bytes(pictures.wear_area_picture(
                session, model_id, route_id=_route_ref(route_id), bogie_type=bogie_type,
                axle=axle, side=side, max_mileage_km=max(max(mileage_km), 1.0), fmt=fmt))
            console.print(f"wrote {picture}")


def _num(value: float | None) -> str:
    return "—" if value is None else f"{value:.2f}"


def _band(q: Any) -> str:
    return f"{q.p10:.1f} / {q.p50:.1f} / {q.p90:.1f}"


@app.command()
def reprofile(model_id: Annotated[int, typer.Argument(help="model id")],
              route_id: Annotated[str, typer.Option("--route", help="route id or name")],
              wheel_id: Annotated[str | None, typer.Option(
                  help="start from this wheel's latest measurement")] = None,
              bogie_type: Annotated[str | None, typer.Option()] = None,
              axle: Annotated[int | None, typer.Option()] = None,
              side: Annotated[str | None, typer.Option()] = None,
              sd_min_mm: Annotated[float | None, typer.Option()] = None,
              sh_max_mm: Annotated[float | None, typer.Option()] = None,
              qr_min_mm: Annotated[float | None, typer.Option()] = None) -> None:
    """Mileage to the first Sd/Sh/qR limit (P10/P50/P90) and the governing limit."""
    from wearcast.service import reprofiling_store
    from wearcast.service.reprofiling_schemas import ReprofilingIn

    limits = {k: v for k, v in (("sd_min_mm", sd_min_mm), ("sh_max_mm", sh_max_mm),
                                ("qr_min_mm", qr_min_mm)) if v is not None}
    body = _validated(ReprofilingIn, {
        "route_id": _route_ref(route_id), "wheel_id": wheel_id, "bogie_type": bogie_type,
        "axle": axle, "side": side, "limits": limits or None})
    with _session() as (_, session):
        _show(reprofiling_store.reprofiling(session, model_id, body))


@app.command()
def picture(model_id: Annotated[int, typer.Argument(help="model id")],
            kind: Annotated[str, typer.Argument(help="wear-area or profile")],
            out: Annotated[Path, typer.Argument(help="output file (.svg or .png)")],
            route_id: Annotated[str, typer.Option("--route", help="route id or name")],
            bogie_type: Annotated[str, typer.Option()],
            axle: Annotated[int, typer.Option()],
            side: Annotated[str, typer.Option()],
            mileage_km: Annotated[float, typer.Option(help="for the profile picture")]
            = 100_000.0,
            wheel_id: Annotated[str | None, typer.Option()] = None) -> None:
    """Write a picture: wear area over mileage (Fig. 11) or the worn profile (Figs. 12–14)."""
    from wearcast.service import pictures

    if kind not in {"wear-area", "profile"}:
        err.print("[red]error[/red] kind: must be wear-area or profile")
        raise typer.Exit(2)
    fmt = "png" if out.suffix.lower() == ".png" else "svg"
    position = {"route_id": _route_ref(route_id), "bogie_type": bogie_type, "axle": axle,
                "side": side, "wheel_id": wheel_id, "fmt": fmt}
    with _session() as (_, session):
        if kind == "wear-area":
            image = pictures.wear_area_picture(session, model_id, **position)  # type: ignore[arg-type]
        else:
            image = pictures.profile_picture(session, model_id, mileage_km=mileage_km,
                                             **position)  # type: ignore[arg-type]
    out.write_bytes(image)
    console.print(f"wrote {out}")


@app.command()
def demo(out_dir: Annotated[Path, typer.Option(help="where the demo database and pictures go")]
         = Path("demo-output")) -> None:
    """Run the example: calibrate on unit A's motor bogies and predict the rest."""
    try:
        from wearcast.service.demo import run_demo
    except ImportError as exc:
        err.print("the demo is not available (wearcast.service.demo missing)")
        raise typer.Exit(1) from exc
    run_demo(out_dir, echo=console.print)


def _add_planning() -> None:
    from wearcast.service.planning_cli import plan_app

    app.add_typer(plan_app, name="plan")


_add_planning()


def _add_contact() -> None:
    from wearcast.service.contact_cli import contact

    app.command("contact")(contact)


_add_contact()


def _add_physics() -> None:
    from wearcast.service.physics_cli import physics_app

    app.add_typer(physics_app, name="physics")


_add_physics()


def main() -> None:
    """Entry point of the ``wearcast`` script."""
    app()


if __name__ == "__main__":
    main()
