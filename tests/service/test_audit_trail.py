"""The audit record of an accepted write is stored before the answer leaves the service
(``service/middleware.py`` ``AuditTrail``), so an acknowledged write always has its record;
refused writes and reads leave none."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path
from typing import Any

from sqlalchemy import select

from wearcast.service.auth import Principal
from wearcast.service.db import Database
from wearcast.service.middleware import AuditTrail
from wearcast.service.models_access import AuditRecord
from wearcast.service.settings import Settings


def _records(database: Database) -> list[tuple[str, str, str | None, int]]:
    with database.session_factory() as s:
        return [(r.action, r.entity, r.entity_id, r.status)
                for r in s.scalars(select(AuditRecord).order_by(AuditRecord.id))]


def _call(trail: AuditTrail, method: str, path: str, on_start: Any) -> list[dict[str, Any]]:
    scope = {"type": "http", "method": method, "path": path, "headers": [],
             "state": {"principal": Principal(1, "writer", frozenset({"write"}))}}
    sent: list[dict[str, Any]] = []

    async def receive() -> dict[str, Any]:
        return {"type": "http.request", "body": b"", "more_body": False}

    async def send(message: dict[str, Any]) -> None:
        if message["type"] == "http.response.start":
            on_start()
        sent.append(message)

    asyncio.run(trail(scope, receive, send))
    return sent


def _app(status: int, body: dict[str, Any]) -> Any:
    async def app(scope: Any, receive: Any, send: Any) -> None:
        data = json.dumps(body).encode()
        await send({"type": "http.response.start", "status": status,
                    "headers": [(b"content-type", b"application/json")]})
        await send({"type": "http.response.body", "body": data[:5], "more_body": True})
        await send({"type": "http.response.body", "body": data[5:]})
    return app


def test_an_accepted_write_is_recorded_before_its_answer_starts(tmp_path: Path) -> None:
    database = Database(Settings(data_dir=tmp_path))
    database.migrate()
    try:
        seen_at_start: list[list[Any]] = []
        trail = AuditTrail(_app(201, {"id": 7, "name": "line"}), database.session_factory)
        sent = _call(trail, "POST", "/v1/routes",
                     lambda: seen_at_start.append(_records(database)))
        assert seen_at_start == [[("create", "routes", "7", 201)]]
        assert [m["type"] for m in sent] == ["http.response.start", "http.response.body",
                                             "http.response.body"]
        assert b"".join(m.get("body", b"") for m in sent) == b'{"id": 7, "name": "line"}'
        # a refused write and a read leave no record
        refused = AuditTrail(_app(422, {"detail": "bad"}), database.session_factory)
        _call(refused, "POST", "/v1/routes", lambda: None)
        _call(trail, "GET", "/v1/routes", lambda: None)
        assert _records(database) == [("create", "routes", "7", 201)]
    finally:
        database.dispose()
