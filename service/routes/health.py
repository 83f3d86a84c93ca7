"""``GET /v1/health``: 200 when the service and its database answer."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import JSONResponse
from sqlalchemy import text

from wearcast.service.deps import SessionDep

router = APIRouter(tags=["health"])


@router.get("/health")
def health(session: SessionDep) -> JSONResponse:
    try:
        session.execute(text("SELECT 1"))
    except Exception as exc:  # the database is down or unreachable
        return JSONResponse(status_code=503,
                            content={"status": "unavailable", "database": str(exc)[:200]})
    dialect = session.get_bind().dialect.name
    return JSONResponse(content={"status": "ok", "database": dialect})
