"""docker-compose.yml is valid YAML and wires the service as documented (no Docker here)."""

from __future__ import annotations

from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[2]


def _compose() -> dict:
    return yaml.safe_load((REPO / "docker-compose.yml").read_text())


def test_the_default_service_keeps_sqlite_in_a_named_volume() -> None:
    compose = _compose()
    service = compose["services"]["wearcast"]
    assert "profiles" not in service  # runs by default
    data_dir = service["environment"]["WEARCAST_DATA_DIR"]
    volume, _, mount = service["volumes"][0].partition(":")
    assert mount == data_dir and volume in compose["volumes"]
    assert "WEARCAST_DATABASE_URL" not in service["environment"]  # SQLite in the data dir
    assert service["command"][:2] == ["wearcast", "serve"]
    dockerfile = REPO / service["build"]["context"] / service["build"]["dockerfile"]
    assert dockerfile == REPO / "service" / "Dockerfile" and dockerfile.is_file()
    assert not (REPO / "Dockerfile").exists() and not (REPO / "alembic.ini").exists()


def test_the_postgres_profile_runs_the_service_on_postgresql() -> None:
    services = _compose()["services"]
    assert "postgres" in services["postgres"]["profiles"]
    # no password is built in, and nothing is published beyond the loopback interface
    assert "${POSTGRES_PASSWORD:?" in services["postgres"]["environment"]["POSTGRES_PASSWORD"]
    assert all(port.startswith("127.0.0.1:") for service in services.values()
               for port in service.get("ports", []))
    api = services["wearcast-pg"]
    assert api["profiles"] == ["postgres"]
    assert api["environment"]["WEARCAST_DATABASE_URL"].startswith("postgresql+psycopg://")
    assert "@postgres:5432/" in api["environment"]["WEARCAST_DATABASE_URL"]
    assert api["depends_on"]["postgres"]["condition"] == "service_healthy"
    assert api["build"]["dockerfile"] == "service/Dockerfile"  # the YAML anchor resolved


def test_the_scale_profile_runs_workers_on_a_broker() -> None:
    services = _compose()["services"]
    api, worker = services["wearcast-scale"], services["worker"]
    assert api["profiles"] == worker["profiles"] == ["scale"]
    assert api["environment"]["WEARCAST_JOB_QUEUE"] == "dramatiq"
    assert worker["environment"] == api["environment"]  # same database and broker
    assert worker["command"][:2] == ["wearcast", "worker"]
    assert worker["deploy"]["replicas"] == "${WEARCAST_WORKERS:-2}"
    assert {"redis", "postgres"} <= set(worker["depends_on"])
