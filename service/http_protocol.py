"""uvicorn's HTTP/1.1 protocols answering unparseable requests with problem details.

A request uvicorn's parser rejects before the application sees it (a control character in a
header, a malformed request line, a header block past h11's size limit) is answered by uvicorn
itself with a plain-text ``400 Invalid HTTP request received.``. That breaks the service's one
error format (RFC 9457 problem details, :mod:`wearcast.service.errors`) for a schema-driven
client. These subclasses keep uvicorn's parsing and connection handling and only change the
body of that answer; ``wearcast serve`` passes them as uvicorn's ``http`` protocol.
"""

from __future__ import annotations

import json
from typing import Any

from uvicorn.protocols.http.h11_impl import H11Protocol
from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

from wearcast.service.errors import PROBLEM_MEDIA_TYPE, problem_body

#: The field an unparseable request is blamed on: the request itself, as HTTP framed it.
FIELD = "request"


def unparseable_request_answer(reason: str) -> bytes:
    """The complete HTTP/1.1 400 answer (status line, headers, problem body) to a request the
    parser rejected; the connection is closed after it (``connection: close``)."""
    body = json.dumps(problem_body(400, [{"loc": [FIELD], "field": FIELD, "reason": reason}]),
                      separators=(",", ":")).encode("utf-8")
    head = ("HTTP/1.1 400 Bad Request\r\n"
            f"content-type: {PROBLEM_MEDIA_TYPE}\r\n"
            f"content-length: {len(body)}\r\n"
            "connection: close\r\n\r\n").encode("ascii")
    return head + body


def _reason(msg: str) -> str:
    return (f"{msg.rstrip('.')}: the request line or a header is malformed (control "
            "character, bad framing) or the header block is too large")


class _ProblemAnswer:
    """The 400 answer of both protocols: problem details, then the connection closed."""

    transport: Any

    def send_400_response(self, msg: str) -> None:
        self.transport.write(unparseable_request_answer(_reason(msg)))
        self.transport.close()


class ProblemHttpToolsProtocol(_ProblemAnswer, HttpToolsProtocol):
    """uvicorn's httptools protocol (the default with ``uvicorn[standard]``)."""


class ProblemH11Protocol(_ProblemAnswer, H11Protocol):
    """uvicorn's pure-Python h11 protocol (where httptools is not installed)."""


def problem_http_protocol() -> type:
    """The protocol class uvicorn would pick by itself (``http="auto"``), with problem answers."""
    try:
        import httptools  # noqa: F401
    except ImportError:  # pragma: no cover - uvicorn[standard] installs httptools
        return ProblemH11Protocol
    return ProblemHttpToolsProtocol
