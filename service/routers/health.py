"""``GET /v1/health``: 200 when the service and its database answer; open (no key) and
without internals: the database's error text is logged, never sent."""

from __future__ import annotations

import logging
from typing import Literal

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from sqlalchemy import text

from wearcast.service.errors import problem

log = logging.getLogger(__name__)
router = APIRouter(tags=["health"])


class HealthOut(BaseModel):
    status: Literal["ok"]
    database: str


@router.get("/health", response_model=HealthOut)
def health(request: Request) -> JSONResponse:
    try:
        with request.app.state.database.session_factory() as session:
            session.execute(text("SELECT 1"))
            dialect = session.get_bind().dialect.name
    except Exception as exc:  # the database is down or unreachable
        log.warning("health: database unavailable: %s", exc)
        return problem(503, "database", "the database does not answer",
                       headers={"Retry-After": "5"})
    return JSONResponse(content={"status": "ok", "database": dialect})
