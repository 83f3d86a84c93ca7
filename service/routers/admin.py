"""``/v1/admin``: API keys, the audit trail, and deleting or superseding stored data with the
history kept (scope ``admin``; see :mod:`wearcast.service.admin_store`)."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Literal

from fastapi import APIRouter, Path, Query, Request
from pydantic import BaseModel, Field
from sqlalchemy import func, select

from wearcast.service import admin_store, auth
from wearcast.service.deps import SessionDep
from wearcast.service.errors import Conflict, NotFound
from wearcast.service.id_text import INT64_MAX
from wearcast.service.middleware import write_audit
from wearcast.service.models_access import ApiKey, AuditRecord
from wearcast.service.schema_base import Strict

router = APIRouter(prefix="/admin", tags=["admin"])
Scope = Literal["read", "write", "admin"]
EntityId = Annotated[int, Path(ge=1, le=INT64_MAX)]


class ApiKeyIn(Strict):
    name: str = Field(min_length=1, max_length=200)
    scopes: list[Scope] = Field(min_length=1, max_length=3)


class ApiKeyOut(BaseModel):
    id: int
    name: str
    prefix: str
    scopes: list[str]
    created_by: int | None = None
    created_at: dt.datetime | None = None
    revoked_at: dt.datetime | None = None
    key: str | None = Field(default=None, description="the secret: shown only when created")


class AuditOut(BaseModel):
    id: int
    at: dt.datetime | None
    api_key_id: int | None
    key_name: str | None
    action: str
    entity: str
    entity_id: str | None
    method: str
    path: str
    status: int
    snapshot: dict | None = None


class RemovedOut(BaseModel):
    kind: str
    id: int
    action: str
    superseded_by: int | None = None
    audit_id: int


class SupersedeIn(Strict):
    by: int = Field(ge=1, le=INT64_MAX, description="id of the row that replaces this one")
    reason: str | None = Field(default=None, max_length=1000)


def _key_out(row: ApiKey, secret: str | None = None) -> ApiKeyOut:
    return ApiKeyOut(id=row.id, name=row.name, prefix=row.prefix, scopes=row.scopes.split(","),
                     created_by=row.created_by, created_at=row.created_at,
                     revoked_at=row.revoked_at, key=secret)


@router.post("/api-keys", response_model=ApiKeyOut, status_code=201)
def create_api_key(body: ApiKeyIn, session: SessionDep, request: Request) -> ApiKeyOut:
    """A new key; its secret is in this answer only."""
    row, secret = auth.create_key(session, body.name, body.scopes,
                                  created_by=request.state.principal.key_id)
    session.commit()
    return _key_out(row, secret)


@router.get("/api-keys", response_model=list[ApiKeyOut])
def list_api_keys(session: SessionDep) -> list[ApiKeyOut]:
    return [_key_out(r) for r in session.scalars(select(ApiKey).order_by(ApiKey.id))]


@router.delete("/api-keys/{key_id}", response_model=ApiKeyOut)
def revoke_api_key(key_id: EntityId, session: SessionDep, request: Request) -> ApiKeyOut:
    """Revoke a key (it stops working at once here, within seconds in other processes)."""
    row = session.get(ApiKey, key_id)
    if row is None:
        raise NotFound("key_id", f"no API key with id {key_id}")
    configured = request.app.state.settings.api_key
    if configured is not None and row.key_sha256 == auth.key_hash(
            configured.get_secret_value()):
        raise Conflict("key_id", "this is the key set by WEARCAST_API_KEY; change the "
                       "service's environment to replace it")
    if "admin" in row.scopes.split(",") and row.revoked_at is None:
        admins = session.scalar(select(func.count()).select_from(ApiKey).where(
            ApiKey.revoked_at.is_(None), ApiKey.scopes.contains("admin")))
        if (admins or 0) <= 1:
            raise Conflict("key_id", "the last admin key cannot be revoked")
    auth.revoke(session, key_id)
    session.commit()
    session.refresh(row)
    request.app.state.key_cache.clear()
    return _key_out(row)


@router.get("/audit", response_model=list[AuditOut])
def audit_trail(session: SessionDep,
                limit: Annotated[int, Query(ge=1, le=1000)] = 100,
                offset: Annotated[int, Query(ge=0, le=2**31)] = 0,
                entity: Annotated[str | None, Query(max_length=100)] = None) -> list[AuditOut]:
    """The newest audit records first (deleted rows' snapshots included)."""
    query = select(AuditRecord).order_by(AuditRecord.id.desc()).limit(limit).offset(offset)
    if entity:
        query = query.where(AuditRecord.entity == entity)
    return [AuditOut.model_validate(r, from_attributes=True) for r in session.scalars(query)]


def _remove(session: SessionDep, request: Request, kind: str, entity_id: int, action: str,
            by: int | None, reason: str | None) -> RemovedOut:
    if by is not None:
        admin_store.check_replacement(session, kind, entity_id, by)
    shot = admin_store.remove(session, kind, entity_id)
    shot = {"row": shot, "reason": reason, "superseded_by": by}
    write_audit(None, request.state.principal, action, kind, str(entity_id), request.method,
                request.url.path, 200, shot, session=session)
    session.flush()
    audit_id = session.scalar(select(func.max(AuditRecord.id)))
    session.commit()
    admin_store.clear_caches()
    request.state.audited = True
    return RemovedOut(kind=kind, id=entity_id, action=action, superseded_by=by,
                      audit_id=int(audit_id or 0))


@router.delete("/{kind}/{entity_id}", response_model=RemovedOut)
def delete_entity(kind: admin_store.Kind,
                  entity_id: EntityId,
                  session: SessionDep, request: Request,
                  reason: Annotated[str | None, Query(max_length=1000)] = None) -> RemovedOut:
    """Delete a batch (with its measurements), a measurement, a route, a wear table or a
    model; the row is kept in the audit trail."""
    return _remove(session, request, kind, entity_id, "delete", None, reason)


@router.post("/{kind}/{entity_id}/supersede", response_model=RemovedOut)
def supersede_entity(kind: admin_store.Kind,
                     entity_id: EntityId,
                     body: SupersedeIn, session: SessionDep, request: Request) -> RemovedOut:
    """Replace a row by another one of the same kind (already stored, e.g. a corrected
    measurement): the old row leaves the data, its snapshot and the replacement's id stay
    in the audit trail."""
    return _remove(session, request, kind, entity_id, "supersede", body.by, body.reason)
