"""API keys: ``Authorization: Bearer <key>`` on every ``/v1`` route but ``/v1/health``.

A key is 256 random bits (``wc_`` + 43 URL-safe characters); only its SHA-256 is stored, and
the presented key's hash is compared with :func:`hmac.compare_digest`. Scopes: ``read``
(GET/HEAD, and the POSTs that store nothing: predict, reprofiling), ``write`` (any other
write) and ``admin`` (``/v1/admin/...``); ``admin`` implies
``write``, which implies ``read``.

The check is one FastAPI dependency (:func:`require_key`) that :func:`wearcast.service.app.
create_app` puts on every router it includes, so a new router is covered without doing
anything. Keys found valid are remembered in process for :data:`KEY_CACHE_S` seconds (a key
revoked through another process stops working within that time; in this process at once).
"""

from __future__ import annotations

import contextvars
import datetime as dt
import hashlib
import hmac
import logging
import secrets
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from wearcast.service.db import Database, SessionFactory, transaction
from wearcast.service.errors import ApiError
from wearcast.service.models_access import ApiKey
from wearcast.service.settings import Settings

log = logging.getLogger(__name__)
SCOPES = ("read", "write", "admin")
KEY_CACHE_S = 5.0
KEY_PREFIX = "wc_"
#: The key (and the app's settings) of the request being served, for code below the routes
#: (e.g. a job's owner and time limit); None outside a request.
current_principal: contextvars.ContextVar[Principal | None] = contextvars.ContextVar(
    "wearcast_principal", default=None)
current_settings: contextvars.ContextVar[Settings | None] = contextvars.ContextVar(
    "wearcast_settings", default=None)
_bearer = HTTPBearer(auto_error=False, description="an API key: Authorization: Bearer <key>")


@dataclass(frozen=True)
class Principal:
    """The key a request was made with."""

    key_id: int
    name: str
    scopes: frozenset[str]

    def allows(self, scope: str) -> bool:
        if "admin" in self.scopes:
            return True
        if scope == "read":
            return bool(self.scopes & {"read", "write"})
        return scope in self.scopes


def new_key() -> str:
    return KEY_PREFIX + secrets.token_urlsafe(32)


def key_hash(key: str) -> str:
    return hashlib.sha256(key.encode("utf-8", "surrogatepass")).hexdigest()


def normalise_scopes(scopes: Sequence[str] | set[str]) -> str:
    unknown = set(scopes) - set(SCOPES)
    if unknown or not scopes:
        raise ApiError(422, "scopes", f"must be a non-empty list of {', '.join(SCOPES)}")
    return ",".join(s for s in SCOPES if s in scopes)


def create_key(session: Session, name: str, scopes: Sequence[str],
               created_by: int | None = None, key: str | None = None) -> tuple[ApiKey, str]:
    """Store a new key (or the given secret) and return the row and the secret (shown once)."""
    secret = key or new_key()
    row = ApiKey(name=name, key_sha256=key_hash(secret), prefix=secret[:8],
                 scopes=normalise_scopes(scopes), created_by=created_by)
    session.add(row)
    session.flush()
    return row, secret


def bootstrap_admin_key(factory: SessionFactory, settings: Settings,
                        announce: bool = True) -> str | None:
    """Make sure an admin key exists.

    ``WEARCAST_API_KEY`` is stored as an admin key (once; it keeps working until revoked).
    Without it, when no key exists at all, an admin key is created and returned (and printed
    to stderr when ``announce``): the only time its secret is ever shown.
    """
    with transaction(factory) as session:
        if settings.api_key is not None:
            secret = settings.api_key.get_secret_value()
            if len(secret) < 16:
                raise ValueError("WEARCAST_API_KEY: must be at least 16 characters")
            digest = key_hash(secret)
            row = session.scalar(select(ApiKey).where(ApiKey.key_sha256 == digest))
            if row is None:
                create_key(session, "admin (WEARCAST_API_KEY)", list(SCOPES), key=secret)
            return None
        if session.scalar(select(func.count()).select_from(ApiKey)):
            return None
        _row, secret = create_key(session, "admin (first start)", list(SCOPES))
    if announce:
        print("wearcast: created the admin API key (shown only this once; keep it):\n"
              f"  {secret}\n"
              "  send it as 'Authorization: Bearer <key>'; create others with "
              "POST /v1/admin/api-keys", file=sys.stderr, flush=True)
    return secret


class KeyCache:
    """Recently verified keys, by hash, for :data:`KEY_CACHE_S` seconds."""

    def __init__(self) -> None:
        self._data: dict[str, tuple[float, Principal | None]] = {}
        self._lock = threading.Lock()

    def get(self, digest: str) -> tuple[bool, Principal | None]:
        with self._lock:
            hit = self._data.get(digest)
        if hit is None or hit[0] < time.monotonic():
            return False, None
        return True, hit[1]

    def put(self, digest: str, principal: Principal | None) -> None:
        with self._lock:
            if len(self._data) > 10_000:
                self._data.clear()
            self._data[digest] = (time.monotonic() + KEY_CACHE_S, principal)

    def clear(self) -> None:
        with self._lock:
            self._data.clear()


def _lookup(database: Database, digest: str) -> Principal | None:
    with database.session_factory() as session:
        row = session.scalar(select(ApiKey).where(ApiKey.key_sha256 == digest,
                                                  ApiKey.revoked_at.is_(None)))
    if row is None or not hmac.compare_digest(row.key_sha256, digest):
        return None
    return Principal(row.id, row.name, frozenset(row.scopes.split(",")))


#: POST operations that compute an answer and store nothing: a ``read`` key may call them,
#: and they leave no audit record.
READ_ONLY_POSTS = ("/predict", "/reprofiling")


def is_read_only(method: str, path: str) -> bool:
    return method in ("GET", "HEAD", "OPTIONS") or (
        method == "POST" and path.endswith(READ_ONLY_POSTS))


def required_scope(request: Request) -> str:
    path = request.url.path
    if path.startswith("/v1/admin/") or path == "/v1/admin":
        return "admin"
    return "read" if is_read_only(request.method, path) else "write"


def _unauthorized(reason: str) -> ApiError:
    error = ApiError(401, "Authorization", reason)
    error.headers = {"WWW-Authenticate": 'Bearer realm="wearcast"'}
    return error


async def require_key(request: Request, credentials: Annotated[
        HTTPAuthorizationCredentials | None, Depends(_bearer)] = None) -> Principal:
    """The request's key, checked against the scope its method and path need (401/403)."""
    if credentials is None or credentials.scheme.lower() != "bearer":
        raise _unauthorized("send an API key as 'Authorization: Bearer <key>'")
    secret = credentials.credentials.strip()
    if not secret or len(secret) > 200:
        raise _unauthorized("the API key is not valid")
    digest = key_hash(secret)
    cache: KeyCache = request.app.state.key_cache
    found, principal = cache.get(digest)
    if not found:
        from starlette.concurrency import run_in_threadpool

        principal = await run_in_threadpool(_lookup, request.app.state.database, digest)
        cache.put(digest, principal)
    if principal is None:
        raise _unauthorized("the API key is not valid or was revoked")
    scope = required_scope(request)
    if not principal.allows(scope):
        raise ApiError(403, "Authorization", f"this key lacks the {scope!r} scope")
    request.state.principal = principal
    current_principal.set(principal)
    current_settings.set(request.app.state.settings)
    limiter = getattr(request.app.state, "rate_limiter", None)
    if limiter is not None:
        limiter.check(principal.key_id)
    return principal


PrincipalDep = Annotated[Principal, Depends(require_key)]


def revoke(session: Session, key_id: int) -> ApiKey | None:
    row = session.get(ApiKey, key_id)
    if row is None:
        return None
    session.execute(update(ApiKey).where(ApiKey.id == key_id)
                    .values(revoked_at=dt.datetime.now(dt.UTC)))
    return row
