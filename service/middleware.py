"""Cross-cutting request handling, applied to every route (present and future) by
:func:`wearcast.service.app.create_app`; pure ASGI, so streamed bodies stay streamed.

* :class:`ProblemGuard` (outermost): any unexpected exception becomes a 500 problem document
  (the exception is logged with a request id, never sent), so a failure never resets a
  kept-alive connection; security headers on every answer.
* :class:`RequestGuard`: refuses, before any route runs, bodies beyond the size limits (413
  naming the limit, checked on ``Content-Length`` and again while the body streams),
  cross-site writes (403: an ``Origin`` that is not allowed, or ``Sec-Fetch-Site:
  cross-site``) and undocumented methods on literal paths (405 with ``Allow``).
* :func:`check_request_values` (a dependency after the key check): path, query or JSON body
  values no route could use (422: NUL bytes, integers beyond 64 bits, over-long values).
* :class:`AuditTrail`: one :class:`~wearcast.service.models_access.AuditRecord` per accepted
  write, naming the key, the entity and its id.
* :class:`RateLimiter`: a token bucket per key (429 with ``Retry-After``), called by
  :func:`wearcast.service.auth.require_key`.
"""

from __future__ import annotations

import json
import logging
import math
import re
import threading
import time
import uuid
from typing import Any
from urllib.parse import parse_qsl

from fastapi.exceptions import HTTPException
from starlette.concurrency import run_in_threadpool
from starlette.requests import Request
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from wearcast.service.errors import ApiError, LimitExceeded, problem_body
from wearcast.service.id_text import INT64_MAX, INT64_MIN, int64_of_decimal
from wearcast.service.settings import Settings

log = logging.getLogger(__name__)
SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}
_DIGITS = re.compile(r"^[+-]?\d+$")
_LONG_DIGITS = re.compile(rb"\d{19,}")
MAX_QUERY_VALUE_CHARS = 1000


async def send_problem(send: Send, status: int, items: list[dict[str, Any]],
                       headers: dict[str, str] | None = None) -> None:
    body = json.dumps(problem_body(status, items)).encode()
    raw = [(b"content-type", b"application/problem+json"),
           (b"content-length", str(len(body)).encode())]
    raw += [(k.lower().encode(), v.encode()) for k, v in (headers or {}).items()]
    await send({"type": "http.response.start", "status": status, "headers": raw})
    await send({"type": "http.response.body", "body": body})


class BodyTooLarge(HTTPException):
    """Raised from ``receive`` when a body passes its limit; FastAPI passes HTTPExceptions
    through its body parsing, and the problem handler answers 413 naming the limit."""

    def __init__(self, limit: str, value: int) -> None:
        item = LimitExceeded("body", limit, value, "the request body is too large").item()
        super().__init__(413, detail=[item])


class ProblemGuard:
    """Unexpected exceptions → 500 problem details; security headers; a request id."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        request_id = uuid.uuid4().hex[:16]
        started = False

        async def send_wrapper(message: Message) -> None:
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
                headers = list(message.get("headers", []))
                headers += [(b"x-request-id", request_id.encode()),
                            (b"x-content-type-options", b"nosniff"),
                            (b"referrer-policy", b"no-referrer")]
                message = {**message, "headers": headers}
            await send(message)

        try:
            await self.app(scope, receive, send_wrapper)
        except Exception:
            log.exception("request %s failed", request_id)
            if not started:
                await send_problem(send, 500, [{
                    "loc": [], "field": "request",
                    "reason": f"the server failed on this request (request id {request_id})"}],
                    {"x-request-id": request_id})


def _query_problem(query: bytes, max_chars: int) -> dict[str, Any] | None:
    try:
        pairs = parse_qsl(query.decode("latin-1"), keep_blank_values=True)
    except ValueError:
        return {"loc": ["query"], "field": "query", "reason": "malformed query string"}
    for name, value in pairs:
        problem = _value_problem(value, max_chars)
        if problem:
            return {"loc": ["query", name[:100]], "field": name[:100], "reason": problem}
        if "\x00" in name:
            return {"loc": ["query"], "field": "query", "reason": "NUL byte in a name"}
    return None


def _value_problem(value: str, max_chars: int) -> str | None:
    if "\x00" in value:
        return "holds a NUL byte"
    if len(value) > max_chars:
        return f"longer than {max_chars} characters"
    if _DIGITS.match(value) and int64_of_decimal(value) is None:
        return "integer out of the 64-bit range"
    return None


def _literal_path_methods(scope: Scope) -> list[str] | None:
    """The documented methods when the path is one of the contract's literal paths."""
    app = scope.get("app")
    if app is None or not hasattr(app, "openapi"):
        return None
    table = getattr(app.state, "literal_paths", None)
    if table is None:
        table = {path: sorted(m.upper() for m in operations)
                 for path, operations in app.openapi().get("paths", {}).items()
                 if "{" not in path}
        app.state.literal_paths = table
    return table.get(scope.get("path", ""))


async def check_request_values(request: Request) -> None:
    """422 for path, query or JSON body values no route could use (NUL bytes, integers beyond
    64 bits, over-long values), naming the field; a dependency run after the key check, so a
    request without a key gets 401 whatever its values."""
    settings = request.app.state.settings
    for segment in request.url.path.split("/"):
        problem = _value_problem(segment, settings.max_id_length)
        if problem:
            raise ApiError(422, "path", f"a path segment {problem}")
    item = _query_problem(request.scope.get("query_string", b""), MAX_QUERY_VALUE_CHARS)
    if item:
        raise ApiError(422, item["field"], item["reason"])
    content_type = request.headers.get("content-type", "")
    if content_type.startswith("application/json"):
        found = _unstorable_field(await request.body())
        if found is not None:
            raise ApiError(422, *found)
    elif content_type.startswith(("multipart/form-data", "application/x-www-form-urlencoded")):
        found = await _unstorable_form_field(request)
        if found is not None:
            raise ApiError(422, *found)


async def _unstorable_form_field(request: Request) -> tuple[str, str] | None:
    """The form field (a value or an uploaded file's name) holding a NUL byte, and why; the
    form is the one the route already read (Starlette keeps it on the request)."""
    try:
        form = await request.form()
    except Exception:  # not a readable form: the route's body parsing named that
        return None
    for name, value in form.multi_items():
        text = value if isinstance(value, str) else (getattr(value, "filename", None) or "")
        if "\x00" in text:
            return name[:100], ("holds a NUL byte" if isinstance(value, str)
                                else "the file name holds a NUL byte")
    return None


def _unstorable_field(body: bytes) -> tuple[str, str] | None:
    """The field of a JSON body no database column could hold, and why: an integer beyond
    64 bits, or a string (value or key) holding a NUL byte, which PostgreSQL refuses in text
    and JSON (None when there is none or the body is not JSON: request validation names
    that)."""
    if not body or not (_LONG_DIGITS.search(body) or b"\\u0000" in body):
        return None  # no run of 19+ digits and no escaped NUL: nothing to walk
    try:
        value = json.loads(body)
    except (ValueError, RecursionError):
        return None

    def find(node: Any, path: str) -> tuple[str, str] | None:
        if isinstance(node, bool):
            return None
        if isinstance(node, int) and not INT64_MIN <= node <= INT64_MAX:
            return path or "body", "integer out of the 64-bit range"
        if isinstance(node, str) and "\x00" in node:
            return path or "body", "holds a NUL byte"
        if isinstance(node, dict):
            for key, child in node.items():
                where = f"{path}.{key}" if path else str(key)
                if "\x00" in key:
                    return path or "body", "holds a key with a NUL byte"
                found = find(child, where)
                if found:
                    return found
        if isinstance(node, list):
            for i, child in enumerate(node):
                found = find(child, f"{path}[{i}]")
                if found:
                    return found
        return None

    return find(value, "")


class RequestGuard:
    """Size limits, cross-site writes and methods of literal paths, before routing."""

    def __init__(self, app: ASGIApp, settings: Settings) -> None:
        self.app = app
        self.settings = settings

    def _body_limit(self, scope: Scope) -> tuple[str, int]:
        headers = dict(scope.get("headers") or [])
        ctype = headers.get(b"content-type", b"").decode("latin-1").lower()
        if ctype.startswith("multipart/") or ctype.startswith("application/octet-stream"):
            return "max_upload_bytes", self.settings.max_upload_bytes
        return "max_body_bytes", self.settings.max_body_bytes

    def _cross_site(self, scope: Scope) -> str | None:
        headers = dict(scope.get("headers") or [])
        site = headers.get(b"sec-fetch-site", b"").decode("latin-1").lower()
        origin = headers.get(b"origin", b"").decode("latin-1")
        if origin and origin != "null":
            host = headers.get(b"host", b"").decode("latin-1")
            same = origin.split("://", 1)[-1] == host
            if not same and origin not in self.settings.cors_origins:
                return f"origin {origin[:100]!r} is not allowed to write"
        elif origin == "null":
            return "an opaque origin may not write"
        if site == "cross-site" and origin not in self.settings.cors_origins:
            return "cross-site writes are refused"
        return None

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        method = scope.get("method", "GET")
        allowed = _literal_path_methods(scope)
        if allowed is not None and method not in allowed:
            # a literal path (``/v1/measurements/import``) is not an id of a templated one
            await send_problem(send, 405, [{"loc": ["method"], "field": "method",
                                            "reason": f"{method} is not allowed here"}],
                               {"allow": ", ".join(allowed)})
            return
        if method not in SAFE_METHODS:
            reason = self._cross_site(scope)
            if reason:
                await send_problem(send, 403, [{"loc": ["header", "Origin"], "field": "Origin",
                                                "reason": reason}])
                return
        limit_name, limit = self._body_limit(scope)
        headers = dict(scope.get("headers") or [])
        declared = headers.get(b"content-length")
        if declared is not None:
            try:
                declared_bytes = int(declared)
            except ValueError:
                await send_problem(send, 400, [{"loc": ["header", "Content-Length"],
                                                "field": "Content-Length",
                                                "reason": "not an integer"}])
                return
            if declared_bytes > limit:
                item = LimitExceeded("body", limit_name, limit,
                                     "the request body is too large").item()
                await send_problem(send, 413, [item], {"connection": "close"})
                return
        seen = 0

        async def limited_receive() -> Message:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > limit:
                    raise BodyTooLarge(limit_name, limit)
            return message

        await self.app(scope, limited_receive, send)


class RateLimiter:
    """A token bucket per key: ``per_second`` sustained, ``burst`` at once (0 = off)."""

    def __init__(self, per_second: float, burst: int) -> None:
        self.per_second = per_second
        self.burst = burst
        self._buckets: dict[int, tuple[float, float]] = {}
        self._lock = threading.Lock()

    def check(self, key_id: int) -> None:
        if self.per_second <= 0:
            return
        now = time.monotonic()
        with self._lock:
            tokens, last = self._buckets.get(key_id, (float(self.burst), now))
            tokens = min(float(self.burst), tokens + (now - last) * self.per_second)
            if tokens < 1.0:
                self._buckets[key_id] = (tokens, now)
                wait = math.ceil((1.0 - tokens) / self.per_second)
                error = ApiError(429, "Authorization", "too many requests for this key; "
                                 f"retry after {wait} s (limit rate_limit_per_second = "
                                 f"{self.per_second:g}, rate_limit_burst = {self.burst})",
                                 limit="rate_limit_per_second")
                error.headers = {"Retry-After": str(max(1, wait))}
                raise error
            self._buckets[key_id] = (tokens - 1.0, now)


# --- audit ------------------------------------------------------------------------------

_ID_KEYS = ("id", "batch_id")


def _entity(path: str) -> tuple[str, str | None]:
    parts = [p for p in path.split("/") if p][1:]  # drop "v1"
    if parts and parts[0] == "admin":
        parts = parts[1:]
    entity = parts[0] if parts else "?"
    entity_id = parts[1] if len(parts) > 1 and parts[1] not in ("import", "compute") else None
    return entity[:100], entity_id


class AuditTrail:
    """One audit record per accepted write (status < 400), stored before the answer leaves:
    a client that was told its write succeeded can rely on the record (a crash after the
    write's own commit and before its record loses the answer too, so the client retries)."""

    def __init__(self, app: ASGIApp, factory: Any) -> None:
        self.app = app
        self.factory = factory

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        from wearcast.service.auth import is_read_only

        if scope["type"] != "http" or is_read_only(scope.get("method", "GET"),
                                                    scope.get("path", "")):
            await self.app(scope, receive, send)
            return
        held: list[Message] = []

        async def send_wrapper(message: Message) -> None:
            held.append(message)
            if message["type"] == "http.response.body" and not message.get("more_body"):
                await self._record(scope, held)
                for m in held:
                    await send(m)
                held.clear()

        await self.app(scope, receive, send_wrapper)
        for m in held:  # an answer that never finished its body: pass on what there is
            await send(m)

    async def _record(self, scope: Scope, messages: list[Message]) -> None:
        start = messages[0] if messages and messages[0]["type"] == "http.response.start" \
            else None
        status = int(start["status"]) if start is not None else 0
        principal = (scope.get("state") or {}).get("principal")
        if principal is None or not 200 <= status < 400:
            return
        if (scope.get("state") or {}).get("audited"):
            return  # the route wrote its own record (e.g. an admin delete with a snapshot)
        entity, entity_id = _entity(scope.get("path", ""))
        ctype = dict(start.get("headers", [])).get(b"content-type", b"") if start else b""
        if entity_id is None and ctype.startswith(b"application/json"):
            body = b"".join(m.get("body", b"") for m in messages[1:])[: 1 << 16]
            try:
                answer = json.loads(body)
            except ValueError:
                answer = None
            if isinstance(answer, dict):
                entity_id = next((str(answer[k]) for k in _ID_KEYS if k in answer), None)
        method = scope.get("method", "POST")
        action = {"DELETE": "delete", "PUT": "change", "PATCH": "change"}.get(method, "create")
        try:
            await run_in_threadpool(write_audit, self.factory, principal, action, entity,
                                    entity_id, method, scope.get("path", ""), status, None)
        except Exception:  # the write itself succeeded; a lost audit row is logged loudly
            log.exception("audit record for %s %s not written", method, scope.get("path"))


def write_audit(factory: Any, principal: Any, action: str, entity: str, entity_id: str | None,
                method: str, path: str, status: int, snapshot: dict[str, Any] | None,
                session: Any = None) -> None:
    """Store one audit record (in ``session`` when given, else in its own transaction)."""
    from wearcast.service.db import transaction
    from wearcast.service.models_access import AuditRecord

    row = AuditRecord(api_key_id=getattr(principal, "key_id", None),
                      key_name=getattr(principal, "name", None), action=action,
                      entity=entity, entity_id=None if entity_id is None else entity_id[:200],
                      method=method, path=path[:500], status=status, snapshot=snapshot)
    if session is not None:
        session.add(row)
        return
    with transaction(factory) as own:
        own.add(row)
