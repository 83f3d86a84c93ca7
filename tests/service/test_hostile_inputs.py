"""Hostile inputs found by fuzzing a live server (issue 14): each was a 500 or a schema
violation, and is now a documented answer.

- ``-9223372036854775808`` (the smallest 64-bit integer, which the OpenAPI publishes as the
  ``minimum`` of every integer) in a path or query was refused as "out of the 64-bit range";
- a path or query id of leading zeros past 40 characters was cut to 40 characters before its
  range was checked;
- a route id of digits ``int`` cannot read (``"²"``, a superscript ``str.isdigit`` accepts) or
  beyond 64 bits went to the database as an id: a 500;
- a MiniProf ``XYPoints`` header of such digits, or of thousands of digits, failed ``int``;
- ``format=csv`` answered ``text/csv`` that the OpenAPI did not publish.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

from wearcast.service.app import create_app
from wearcast.service.id_text import decimal_id
from wearcast.service.readers.miniprof import declared_count_differs
from wearcast.service.settings import Settings

INT64_MIN = -(2**63)
ROUTE = {"name": "line", "classes": [{"radius_m": None, "speed_kmh": 80, "share": 1.0}]}


@pytest.fixture
def client(backend_url: str, tmp_path: Path) -> TestClient:
    return TestClient(create_app(Settings(data_dir=tmp_path, database_url=backend_url)))


def _problem_fields(response) -> list[str]:  # type: ignore[no-untyped-def]
    assert response.headers["content-type"].startswith("application/problem+json")
    return [e["field"] for e in response.json()["errors"]]


def test_the_smallest_64_bit_integer_is_an_id_like_any_other(client: TestClient) -> None:
    for path in (f"/v1/measurements/{INT64_MIN}", f"/v1/coefficient-fits/{INT64_MIN}",
                 f"/v1/models/{INT64_MIN}", f"/v1/simulations/{INT64_MIN}"):
        r = client.get(path)
        assert r.status_code == 404, (path, r.status_code, r.text)
    r = client.get("/v1/fleet/state", params={"model_id": str(INT64_MIN)})
    assert r.status_code in (404, 422) and "64-bit" not in r.text, r.text
    for value in (str(INT64_MIN - 1), str(2**63), "0" * 60 + "1" + "0" * 19):
        r = client.get(f"/v1/measurements/{value}")
        assert r.status_code == 422 and "64-bit" in r.text, (value, r.text)
        r = client.get("/v1/fleet/state", params={"model_id": value})
        assert r.status_code == 422 and _problem_fields(r) == ["model_id"], (value, r.text)
    r = client.get(f"/v1/measurements/{'0' * 60}1")  # leading zeros are still the id 1
    assert r.status_code == 404, r.text


def test_route_ids_that_are_not_ascii_digits_are_names(client: TestClient) -> None:
    assert client.post("/v1/routes", json=ROUTE).status_code == 201
    for ref in ("²", "١", "99999999999999999999999", "0" * 30 + "1"):
        r = client.get(f"/v1/routes/{ref}")
        if ref == "0" * 30 + "1":  # leading zeros: the id 1, the route stored above
            assert r.status_code == 200 and r.json()["name"] == "line", r.text
        else:
            assert r.status_code in (404, 422) and _problem_fields(r), (ref, r.text)
        r = client.get("/v1/fleet/state", params={"route_id": ref})
        assert r.status_code < 500, (ref, r.status_code, r.text)



def test_a_curve_without_a_direction_is_refused_a_tangent_is_not(client: TestClient) -> None:
    # one rule for curve classes and segments: radius_m given -> direction left or right
    curve = {"radius_m": 300.0, "speed_kmh": 60}
    for body, item in (({"name": "c", "classes": [{**curve, "share": 1.0}]}, "a curve class"),
                       ({"name": "s", "segments": [{**curve, "length_m": 100.0}]},
                        "a curved segment")):
        r = client.post("/v1/routes", json=body)
        assert r.status_code == 422 and f"{item} (radius_m given) needs a direction" in r.text, \
            r.text
    r = client.post("/v1/routes", json={"name": "t", "segments": [
        {"radius_m": None, "speed_kmh": 60, "length_m": 100.0},
        {**curve, "direction": "left", "length_m": 100.0}]})
    assert r.status_code == 201, r.text

def test_decimal_id_reads_only_ascii_digits_in_the_64_bit_range() -> None:
    assert decimal_id("17") == 17 and decimal_id("007") == 7 and decimal_id("0") == 0
    assert decimal_id(str(2**63 - 1)) == 2**63 - 1
    for text in ("²", "١٢", "-1", "+1", " 1", "", str(2**63), "9" * 5000, "line"):
        assert decimal_id(text) is None, text


def test_a_declared_point_count_is_compared_as_text() -> None:
    assert not declared_count_differs("20", 20) and not declared_count_differs("020", 20)
    assert declared_count_differs("21", 20) and declared_count_differs("9" * 5000, 20)
    assert not declared_count_differs("²", 20) and not declared_count_differs("", 20)
    assert not declared_count_differs("0", 0)


def test_miniprof_with_an_unreadable_point_count_is_a_4xx(client: TestClient) -> None:
    rows = "".join(f"{-30 + i:.1f} {0.01 * i * i:.3f}\n" for i in range(60))
    manifest = b"file,wheel_id,vehicle_id,bogie_type,axle,side,mileage_km\n" \
               b"a.whl,W1,V1,motor,1,left,1000\n"
    for count in ("\u00b2", "9" * 5000):
        data = f"XYPoints={count}\n{rows}".encode()
        r = client.post("/v1/measurements/import", files={
            "file": ("a.whl", data, "application/octet-stream"),
            "manifest": ("m.csv", manifest, "text/csv")})
        assert r.status_code < 500, (count[:5], r.status_code, r.text)
        if r.status_code >= 400:
            assert _problem_fields(r), r.text
        r = client.post("/v1/rails/import", files={
            "file": ("a.whl", data, "application/octet-stream")})
        assert r.status_code < 500, (count[:5], r.status_code, r.text)


def test_csv_answers_are_published_in_the_openapi(client: TestClient) -> None:
    paths = client.get("/openapi.json").json()["paths"]
    for path in ("/v1/fleet/state", "/v1/plans/{plan_id}"):
        content = paths[path]["get"]["responses"]["200"]["content"]
        assert "text/csv" in content and "application/json" in content, path
    r = client.get("/v1/fleet/state", params={"format": "csv"})
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/csv")


def _walk(node: object, path: str = ""):  # type: ignore[no-untyped-def]
    if isinstance(node, dict):
        yield path, node
        for key, value in node.items():
            yield from _walk(value, f"{path}/{key}")
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _walk(value, f"{path}/{i}")


def test_the_openapi_publishes_what_the_server_refuses(client: TestClient) -> None:
    """Integer bounds are integers in the 64-bit range (pydantic wrote ``le=2**63 - 1`` as the
    float 2**63), admin bodies refuse unknown fields, profiles need 10 points, the vehicle
    presets are an enum and path/query strings hold no NUL byte."""
    spec = client.get("/openapi.json").json()
    for where, node in _walk(spec):
        if node.get("type") == "integer" and "/headers/" not in where:
            for key in ("minimum", "maximum"):
                assert isinstance(node[key], int), (where, key, node[key])
                assert -(2**63) <= node[key] <= 2**63 - 1, (where, key, node[key])
    schemas = spec["components"]["schemas"]
    for name in ("ApiKeyIn", "SupersedeIn"):
        assert schemas[name]["additionalProperties"] is False, name
    y_mm = schemas["MeasurementIn"]["properties"]["y_mm"]["anyOf"][0]
    assert y_mm["minItems"] == 10
    assert "metro_b" in schemas["PhysicsModelIn"]["properties"]["vehicle"]["enum"]
    reference = next(p for p in spec["paths"]["/v1/rails"]["get"]["parameters"]
                     if p["name"] == "reference")["schema"]["anyOf"][0]
    assert reference["pattern"] == "^[^\\x00]*$"

    r = client.post("/v1/admin/batches/1/supersede", json={"by": 2**63 - 1 + 192})
    assert r.status_code == 422 and _problem_fields(r) == ["by"], r.text
    r = client.post("/v1/admin/api-keys", json={"name": "k", "scopes": ["read"], "x": 2**70})
    assert r.status_code == 422 and "x" in _problem_fields(r), r.text
    r = client.post("/v1/measurements", json={
        "wheel_id": "W", "vehicle_id": "V", "bogie_type": "motor", "axle": 1, "side": "left",
        "mileage_km": 10, "y_mm": [], "z_mm": []})
    assert r.status_code == 422 and set(_problem_fields(r)) == {"y_mm", "z_mm"}, r.text
    r = client.post("/v1/models", json={"kind": "physics", "name": "p", "vehicle": "tram",
                                        "route_id": 1})
    assert r.status_code == 422 and "vehicle" in _problem_fields(r), r.text
    r = client.get("/v1/rails", params={"reference": "a\x00b"})
    assert r.status_code == 422 and _problem_fields(r) == ["reference"], r.text


def test_ids_beyond_32_bits_are_looked_up_not_refused(client: TestClient) -> None:
    """PostgreSQL's INTEGER is 32-bit: an id such as 2**40 made the lookup fail ("integer out
    of range", a 422 naming no field); ids are BIGINT there now (migration 0008), as the
    OpenAPI publishes, so it is a 404 naming the id on both databases."""
    for big in (2**31, 2**40, 2**63 - 2):
        for path in (f"/v1/measurements/{big}", f"/v1/models/{big}", f"/v1/jobs/{big}",
                     f"/v1/wear-tables/{big}", f"/v1/rails/{big}", f"/v1/plans/{big}",
                     f"/v1/simulations/{big}", f"/v1/coefficient-fits/{big}"):
            r = client.get(path)
            assert r.status_code == 404, (path, r.status_code, r.text)
            assert _problem_fields(r) != ["body"], (path, r.text)
        r = client.delete(f"/v1/admin/api-keys/{big}")
        assert r.status_code == 404, (big, r.status_code, r.text)
        r = client.get("/v1/fleet/wheels/W1", params={"model_id": str(big)})
        assert r.status_code in (404, 422) and _problem_fields(r) != ["body"], r.text


def test_contact_with_the_smallest_positive_wheel_load_ends(client: TestClient) -> None:
    """A wheel load of 5e-324 N (schema-valid: > 0) made the Hertz-like first guess of the
    approach underflow to 0 mm, which the search then doubled for ever (a request that never
    ended). It now starts from ``MIN_APPROACH_MM`` and answers."""
    r = client.post("/v1/contact", json={"friction": 0.3, "poses": [
        {"shift_mm": 0.0, "wheel_load_n": 5e-324}]})
    assert r.status_code < 500, r.text
    if r.status_code >= 400:
        assert _problem_fields(r), r.text
