"""Calibration through the service layer on ~10,000 stored measurements.

    .venv/bin/python benchmarks/bench_calibration_service.py [n_profiles]   # default 20,000

Imports ``n_profiles`` fleet-twin profiles (half on the Aosta route, half on the metro line)
into a fresh SQLite database, then times ``model_store.create_model`` calibrating on every
Aosta measurement (~10,000): reading the measurements and their wear-curve blobs from SQLite,
``hybrid.calibrate`` (wear states, rates, c_s) and storing the model. The pure statistics part
alone is timed by ``bench_calibration.py``.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_import  # noqa: E402  (the import benchmark's file writer)


def main() -> None:
    from sqlalchemy import func, select

    from wearcast.service import demo, importing, model_store
    from wearcast.service import models_db as db
    from wearcast.service.db import Database
    from wearcast.service.model_schemas import ModelIn
    from wearcast.service.settings import Settings

    n_profiles = int(sys.argv[1]) if len(sys.argv) > 1 else 20_000
    work = Path(tempfile.mkdtemp(prefix="wearcast-bench-"))
    csv = work / "profiles.csv"
    bench_import.write_csv(csv, n_profiles)
    settings = Settings(data_dir=work / "data", database_url=None)
    database = Database(settings)
    database.migrate()
    with database.session_factory() as session, csv.open("rb") as stream:
        importing.import_upload(session, settings.raw_dir, stream, csv.name)
    ids = demo.load_example_fleet(database.session_factory, settings.raw_dir)
    with database.session_factory() as session:
        start = time.perf_counter()
        model = model_store.create_model(session, ModelIn(
            name="bench", measure="tau_max", running_mode="mixed",
            wear_table_id=ids.wear_table_id,
            calibration={"route_id": "aosta", "filter": {"route_id": "aosta"}}))
        seconds = time.perf_counter() - start
        n = session.scalar(select(func.count()).select_from(db.ModelCalibrationMeasurement)
                           .where(db.ModelCalibrationMeasurement.model_id == model.id))
    database.dispose()
    print(f"calibration through the service on {n:,} stored measurements: {seconds:.2f} s "
          "(target < 2 s)")


if __name__ == "__main__":
    main()
