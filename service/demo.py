"""The bundled example fleet and the demo (``wearcast demo``, ``make run``).

``load_example_fleet`` puts the example (``service/example_fleet/``: routes, curve-radius
table, long-CSV profiles — see its README) into a database through the service layer, and is
idempotent. ``run_demo`` does what seed 001 did with its trains: calibrate on unit A's motor
bogies, predict unit A's trailer bogies, unit B (another route) and a new route (100 %
tangent), and print predicted vs measured wear areas and the reprofiling mileages.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

EXAMPLE_DIR = Path(__file__).resolve().parent / "example_fleet"
PROFILES_FILE = "profiles.csv"
ROUTES_FILE = "routes.json"
TABLE_FILE = "wear_table.csv"
TABLE_NAME = "example synthetic table"
CALIBRATION_ROUTE = "aosta"
NEW_ROUTE = "tangent"
#: Mileage at which predicted and measured wear areas are compared [km].
COMPARE_AT_KM = 200_000.0


@dataclass(frozen=True)
class ExampleIds:
    """What ``load_example_fleet`` stored (or found already stored)."""

    route_ids: dict[str, int]
    wear_table_id: int
    batch_id: int | None
    measurements_created: int


def _routes() -> list[dict[str, Any]]:
    return json.loads((EXAMPLE_DIR / ROUTES_FILE).read_text())


def _is_http_client(target: Any) -> bool:
    return hasattr(target, "post") and hasattr(target, "get")


def load_example_fleet(target: Any, raw_dir: Path | None = None) -> ExampleIds:
    """Load the bundled routes, wear table and profiles; idempotent.

    Parameters
    ----------
    target : a SQLAlchemy session factory (callable returning a ``Session``; then ``raw_dir``,
        where uploaded files are kept, is required) or an HTTP client of the app (FastAPI
        ``TestClient`` or an ``httpx.Client`` with ``base_url`` set)
    raw_dir : directory for the raw uploaded file (session-factory path only)

    A second call creates nothing: routes are found by name, the table by its content's
    SHA-256, and the import pipeline recognises the same file.
    """
    if _is_http_client(target):
        return _load_over_http(target)
    if raw_dir is None:
        raise ValueError("raw_dir: required when loading through a session factory")
    return _load_with_session(target, Path(raw_dir))


def _load_with_session(session_factory: Callable[[], Session], raw_dir: Path) -> ExampleIds:
    from wearcast.service import importing, route_store, wear_table_store
    from wearcast.service import models_db as db
    from wearcast.service.route_schemas import RouteIn

    route_ids: dict[str, int] = {}
    with session_factory() as session:
        for body in _routes():
            row = route_store.find_route(session, body["name"])
            if row is None:
                row = route_store.create_route(session, RouteIn(**body))
            route_ids[body["name"]] = int(row.id)
        data = (EXAMPLE_DIR / TABLE_FILE).read_bytes()
        sha = hashlib.sha256(data).hexdigest()
        table = session.scalar(select(db.WearTable).where(db.WearTable.sha256 == sha).limit(1))
        if table is None:
            table = wear_table_store.upload_wear_table(session, data, TABLE_FILE, TABLE_NAME)
        table_id = int(table.id)
        with (EXAMPLE_DIR / PROFILES_FILE).open("rb") as stream:
            result = importing.import_upload(session, raw_dir, stream, PROFILES_FILE)
    return ExampleIds(route_ids, table_id, result.batch_id, result.created)


def _load_over_http(client: Any) -> ExampleIds:
    route_ids: dict[str, int] = {}
    for body in _routes():
        response = client.post("/v1/routes", json=body)
        if response.status_code == 409:
            response = client.get(f"/v1/routes/{body['name']}")
        response.raise_for_status()
        route_ids[body["name"]] = int(response.json()["id"])
    data = (EXAMPLE_DIR / TABLE_FILE).read_bytes()
    sha = hashlib.sha256(data).hexdigest()
    # The same content always carries the same Idempotency-Key, so a reload creates nothing.
    response = client.post("/v1/measurements/import",
                           files={"file": (PROFILES_FILE, (EXAMPLE_DIR / PROFILES_FILE)
                                           .read_bytes(), "text/csv")})
    response.raise_for_status()
    imported = response.json()
    response = client.post("/v1/wear-tables", files={"file": (TABLE_FILE, data, "text/csv")},
                           data={"name": f"{TABLE_NAME} {sha[:12]}"})
    response.raise_for_status()
    return ExampleIds(route_ids, int(response.json()["id"]), imported.get("batch_id"),
                      int(imported.get("created", 0)))


# --------------------------------------------------------------------------------------------
# The demo
# --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class DemoRow:
    """One wheel position of the demo table (areas in mm², mileages in km)."""

    role: str
    route: str
    bogie_type: str
    axle: int
    measured_tread_mm2: float | None
    predicted_tread_mm2: tuple[float, float, float]
    measured_flange_mm2: float | None
    predicted_flange_mm2: tuple[float, float, float]
    reprofiling_km: tuple[float | None, float | None, float | None]
    governing_limit: str | None


@dataclass(frozen=True)
class DemoDiagnosis:
    """What the demo's diagnosis found (``run_demo`` step 2)."""

    verdict: str
    #: (cause, relative gain, 95 % CI low, high, max-T adjusted p, reported) per finding
    findings: tuple[tuple[str, float, float, float, float, bool], ...]
    report: Path
    extended_model_id: int | None
    save_reason: str | None
    extended_prediction: str | None


@dataclass(frozen=True)
class DemoResult:
    model_id: int
    rows: tuple[DemoRow, ...]
    pictures: tuple[Path, ...]
    database_url: str
    diagnosis: DemoDiagnosis | None = None
    hidden_effect: DemoDiagnosis | None = None


def _measured_at(session: Session, route: str, bogie_type: str, axle: int,
                 at_km: float) -> tuple[float | None, float | None]:
    """Measured wear areas at ``at_km``: least-squares line through the origin of all the
    group's measurements (both sides), evaluated at ``at_km`` [mm²]."""
    from wearcast.service import measurement_store

    ids = measurement_store.matching_ids(
        session, {"route_id": route, "bogie_type": bogie_type, "axle": axle, "kind": "profile"})
    found = measurement_store.load(session, ids)
    if not found:
        return None, None
    s = np.array([m.mileage_km for m in found], dtype=float)
    out = []
    for attr in ("tread_area_mm2", "flange_area_mm2"):
        a = np.array([getattr(m, attr) if getattr(m, attr) is not None else np.nan
                      for m in found], dtype=float)
        ok = np.isfinite(a)
        out.append(float(np.sum(s[ok] * a[ok]) / np.sum(s[ok] ** 2) * at_km) if ok.any()
                   else None)
    return out[0], out[1]


def _fmt(value: float | None, digits: int = 1) -> str:
    return "-" if value is None else f"{value:,.{digits}f}"


def _band(q: tuple[float, float, float]) -> str:
    return f"{_fmt(q[1])} [{_fmt(q[0])}-{_fmt(q[2])}]"


def format_table(rows: tuple[DemoRow, ...]) -> str:
    """The demo's plain-text table."""
    head = (f"{'role':<12}{'route':<9}{'bogie':<8}{'axle':>4}  {'tread meas':>10}  "
            f"{'tread pred P50 [P10-P90]':<24}  {'flange meas':>11}  "
            f"{'flange pred P50 [P10-P90]':<26}  {'reprofiling km P10/P50/P90':<30}  limit")
    lines = [f"wear areas [mm2] at {COMPARE_AT_KM:,.0f} km (measured: fit through the origin "
             "of the group's measurements)", head, "-" * len(head)]
    for r in rows:
        mileages = " / ".join(_fmt(v, 0) for v in r.reprofiling_km)
        lines.append(
            f"{r.role:<12}{r.route:<9}{r.bogie_type:<8}{r.axle:>4}  "
            f"{_fmt(r.measured_tread_mm2):>10}  {_band(r.predicted_tread_mm2):<24}  "
            f"{_fmt(r.measured_flange_mm2):>11}  {_band(r.predicted_flange_mm2):<26}  "
            f"{mileages:<30}  {r.governing_limit or '-'}")
    return "\n".join(lines)


def run_demo(out_dir: Path | str, *, echo: Callable[[str], None] = print) -> DemoResult:
    """Import the example into a fresh SQLite database under ``out_dir``, calibrate on unit A's
    motor bogies (seed 001 §4: calibration on the motor bogies of train I), predict unit A's
    trailer bogies, unit B and the new 100 % tangent route, print the comparison table and
    the reprofiling mileages, and write the pictures when ``wearcast.service.pictures``
    exists. Then diagnose the whole fleet with the discrepancy finder (``_diagnose``): print
    the verdict and the findings, write ``diagnosis_report.html`` into ``out_dir``, save the
    extended model and predict with it. Returns what it printed, as data."""
    from wearcast.service import model_store, prediction_store, reprofiling_store
    from wearcast.service.db import Database
    from wearcast.service.model_schemas import ModelIn
    from wearcast.service.prediction_schemas import PredictIn
    from wearcast.service.reprofiling_schemas import ReprofilingIn
    from wearcast.service.settings import Settings

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    settings = Settings(data_dir=out / "data", database_url=None)
    settings.data_dir.mkdir(parents=True, exist_ok=True)
    database = Database(settings)
    database.migrate()
    try:
        ids = load_example_fleet(database.session_factory, settings.raw_dir)
        echo(f"example fleet loaded: {ids.measurements_created} new measurements, "
             f"routes {sorted(ids.route_ids)}, wear table {ids.wear_table_id}")
        with database.session_factory() as session:
            model = model_store.create_model(session, ModelIn(
                name="demo: unit A motor bogies", measure="tau_max", running_mode="mixed",
                wear_table_id=ids.wear_table_id,
                calibration={"route_id": CALIBRATION_ROUTE,
                             "filter": {"route_id": CALIBRATION_ROUTE, "bogie_type": "motor"}}))
            model_id = int(model.id)
            plan = [("calibration", CALIBRATION_ROUTE, "motor"),
                    ("validation", CALIBRATION_ROUTE, "trailer"),
                    ("other route", "metro", "motor"), ("other route", "metro", "trailer"),
                    ("new route", NEW_ROUTE, "motor"), ("new route", NEW_ROUTE, "trailer")]
            rows = []
            predictions = []
            for role, route, bogie in plan:
                for axle in (1, 2):
                    prediction = prediction_store.predict(session, model_id, PredictIn(
                        route_id=route, bogie_type=bogie, axle=axle, side="left",
                        mileage_km=[COMPARE_AT_KM]))
                    predictions.append(prediction)
                    at = prediction.points[0]
                    repro = reprofiling_store.reprofiling(session, model_id, ReprofilingIn(
                        route_id=route, bogie_type=bogie, axle=axle, side="left"))
                    tread, flange = _measured_at(session, route, bogie, axle, COMPARE_AT_KM)
                    rows.append(DemoRow(
                        role, route, bogie, axle, tread,
                        (at.tread_area_mm2.p10, at.tread_area_mm2.p50, at.tread_area_mm2.p90),
                        flange,
                        (at.flange_area_mm2.p10, at.flange_area_mm2.p50,
                         at.flange_area_mm2.p90),
                        (repro.mileage_km.p10, repro.mileage_km.p50, repro.mileage_km.p90),
                        repro.governing_limit))
        result_rows = tuple(rows)
        echo(format_table(result_rows))
        pictures = _pictures(out, model_id, predictions, database, echo)
        with database.session_factory() as session:
            diagnosis = _diagnose(session, out, model_id, echo)
        hidden = _hidden_effect_demo(out / "hidden_effect", echo)
        return DemoResult(model_id, result_rows, pictures, settings.resolved_database_url,
                          diagnosis, hidden)
    finally:
        database.dispose()


def _pictures(out: Path, model_id: int, predictions: list[Any], database: Any,
              echo: Callable[[str], None]) -> tuple[Path, ...]:
    """Pictures through ``wearcast.service.pictures`` when that module exists."""
    try:
        from wearcast.service import pictures
    except ImportError:
        echo("pictures skipped: wearcast.service.pictures is not available yet")
        return ()
    write = getattr(pictures, "write_demo_pictures", None)
    if write is None:
        echo("pictures skipped: wearcast.service.pictures has no write_demo_pictures()")
        return ()
    paths = tuple(Path(p) for p in write(out, model_id=model_id, predictions=predictions,
                                         session_factory=database.session_factory))
    for p in paths:
        echo(f"wrote {p}")
    return paths


def format_findings(findings: tuple[tuple[str, float, float, float, float, bool], ...]) -> str:
    """The demo's findings table: cause, held-out gain with its 95 % interval, adjusted p."""
    head = f"{'cause':<24}{'held-out gain [95 % CI]':<28}{'p (max-T)':>10}  reported"
    lines = [head, "-" * len(head)]
    for cause, gain, lo, hi, p, reported in findings:
        band = f"{100 * gain:+.1f} % [{100 * lo:+.1f}, {100 * hi:+.1f}]"
        lines.append(f"{cause:<24}{band:<28}{p:>10.2g}  {'yes' if reported else 'no'}")
    return "\n".join(lines)


def _diagnose(session: Session, out: Path, model_id: int,
              echo: Callable[[str], None], *, route: str = "metro",
              report_name: str = "diagnosis_report.html") -> DemoDiagnosis:
    """Run the discrepancy finder on every stored measurement (issue 4), print the verdict
    and findings, write the HTML report, save the extended model and predict with it."""
    from wearcast.physics.vocabulary import BOGIE_TYPES
    from wearcast.service import diagnosis_store, prediction_store
    from wearcast.service.diagnosis_schemas import DiagnoseIn
    from wearcast.service.prediction_schemas import PredictIn
    from wearcast.statistics import discrepancy_report

    run = diagnosis_store.run_diagnosis(session, model_id, DiagnoseIn())
    d = run.diagnosis
    findings = tuple((f.cause, f.gain.relative, f.gain.ci95_low, f.gain.ci95_high,
                      float(f.evidence["p_value"]), f.significant and f.material)
                     for f in d.findings)
    echo(f"diagnosis of model {model_id} on {d.n_measurements} measurements "
         f"({d.n_groups} groups by {d.group_by}): verdict {d.verdict}")
    top = d.finding(d.verdict)
    if top is not None:
        echo(f"  {top.summary}")
    elif d.verdict == "ambiguous":
        echo(f"  candidates no tested margin separates: {', '.join(d.candidates)}")
    for u in d.unexplained:
        echo(f"  residual structure by {u['by']}: {100 * u['share_of_residual']:.1f} % of "
             f"the residual (p = {u['p_value']:.3f})")
    echo(format_findings(findings))
    for code, skip_reason in d.skipped.items():
        echo(f"  skipped {code}: {skip_reason}")
    report = out / report_name
    report.write_text(discrepancy_report.report_html(d, discrepancy_report.diagnosis_figures(d)),
                      encoding="utf-8")
    echo(f"wrote {report}")
    saved, reason = diagnosis_store.save_extension(session, run, f"demo: {d.verdict} extension")
    shown = None
    if saved is not None:
        echo(f"saved the extended model as model {saved.id} ({d.verdict})")
        if reason:
            echo(f"  {reason}")
        lines = []
        for bogie in BOGIE_TYPES:
            for mid, label in ((model_id, "calibrated"), (int(saved.id), "extended")):
                p = prediction_store.predict(session, mid, PredictIn(
                    route_id=route, bogie_type=bogie, axle=1, side="left",
                    mileage_km=[COMPARE_AT_KM])).points[0]
                lines.append(f"  {label:<10} model {mid}: {route} {bogie:<7} axle 1 at "
                             f"{COMPARE_AT_KM:,.0f} km: tread {p.tread_area_mm2.p50:.1f} mm2, "
                             f"flange {p.flange_area_mm2.p50:.1f} mm2 (P50)")
        shown = "\n".join(lines)
        echo(shown)
    else:
        echo(f"no extended model saved: {reason}")
    return DemoDiagnosis(d.verdict, findings, report, None if saved is None else int(saved.id),
                         reason, shown)


def _hidden_effect_demo(out: Path, echo: Callable[[str], None]) -> DemoDiagnosis:
    """The finder on a fleet-twin dataset with a known hidden effect (motor-bogie treads
    wearing 1.3 x faster, ``twin_effects.traction``), imported through the API into its own
    database, calibrated on unit A's motor bogies: verdict, findings, report, the saved
    extended model and a prediction with it."""
    import io

    from fastapi.testclient import TestClient

    from wearcast.service.app import create_app
    from wearcast.service.settings import Settings
    from wearcast.statistics.generators import fleet_twin as ft
    from wearcast.statistics.generators import twin_effects as te
    from wearcast.statistics.generators import twin_wear_table

    out.mkdir(parents=True, exist_ok=True)
    echo("hidden-effect example: fleet twin with motor-bogie treads wearing 1.3 x faster "
         "(the model does not know it)")
    table = twin_wear_table.synthetic_wear_table()
    cfg = te.scenario_config(seed=7, wear_effects=(te.traction(1.3),), vehicles_per_unit=2,
                             points_per_profile=150)
    twin = ft.generate_fleet(cfg, table)
    settings = Settings(data_dir=out / "data", database_url=None)
    with TestClient(create_app(settings)) as client:
        for unit in cfg.units:
            r = client.post("/v1/routes", json=unit.route.to_json())
            if r.status_code != 409:
                r.raise_for_status()
        buf = io.BytesIO()
        table.to_csv(buf, index=False)
        r = client.post("/v1/wear-tables", files={"file": ("table.csv", buf.getvalue(),
                                                           "text/csv")})
        r.raise_for_status()
        table_id = r.json()["id"]
        r = client.post("/v1/measurements/import", files={
            "file": ("profiles.csv", twin.profiles.to_csv(index=False).encode(), "text/csv")})
        r.raise_for_status()
        r = client.post("/v1/models", json={
            "name": "hidden effect: unit A motor bogies", "measure": "tau_max",
            "running_mode": "mixed", "wear_table_id": table_id,
            "calibration": {"route_id": "aosta",
                            "filter": {"vehicle_id": ["A1", "A2"], "bogie_type": "motor"}}})
        r.raise_for_status()
        model_id = int(r.json()["id"])
    from wearcast.service.db import Database

    database = Database(settings)
    try:
        with database.session_factory() as session:
            return _diagnose(session, out, model_id, echo, route="aosta")
    finally:
        database.dispose()
