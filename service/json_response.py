"""JSON answers serialised straight from their (already validated) pydantic models.

A plain ``def`` route that returns a model has FastAPI validate it against the
``response_model`` once more, in the threadpool — one more thread hop per request — before
serialising it. The common GET routes build their models themselves (validated when built),
so they answer with :func:`json_response` instead; their ``response_model`` still documents
the answer.
"""

from __future__ import annotations

from collections.abc import Sequence

from pydantic import BaseModel
from starlette.responses import Response


def json_response(value: BaseModel | Sequence[BaseModel], status_code: int = 200) -> Response:
    """``value`` (a model or a list of models) as ``application/json``."""
    if isinstance(value, BaseModel):
        body = value.model_dump_json().encode()
    else:
        body = b"[" + b",".join(item.model_dump_json().encode() for item in value) + b"]"
    return Response(content=body, status_code=status_code, media_type="application/json")
