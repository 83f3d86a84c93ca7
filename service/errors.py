"""Errors a client can fix, and the handlers that turn every failure into RFC 9457 problem
details (``application/problem+json``).

Every error body, whatever raised it (a route, request validation, an unknown path, a wrong
method, a limit, authentication, an unexpected failure), has the shape::

    {"type": "about:blank", "title": "Unprocessable Content", "status": 422,
     "detail": "classes.share: shares must sum to 1 (±0.001), got 0.5",
     "errors": [{"loc": ["classes", "share"], "field": "classes.share",
                 "reason": "shares must sum to 1 (±0.001), got 0.5"}]}

``errors`` lists every field at fault with its reason (plus ``file``/``line`` for import
errors, ``limit`` for a limit that was passed). A 500 says only that the server failed and
the request id to quote; the exception is logged, never sent.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Sequence
from http import HTTPStatus
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel, ConfigDict, Field
from sqlalchemy.exc import DataError, IntegrityError, OperationalError
from starlette.exceptions import HTTPException as StarletteHTTPException

from wearcast.service.schema_base import FieldsError

log = logging.getLogger(__name__)
PROBLEM_MEDIA_TYPE = "application/problem+json"


class ApiError(Exception):
    """A request the client can correct: HTTP ``status``, the offending ``field`` and why."""

    def __init__(self, status: int, field: str, reason: str, **extra: Any) -> None:
        super().__init__(f"{field}: {reason}")
        self.status = status
        self.field = field
        self.reason = reason
        self.extra = extra
        self.headers: dict[str, str] = {}

    def item(self) -> dict[str, Any]:
        loc = [part for part in self.field.replace("[", ".").replace("]", "").split(".") if part]
        return {"loc": loc, "field": self.field, "reason": self.reason, **self.extra}


class NotFound(ApiError):
    def __init__(self, field: str, reason: str) -> None:
        super().__init__(404, field, reason)


class Unprocessable(ApiError):
    def __init__(self, field: str, reason: str, **extra: Any) -> None:
        super().__init__(422, field, reason, **extra)


class Conflict(ApiError):
    def __init__(self, field: str, reason: str) -> None:
        super().__init__(409, field, reason)


class LimitExceeded(ApiError):
    """A configured limit was passed: 413 for sizes, 422 for counts and values; the
    ``limit`` member names the setting (``WEARCAST_<LIMIT>``) and its value."""

    def __init__(self, field: str, limit: str, value: int | float, reason: str,
                 status: int = 413) -> None:
        super().__init__(status, field, f"{reason} (limit {limit} = {value:,})",
                         limit=limit, limit_value=value)


class ProblemItem(BaseModel):
    """One field at fault."""

    model_config = ConfigDict(extra="allow")
    loc: list[str | int] = Field(default_factory=list)
    field: str
    reason: str
    file: str | None = None
    line: int | None = None
    limit: str | None = None


class Problem(BaseModel):
    """RFC 9457 problem details, with the fields at fault in ``errors``."""

    model_config = ConfigDict(extra="allow")
    type: str = "about:blank"
    title: str
    status: int
    detail: str
    instance: str | None = None
    errors: list[ProblemItem] = Field(default_factory=list)


def _field_from_loc(loc: tuple[Any, ...] | list[Any]) -> str:
    parts = list(loc)
    if parts and parts[0] in {"body", "query", "path", "header", "form", "cookie"}:
        parts = parts[1:]
    out = ""
    for part in parts:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out or "body"


def validation_items(errors: Sequence[Any]) -> list[dict[str, Any]]:
    """FastAPI/pydantic error dicts reduced to ``loc``, ``field`` and ``reason``."""
    items = []
    for error in errors:
        # "[": pydantic's validator names; "kind=": the tags of a union told apart by kind
        loc = [p for p in error.get("loc", ()) if not (isinstance(p, str) and (
            "[" in p or p.startswith("kind=")))]
        if error.get("type") == "model_kind":
            loc = [*loc, "kind"]
        loc = [p if isinstance(p, int | str) else str(p) for p in loc]
        reason = str(error.get("msg", "invalid value"))
        reason = reason.removeprefix("Value error, ")
        if error.get("type") == "json_invalid":
            where = loc[1] if len(loc) > 1 else "?"
            detail = (error.get("ctx") or {}).get("error", "")
            items.append({"loc": ["body"], "field": "body",
                          "reason": f"invalid JSON at character {where}: {detail}".rstrip(": ")})
            continue
        cause = (error.get("ctx") or {}).get("error")
        if isinstance(cause, FieldsError) and cause.fields:  # a rule across named fields
            for name in cause.fields:
                at = [*loc, *(int(p) if p.isdigit() else p
                              for p in re.findall(r"[^.\[\]]+", name))]
                items.append({"loc": at, "field": _field_from_loc(at), "reason": reason})
            continue
        items.append({"loc": loc, "field": _field_from_loc(loc), "reason": reason})
    return items


def problem_body(status: int, items: list[dict[str, Any]], detail: str | None = None,
                 **extra: Any) -> dict[str, Any]:
    """The problem-details document of an error answer."""
    try:
        title = HTTPStatus(status).phrase
    except ValueError:
        title = "Error"
    if detail is None:
        detail = "; ".join(f"{i['field']}: {i['reason']}" for i in items[:5]) or title
        if len(items) > 5:
            detail += f"; and {len(items) - 5} more"
    return {"type": "about:blank", "title": title, "status": status, "detail": detail,
            "errors": items, **extra}


def problem_response(status: int, items: list[dict[str, Any]], detail: str | None = None,
                     headers: dict[str, str] | None = None, **extra: Any) -> JSONResponse:
    return JSONResponse(status_code=status, content=problem_body(status, items, detail, **extra),
                        media_type=PROBLEM_MEDIA_TYPE, headers=headers)


def problem(status: int, field: str, reason: str, headers: dict[str, str] | None = None,
            **extra: Any) -> JSONResponse:
    """A problem answer with one field at fault."""
    return problem_response(status, [ApiError(status, field, reason, **extra).item()],
                            headers=headers)


def _http_exception_items(exc: StarletteHTTPException, request: Request) -> list[dict[str, Any]]:
    if exc.status_code == 404:
        return [{"loc": ["path"], "field": "path",
                 "reason": f"no such resource: {request.url.path[:200]}"}]
    if exc.status_code == 405:
        return [{"loc": ["method"], "field": "method",
                 "reason": f"{request.method} is not allowed on {request.url.path[:200]}"}]
    detail = exc.detail
    if isinstance(detail, list):
        return [d if isinstance(d, dict) and "field" in d else
                {"loc": [], "field": "request", "reason": str(d)} for d in detail]
    if exc.status_code == 400:  # the framework could not read the body
        return [{"loc": ["body"], "field": "body", "reason": body_parse_reason(exc)}]
    return [{"loc": [], "field": "request", "reason": str(detail)}]


def body_parse_reason(exc: StarletteHTTPException) -> str:
    """Why a body could not be read, from the exception FastAPI (``"There was an error
    parsing the body"``) or Starlette (a malformed multipart body) raised the 400 from."""
    cause = exc.__cause__
    if isinstance(cause, UnicodeDecodeError):
        return (f"the body is not JSON in UTF-8, UTF-16 or UTF-32: {cause.encoding} cannot "
                f"decode byte {cause.start}")
    if isinstance(cause, RecursionError):
        return "the JSON body is nested too deeply"
    if cause is not None:
        return f"the body cannot be read as its Content-Type says ({type(cause).__name__})"
    return f"the body cannot be read as its Content-Type says: {str(exc.detail)[:200]}"


def allowed_methods(app: Any, path: str) -> list[str]:
    """The methods the published contract (OpenAPI) documents for ``path``."""
    table = getattr(app.state, "allowed_methods", None)
    if table is None:
        table = []
        for template, operations in app.openapi().get("paths", {}).items():
            pattern = "^" + re.sub(r"\\\{[^}]+\\\}", "[^/]+", re.escape(template)) + "$"
            table.append((re.compile(pattern), sorted(m.upper() for m in operations)))
        app.state.allowed_methods = table
    for pattern, methods in table:
        if pattern.match(path):
            return methods
    return []


def install_handlers(app: FastAPI) -> None:
    """Register the handlers on ``app`` (problem details for every error)."""

    @app.exception_handler(ApiError)
    async def _api_error(_request: Request, exc: ApiError) -> JSONResponse:
        return problem_response(exc.status, [exc.item()], headers=exc.headers or None)

    @app.exception_handler(RequestValidationError)
    async def _validation_error(_request: Request, exc: RequestValidationError) -> JSONResponse:
        return problem_response(422, validation_items(exc.errors()))

    @app.exception_handler(StarletteHTTPException)
    async def _http_error(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        headers = dict(getattr(exc, "headers", None) or {})
        if exc.status_code == 405:
            headers["Allow"] = ", ".join(allowed_methods(request.app, request.url.path))
        return problem_response(exc.status_code, _http_exception_items(exc, request),
                                headers=headers or None)

    @app.exception_handler(DataError)
    async def _data_error(_request: Request, exc: DataError) -> JSONResponse:
        # a value the database cannot store (too long, out of range, a NUL byte): the
        # client's input, not a server failure; the driver's text is not sent
        log.info("database refused a value: %s", exc.orig)
        return problem(422, "body", "a value cannot be stored: too long, out of range, or "
                       "holding a NUL byte")

    @app.exception_handler(IntegrityError)
    async def _integrity_error(_request: Request, exc: IntegrityError) -> JSONResponse:
        log.info("integrity conflict: %s", exc.orig)
        return problem(409, "body", "conflicts with stored data (a duplicate or a reference "
                       "to something that does not exist)")

    @app.exception_handler(OverflowError)
    async def _overflow(_request: Request, _exc: OverflowError) -> JSONResponse:
        return problem(422, "body", "a number is out of range (integers are 64-bit)")

    @app.exception_handler(OperationalError)
    async def _operational(_request: Request, exc: OperationalError) -> JSONResponse:
        log.warning("database unavailable: %s", exc.orig)
        return problem(503, "database", "the database is busy or unavailable; try again",
                       headers={"Retry-After": "5"})


def from_value_error(exc: ValueError, prefix: str = "", status: int = 422) -> ApiError:
    """An :class:`ApiError` from a library ``ValueError`` phrased ``"field: reason"``."""
    message = str(exc)
    field, sep, reason = message.partition(": ")
    if not sep or " " in field.strip():
        field, reason = "body", message
    field = field.strip()
    if prefix:
        field = f"{prefix}.{field}" if not field.startswith("[") else f"{prefix}{field}"
    return ApiError(status, field, reason.strip())
