"""Requests uvicorn's parser rejects before the app sees them get the service's one error
format (RFC 9457 problem details, issue 14 §3), from the real server ``wearcast serve`` runs."""

from __future__ import annotations

import json
import socket
from typing import Any
from urllib.parse import urlsplit

import pytest

from wearcast.service.http_protocol import unparseable_request_answer


def _raw_exchange(base: str, request: bytes) -> tuple[int, dict[str, str], bytes]:
    """Send ``request`` bytes as they are; read the answer until the server closes."""
    host, port = urlsplit(base).hostname, urlsplit(base).port
    with socket.create_connection((host, port), timeout=20) as sock:
        sock.sendall(request)
        chunks = []
        while chunk := sock.recv(65536):
            chunks.append(chunk)
    head, _, body = b"".join(chunks).partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    headers = dict((k.strip().lower(), v.strip())
                   for k, v in (line.split(":", 1) for line in lines[1:]))
    return int(lines[0].split()[1]), headers, body


@pytest.mark.parametrize("request_bytes", [
    b"GET /v1/health HTTP/1.1\r\nHost: x\r\nX-Bad: a\x01b\r\n\r\n",   # control char in a header
    b"GET /v1/he alth HTTP/1.1\r\nHost: x\r\n\r\n",                       # space inside the target
    b"NOT-HTTP\r\n\r\n",                                                  # no request line at all
], ids=["control-char-header", "bad-request-line", "not-http"])
def test_unparseable_requests_get_problem_details(real_server: Any, request_bytes: bytes) -> None:
    status, headers, body = _raw_exchange(real_server.base, request_bytes)
    assert status == 400
    assert headers["content-type"] == "application/problem+json"
    assert headers["connection"] == "close"
    assert int(headers["content-length"]) == len(body)
    problem = json.loads(body)
    assert problem["status"] == 400 and problem["title"] == "Bad Request"
    assert problem["errors"][0]["field"] == "request"
    assert "malformed" in problem["errors"][0]["reason"]


def test_the_answer_is_well_framed_problem_details() -> None:
    """The bytes written to the socket: a status line, a content length that matches the JSON
    body, and the body's fields (no server needed)."""
    raw = unparseable_request_answer("why")
    head, _, body = raw.partition(b"\r\n\r\n")
    assert head.startswith(b"HTTP/1.1 400 Bad Request\r\n")
    assert f"content-length: {len(body)}".encode() in head
    doc = json.loads(body)
    assert doc == {"type": "about:blank", "title": "Bad Request", "status": 400,
                   "detail": "request: why",
                   "errors": [{"loc": ["request"], "field": "request", "reason": "why"}]}
