"""Fast predict/reprofiling in the service: in-process caches of immutable inputs only.

Every request must still compute its answer: the tests compare the HTTP answers with the
statistics core run on a model and table read afresh from the database, count the
computations, and check that caches can never serve another database's or table's data.
"""

from __future__ import annotations

import threading
import warnings
from pathlib import Path

import numpy as np
import pytest
from sqlalchemy import event
from typer.testing import CliRunner

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

from wearcast.service import (
    model_loading,
    prediction_store,
    reprofiling_store,
    route_store,
    wear_table_store,
)
from wearcast.service import models_db as db
from wearcast.service.app import create_app
from wearcast.service.cache import LruCache
from wearcast.service.cli import app as cli_app
from wearcast.service.cli import serve_app
from wearcast.service.demo import load_example_fleet
from wearcast.service.prediction_schemas import PredictIn, PredictionOut
from wearcast.service.reprofiling_schemas import ReprofilingIn, ReprofilingOut
from wearcast.service.settings import Settings
from wearcast.statistics import hybrid, hybrid_prediction, reprofiling
from wearcast.statistics.wear_tables import compile_wear_table

POSITION = {"bogie_type": "motor", "axle": 1, "side": "right"}


def _calibrated(data_dir: Path, bogie_type: str = "motor") -> tuple[TestClient, int]:
    client = TestClient(create_app(Settings(data_dir=data_dir)))
    ids = load_example_fleet(client)
    response = client.post("/v1/models", json={
        "name": "perf", "measure": "tau_max", "running_mode": "mixed",
        "wear_table_id": ids.wear_table_id,
        "calibration": {"route_id": "aosta",
                        "filter": {"route_id": "aosta", "bogie_type": bogie_type}}})
    assert response.status_code == 201, response.text
    return client, int(response.json()["id"])


@pytest.fixture(scope="module")
def example(tmp_path_factory: pytest.TempPathFactory) -> tuple[TestClient, int]:
    return _calibrated(tmp_path_factory.mktemp("perf"))


def _fresh_inputs(client: TestClient, model_id: int, route_name: str):
    """Model, table and route read from the database without any cache."""
    database = client.app.state.database
    with database.session_factory() as session:
        row = session.get(db.Model, model_id)
        model = hybrid.HybridModel.from_dict(row.state)
        table = compile_wear_table(wear_table_store.table_frame(session, row.wear_table_id))
        route = route_store.to_domain(route_store.get_route(session, route_name))
    return model, table, route


def test_lru_cache_is_bounded_and_keeps_the_recent_entries():
    cache: LruCache[int] = LruCache(2)
    calls = []

    def make(v: int):
        return lambda: calls.append(v) or v

    assert cache.get_or_create("a", make(1)) == 1
    assert cache.get_or_create("b", make(2)) == 2
    assert cache.get_or_create("a", make(99)) == 1  # hit: "a" becomes the most recent
    assert cache.get_or_create("c", make(3)) == 3  # evicts "b"
    assert len(cache) == 2 and calls == [1, 2, 3]
    assert cache.get_or_create("b", make(4)) == 4
    assert (cache.hits, cache.misses) == (1, 4)
    with pytest.raises(ValueError, match="maxsize"):
        LruCache(0)


def test_lru_cache_gives_every_thread_the_stored_value():
    cache: LruCache[object] = LruCache(4)
    seen = []

    def worker() -> None:
        seen.append(cache.get_or_create("k", object))

    threads = [threading.Thread(target=worker) for _ in range(16)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len({id(v) for v in seen}) == 1 and len(cache) == 1


@pytest.mark.parametrize("route_name", ["aosta", "metro", "tangent"])
def test_predict_over_http_is_the_statistics_core_on_fresh_inputs(example, route_name):
    client, model_id = example
    mileage = [0.0, 60_000.0, 250_000.0]
    answer = client.post(f"/v1/models/{model_id}/predict",
                         json={"route_id": route_name, "mileage_km": mileage, **POSITION})
    assert answer.status_code == 200, answer.text
    model, table, route = _fresh_inputs(client, model_id, route_name)
    expected = hybrid_prediction.predict(model, route, table, mileage_km=mileage, **POSITION)
    body = answer.json()
    assert body["route"] == route_name
    for region in ("flange", "tread"):
        assert body["weighted_measure"][region] == pytest.approx(
            expected.weighted_measure[region], rel=1e-12)
    for i, point in enumerate(body["points"]):
        assert point["flange_area_mm2"]["p50"] == pytest.approx(
            expected.flange_area_mm2[1, i], rel=1e-12, abs=1e-12)
        np.testing.assert_allclose(point["z_mm"], expected.z_mm[i], atol=1e-12)
        assert point["sd_mm"] == pytest.approx(expected.sd_mm[i], abs=1e-9)
        assert point["qr_mm"] == pytest.approx(expected.qr_mm[i], abs=1e-9)


@pytest.mark.parametrize("route_name", ["aosta", "metro"])
def test_reprofiling_over_http_is_the_statistics_core_on_fresh_inputs(example, route_name):
    client, model_id = example
    answer = client.post(f"/v1/models/{model_id}/reprofiling",
                         json={"route_id": route_name, **POSITION})
    assert answer.status_code == 200, answer.text
    model, table, route = _fresh_inputs(client, model_id, route_name)
    expected = reprofiling.reprofiling_mileage(model, route, table, **POSITION)
    body = answer.json()
    assert body["remaining_km"]["p50"] == pytest.approx(expected.mileage_p50_km, rel=1e-12)
    assert body["remaining_km"]["p10"] == pytest.approx(expected.mileage_p10_km, rel=1e-12)
    assert body["governing_limit"] == expected.governing_limit


def test_every_request_computes_its_answer(example, monkeypatch):
    client, model_id = example
    calls = {"predict": 0, "reprofiling": 0}
    real_predict, real_reprofiling = hybrid_prediction.predict, reprofiling.reprofiling_mileage

    def counting_predict(*args, **kwargs):
        calls["predict"] += 1
        return real_predict(*args, **kwargs)

    def counting_reprofiling(*args, **kwargs):
        calls["reprofiling"] += 1
        return real_reprofiling(*args, **kwargs)

    monkeypatch.setattr(hybrid_prediction, "predict", counting_predict)
    monkeypatch.setattr(reprofiling, "reprofiling_mileage", counting_reprofiling)
    body = {"route_id": "metro", "mileage_km": [80_000.0], **POSITION}
    first = client.post(f"/v1/models/{model_id}/predict", json=body).json()
    again = client.post(f"/v1/models/{model_id}/predict", json=body).json()
    for _ in range(3):
        client.post(f"/v1/models/{model_id}/reprofiling", json={"route_id": "metro",
                                                                **POSITION})
    assert first == again and calls == {"predict": 2, "reprofiling": 3}


def test_cached_requests_run_no_sql_and_read_nothing_again(example, monkeypatch):
    client, model_id = example
    body = {"route_id": "aosta", **POSITION}
    client.post(f"/v1/models/{model_id}/reprofiling", json=body)

    def no_reads(*args, **kwargs):
        raise AssertionError("the cached table and model should not be read again")

    monkeypatch.setattr(wear_table_store, "table_frame", no_reads)
    monkeypatch.setattr(hybrid.HybridModel, "from_dict", no_reads)
    statements: list[str] = []
    engine = client.app.state.database.engine

    def count(conn, cursor, statement, *args):
        statements.append(statement)

    event.listen(engine, "before_cursor_execute", count)
    try:
        hits = model_loading._hot_models.hits
        answer = client.post(f"/v1/models/{model_id}/reprofiling", json=body)
        predicted = client.post(f"/v1/models/{model_id}/predict",
                                json={**body, "mileage_km": [1e5]})
        assert answer.status_code == 200 and predicted.status_code == 200
        assert statements == [] and model_loading._hot_models.hits == hits + 2
        # a wheel's latest measurement can change: reprofiling by wheel_id reads storage
        missing_wheel = client.post(f"/v1/models/{model_id}/reprofiling",
                                    json={"route_id": "aosta", "wheel_id": "no-such-wheel"})
        assert missing_wheel.status_code == 404 and statements
    finally:
        event.remove(engine, "before_cursor_execute", count)
    missing = client.post("/v1/models/999/predict",
                          json={"route_id": "aosta", "mileage_km": [1.0], **POSITION})
    assert missing.status_code == 404 and missing.json()["errors"][0]["field"] == "model_id"
    unknown = client.post(f"/v1/models/{model_id}/reprofiling",
                          json={"route_id": "nowhere", **POSITION})
    assert unknown.status_code == 404 and unknown.json()["errors"][0]["field"] == "route_id"


def test_hot_path_answers_match_the_python_api_and_their_schemas(example):
    # the HTTP answers are written by orjson from numpy arrays; they must be the documented
    # schemas and carry the values of prediction_store.predict/reprofiling (pydantic-built)
    client, model_id = example
    pred_in = {"route_id": "metro", "mileage_km": [0.0, 5e4, 3e6], **POSITION}
    rep_in = {"route_id": "metro", **POSITION, "limits": {"qr_min_mm": 9.0}}
    for _ in range(2):  # the first request loads the inputs, the second is served cached
        pred = client.post(f"/v1/models/{model_id}/predict", json=pred_in)
        rep = client.post(f"/v1/models/{model_id}/reprofiling", json=rep_in)
        assert pred.status_code == 200 and rep.status_code == 200
        with client.app.state.database.session_factory() as session:
            want_pred = prediction_store.predict(session, model_id, PredictIn(**pred_in))
            want_rep = reprofiling_store.reprofiling(session, model_id, ReprofilingIn(**rep_in))
        got_pred = PredictionOut.model_validate_json(pred.content)
        got_rep = ReprofilingOut.model_validate_json(rep.content)
        assert got_pred.model_dump() == want_pred.model_dump()
        assert got_rep.model_dump() == want_rep.model_dump()
    assert got_pred.points[-1].extrapolated  # 3e6 km lies beyond the last wear state


def test_another_database_with_the_same_ids_is_never_served_from_the_cache(example,
                                                                           tmp_path):
    # the same example in a second database, calibrated on other wheels: model id 1 and
    # route "aosta" there must give that model's answer, not the cached one of the first
    client, model_id = example
    other, other_id = _calibrated(tmp_path / "other", bogie_type="trailer")
    assert other_id == model_id
    body = {"route_id": "aosta", "mileage_km": [200_000.0], **POSITION}
    a = client.post(f"/v1/models/{model_id}/predict", json=body).json()
    b = other.post(f"/v1/models/{other_id}/predict", json=body).json()
    model, table, route = _fresh_inputs(other, other_id, "aosta")
    expected = hybrid_prediction.predict(model, route, table, mileage_km=[200_000.0], **POSITION)
    assert b["points"][0]["flange_area_mm2"]["p50"] == pytest.approx(
        expected.flange_area_mm2[1, 0], rel=1e-12)
    assert a["points"][0]["flange_area_mm2"]["p50"] != b["points"][0]["flange_area_mm2"]["p50"]


def test_serve_has_a_workers_option_and_workers_do_not_migrate(tmp_path, monkeypatch):
    result = CliRunner().invoke(cli_app, ["serve", "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0 and "--workers" in result.output
    bad = CliRunner().invoke(cli_app, ["serve", "--workers", "0"])
    assert bad.exit_code != 0
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(tmp_path))
    monkeypatch.delenv("WEARCAST_DATABASE_URL", raising=False)
    worker_app = serve_app()
    assert worker_app.state.database.settings.data_dir == tmp_path
    assert not (tmp_path / "wearcast.sqlite3").exists()  # built lazily, not migrated


@pytest.mark.parametrize("workers", ["1", "2"])
def test_serve_can_turn_the_access_log_off(tmp_path, monkeypatch, workers):
    import uvicorn

    calls: list[dict] = []
    monkeypatch.setattr(uvicorn, "run", lambda *args, **kwargs: calls.append(kwargs))
    monkeypatch.setenv("WEARCAST_DATA_DIR", str(tmp_path))
    monkeypatch.setenv("WEARCAST_API_KEY", "wc_test-key-for-the-access-log-0123")
    monkeypatch.delenv("WEARCAST_DATABASE_URL", raising=False)
    for flag, expected in (("--no-access-log", False), ("--access-log", True)):
        result = CliRunner().invoke(cli_app, ["serve", "--workers", workers, flag])
        assert result.exit_code == 0, result.output
        assert calls[-1]["access_log"] is expected
