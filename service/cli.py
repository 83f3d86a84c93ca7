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
from wearcast.service.id_text import decimal_id
from wearcast.service.rail_cli import HighRailIdOption, LowRailIdOption, RailIdOption
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
    number = decimal_id(value)
    return value if number is None else number


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
    from wearcast.service.http_protocol import problem_http_protocol

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
        # same settings (from the environment), no migration, lost jobs found by heartbeat;
        # what interrupted imports left (pending batches, temporary and orphan raw files) is
        # removed here, before any worker can start an import
        from wearcast.service.housekeeping import clean_after_restart

        clean_after_restart(database.session_factory, settings.data_dir)
        JobRunner(database, settings).recover(all_running=True, dispatch_all=False)
        database.dispose()
        uvicorn.run("wearcast.service.cli:serve_app", factory=True, host=host, port=port,
                    workers=workers, timeout_graceful_shutdown=10, access_log=access_log,
                    http=problem_http_protocol())
    else:
        database.dispose()
        # migrate=True: the one process serving recovers the jobs of the last run
        uvicorn.run(create_app(settings, migrate=True), host=host, port=port,
                    timeout_graceful_shutdown=10, access_log=access_log,
                    http=problem_http_protocol())


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
        rail_id: RailIdOption = None, high_rail_id: HighRailIdOption = None,
        low_rail_id: LowRailIdOption = None) -> None:
    """Compute a curve-radius wear table with the physics core (quasi-static curving)."""
    from wearcast.service import wear_table_store
    from wearcast.service.wear_table_schemas import WearTableComputeIn

    motor, _, trailer = vehicle.partition(",")
    body = _validated(WearTableComputeIn, {
        "name": name, "vehicle": {"motor": motor, "trailer": trailer} if trailer else vehicle,
        "route_id": None if route_id is None else _route_ref(route_id),
        "radii": None if not radius else [_radius(r) for r in radius],
        "unbalanced_acceleration_m_s2": unbalanced_acceleration, "friction": friction,
        "rail_id": rail_id, "high_rail_id": high_rail_id, "low_rail_id": low_rail_id})
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
    from wearcast.statistics.json_values import finite_or_none

    body = _validated(DiagnoseIn, {"filter": _json_option(filter, "filter"),
                                   "save_as": save_as, "causes": cause or None})
    with _session() as (_, session), console.status("diagnosing"):
        run = diagnosis_store.run_diagnosis(session, model_id, body)
        saved, reason = (None, None)
        if save_as is not None:
            saved, reason = diagnosis_store.save_extension(session, run, save_as)
        saved_as = None if saved is None else (saved.id, saved.name)
        if report is not None:
            figures = discrepancy_report.diagnosis_figures(run.diagnosis)
            report.write_text(discrepancy_report.report_html(run.diagnosis, figures),
                              encoding="utf-8")
    d = run.diagnosis  # what the answer of POST /v1/models/{id}/diagnose publishes of it
    table = Table(title=f"model {model_id}: verdict [bold]{d.verdict}[/bold] "
                  f"({d.n_measurements} measurements, {d.n_groups} groups)")
    for column in ("cause", "relative gain [95 % CI]", "p (max-T)", "reported", "summary"):
        table.add_column(column)
    for f in d.findings:
        g = f.gain
        gain = "—" if finite_or_none(g.relative) is None else (
            f"{100 * g.relative:.1f} % [{100 * (finite_or_none(g.ci95_low) or 0):.1f}, "
            f"{100 * (finite_or_none(g.ci95_high) or 0):.1f}]")
        p = f.evidence.get("p_value")
        table.add_row(f.cause, gain, "—" if p is None else f"{p:.2g}",
                      "yes" if f.significant and f.material else "no", f.summary)
    console.print(table)
    for code, why in d.skipped.items():
        console.print(f"skipped {code}: {why}")
    if saved_as is not None:
        console.print(f"saved the extended model as id {saved_as[0]} ({saved_as[1]!r})")
    elif reason:
        console.print(f"nothing saved: {reason}")
    if report is not None:
        console.print(f"wrote {report}")


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


def _add_rails() -> None:
    from wearcast.service.rail_cli import rail_import, rails

    app.command("rail-import")(rail_import)
    app.command("rails")(rails)


_add_rails()


def _add_simulation() -> None:
    from wearcast.service.simulation_cli import fit_coefficients, simulate

    app.command("simulate")(simulate)
    app.command("fit-coefficients")(fit_coefficients)


_add_simulation()


def _add_physics() -> None:
    from wearcast.service.physics_cli import physics_app

    app.add_typer(physics_app, name="physics")


_add_physics()


def main() -> None:
    """Entry point of the ``wearcast`` script."""
    app()


if __name__ == "__main__":
    main()
