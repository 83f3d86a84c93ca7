"""The PostgreSQL path: migrations, import, calibration and listing on a real server.

Runs against ``WEARCAST_TEST_POSTGRES_URL`` (default
``postgresql+psycopg://postgres@127.0.0.1:5432/test``); it creates a throw-away database
there, drops it afterwards, and skips when the server is unreachable.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from pathlib import Path

import pytest
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext

from wearcast.service.models_db import Base
from wearcast.service.settings import Settings
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes, twin_wear_table

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

pytestmark = pytest.mark.postgres

@pytest.fixture(scope="module")
def postgres_url() -> Iterator[str]:
    """A throw-away database on the local PostgreSQL (the service tests' one helper)."""
    from tests.service.conftest import fresh_postgres_database

    yield from fresh_postgres_database()


def test_the_walk_on_postgresql(postgres_url: str, tmp_path: Path) -> None:
    from wearcast.service.app import create_app

    app = create_app(Settings(data_dir=tmp_path, database_url=postgres_url))
    engine = app.state.database.engine
    try:
        with engine.connect() as connection:
            assert compare_metadata(MigrationContext.configure(
                connection, opts={"compare_type": True}), Base.metadata) == []
        client = TestClient(app)
        assert client.get("/v1/health").json() == {"status": "ok", "database": "postgresql"}
        fleet = ft.generate_fleet(ft.FleetConfig(
            units=(ft.UnitConfig("P", twin_routes.metro_route(), running_mode="lead",
                                 covariates={"depot": "west"}),),
            mileages_km=(40_000, 90_000, 140_000), mileage_jitter_km=0.0,
            rate_scatter=0.0, area_scatter=0.0, points_per_profile=200, seed=3))
        data = fleet.profiles.to_csv(index=False).encode()
        first = client.post("/v1/measurements/import",
                            files={"file": ("pg.csv", data, "text/csv")}).json()
        assert first["created"] == 24 and first["duplicate"] is False
        again = client.post("/v1/measurements/import",
                            files={"file": ("pg.csv", data, "text/csv")}).json()
        assert again["duplicate"] is True and again["batch_id"] == first["batch_id"]
        bad = fleet.profiles.assign(axle=fleet.profiles.axle.astype(object))
        bad.loc[bad.index[-1], "axle"] = 7
        refused = client.post("/v1/measurements/import", files={
            "file": ("bad.csv", bad.to_csv(index=False).encode(), "text/csv")})
        assert refused.status_code == 422 and refused.json()["errors"][0]["field"] == "axle"
        assert client.get("/v1/measurements").json()["total"] == 24
        assert client.get("/v1/measurements", params={"depot": "west"}).json()["total"] == 24
        route = twin_routes.metro_route().to_json()
        assert client.post("/v1/routes", json=route).status_code == 201
        table = client.post("/v1/wear-tables", files={"file": (
            "t.csv", twin_wear_table.synthetic_wear_table().to_csv(index=False).encode(),
            "text/csv")})
        model = client.post("/v1/models", json={
            "name": "pg", "measure": "tau_max", "running_mode": "lead",
            "wear_table_id": table.json()["id"],
            "calibration": {"route_id": "metro", "filter": {}}})
        assert model.status_code == 201, model.text
        tread_c_s = model.json()["summary"]["tread"]["c_s"]
        assert tread_c_s == pytest.approx(ft.FleetConfig(units=()).calibration_factor["tread"],
                                          rel=0.03)
    finally:
        engine.dispose()
