"""Schema fuzzing (schemathesis) of the published OpenAPI: no server error, every answer
(errors included) valid against the schema, with the documented status and content type.

The quick test fuzzes a few operations on every run; the slow one (``-m slow``) fuzzes every
operation on an app holding the example fleet. Rejections of schema-valid input by rules the
schema cannot express (shares summing to 1, "route_id or route") are answers, not failures:
the ``positive_data_acceptance`` check is left out.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from schemathesis.specs.openapi.checks import positive_data_acceptance

from wearcast.service.app import create_app
from wearcast.service.settings import Settings

ROUTE = {"name": "line", "classes": [
    {"radius_m": None, "speed_kmh": 80, "share": 0.7},
    {"radius_m": 400, "direction": "left", "cant_mm": 100, "speed_kmh": 70, "share": 0.3}]}


def _app(with_example: bool) -> object:
    data_dir = Path(tempfile.mkdtemp(prefix="wearcast-fuzz-"))
    app = create_app(Settings(data_dir=data_dir, job_workers=1, job_quota_per_key=2))
    if with_example:
        from wearcast.service.demo import load_example_fleet

        load_example_fleet(app.state.database.session_factory, data_dir / "raw")
    return app


QUICK = (r"^/v1/(health|routes.*|measurements(/\{measurement_id\})?|jobs.*|admin/audit|"
         r"models/\{model_id\}(/predict)?)$")


def _fuzz(schema: schemathesis.BaseSchema, max_examples: int) -> tuple[int, list[str]]:
    """Every operation of ``schema`` with ``max_examples`` generated cases; the failures."""
    failures: list[str] = []
    operations = 0
    for result in schema.get_all_operations():
        operation = result.ok()
        operations += 1

        @given(operation.as_strategy())
        @settings(max_examples=max_examples, deadline=None, database=None,
                  suppress_health_check=list(HealthCheck))
        def run(case: schemathesis.Case) -> None:
            case.call_and_validate(excluded_checks=[positive_data_acceptance])

        try:
            run()
        except Exception as exc:  # a failed check, reported with its operation
            failures.append(f"{operation.method.upper()} {operation.path}: {exc}"[:3000])
    return operations, failures


def test_fuzz_a_few_operations() -> None:
    from fastapi.testclient import TestClient

    app = _app(with_example=False)
    TestClient(app).post("/v1/routes", json=ROUTE)  # type: ignore[arg-type]
    schema = schemathesis.openapi.from_asgi("/openapi.json", app).include(path_regex=QUICK)
    operations, failures = _fuzz(schema, max_examples=3)
    assert operations >= 8 and failures == [], "\n\n".join(failures)


@pytest.mark.slow
def test_fuzz_every_operation() -> None:
    schema = schemathesis.openapi.from_asgi("/openapi.json", _app(with_example=True))
    operations, failures = _fuzz(schema, max_examples=40)
    assert operations >= 35 and failures == [], "\n\n".join(failures)
