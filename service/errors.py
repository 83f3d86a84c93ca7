"""Errors a client can fix, and the handlers that turn every one into a 4xx naming the field.

Every error body has the shape ``{"detail": [{"loc": [...], "field": "...", "reason": "..."}]}``
(plus ``file``/``line`` for import errors), for FastAPI's own validation errors too.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse


class ApiError(Exception):
    """A request the client can correct: HTTP ``status``, the offending ``field`` and why."""

    def __init__(self, status: int, field: str, reason: str, **extra: Any) -> None:
        super().__init__(f"{field}: {reason}")
        self.status = status
        self.field = field
        self.reason = reason
        self.extra = extra

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
        loc = [p for p in error.get("loc", ()) if not (isinstance(p, str) and "[" in p)]
        reason = str(error.get("msg", "invalid value"))
        reason = reason.removeprefix("Value error, ")
        if error.get("type") == "json_invalid":
            where = loc[1] if len(loc) > 1 else "?"
            detail = (error.get("ctx") or {}).get("error", "")
            items.append({"loc": ["body"], "field": "body",
                          "reason": f"invalid JSON at character {where}: {detail}".rstrip(": ")})
            continue
        items.append({"loc": loc, "field": _field_from_loc(loc), "reason": reason})
    return items


def install_handlers(app: FastAPI) -> None:
    """Register the handlers on ``app``."""

    @app.exception_handler(ApiError)
    async def _api_error(_request: Request, exc: ApiError) -> JSONResponse:
        return JSONResponse(status_code=exc.status, content={"detail": [exc.item()]})

    @app.exception_handler(RequestValidationError)
    async def _validation_error(_request: Request, exc: RequestValidationError) -> JSONResponse:
        return JSONResponse(status_code=422, content={"detail": validation_items(exc.errors())})


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
