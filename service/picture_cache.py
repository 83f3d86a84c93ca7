"""Rendered pictures keyed by their inputs: strong ETags, ``304 Not Modified`` and a small
bounded in-process cache of the rendered bytes.

A picture is a pure figure builder (:mod:`wearcast.service.pictures`,
:mod:`wearcast.service.wheel_pictures`: arrays in, bytes out) applied to inputs read from the
database. Reading the inputs and predicting take milliseconds; drawing them with matplotlib
takes a hundred or more. So a picture request always reads its inputs afresh, and
:func:`picture_key` hashes them — every array, frame, number and text the builder is given,
the builder's name, the source of the modules that draw and matplotlib's version — into the
picture's key. The key is the strong ``ETag`` (the same in every worker process, as it
depends only on the inputs), and the cache of rendered bytes (:data:`RENDERED`, at most
:data:`CACHE_MAX_BYTES`) is keyed the same way. Whatever data change a picture depends on
(a new or removed measurement, another reference, a changed route) changes its inputs and
hence its key, so nothing needs invalidating and a stale picture is never served.

``If-None-Match`` naming the current ETag is answered ``304`` without drawing or sending the
picture. ``Cache-Control: private, no-cache``: a client may keep the picture but must
revalidate it (the URL stays the same while the data under it change), and shared caches
must not keep it (the request carried an API key).
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import hashlib
import importlib
import inspect
import logging
import struct
import threading
from collections import OrderedDict
from collections.abc import Callable
from functools import cache
from typing import Any, NamedTuple

import numpy as np
import pandas as pd
from starlette.requests import Request
from starlette.responses import Response

log = logging.getLogger(__name__)

#: Bytes of rendered pictures kept per process (least recently used dropped first).
CACHE_MAX_BYTES = 32 * 1024 * 1024
#: A picture larger than this [bytes] is sent but not kept.
MAX_CACHED_PICTURE_BYTES = 4 * 1024 * 1024
CACHE_CONTROL = "private, no-cache"
#: Modules whose drawing code is part of every picture's key.
DRAWING_MODULES = ("wearcast.service.pictures", "wearcast.service.wheel_pictures")


class PictureJob(NamedTuple):
    """A pure figure builder and the arguments to call it with."""

    build: Callable[..., bytes]
    args: tuple[Any, ...]
    kwargs: dict[str, Any]


class Unhashable(TypeError):
    """An input of a type :func:`picture_key` does not know (the picture is then drawn
    every time and sent without an ETag, never cached under an incomplete key)."""


def _feed(h: Any, value: Any) -> None:
    """Add ``value`` to the hash ``h`` unambiguously (type tag, length, content)."""
    if value is None:
        h.update(b"N")
    elif isinstance(value, bool | np.bool_):
        h.update(b"T" if value else b"F")
    elif isinstance(value, int | np.integer):
        h.update(b"I%d;" % int(value))
    elif isinstance(value, float | np.floating):
        h.update(b"D" + struct.pack("<d", float(value)))
    elif isinstance(value, str):
        data = value.encode("utf-8", "surrogatepass")
        h.update(b"S%d:" % len(data) + data)
    elif isinstance(value, bytes):
        h.update(b"Y%d:" % len(value) + value)
    elif isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            h.update(b"O%s:" % str(value.shape).encode())
            items = value.ravel().tolist()
            if all(type(item) is str for item in items):
                # a text column (wheel ids, routes) in one update: lengths, then the bytes
                encoded = [item.encode("utf-8", "surrogatepass") for item in items]
                h.update(b"Z" + np.array([len(e) for e in encoded], np.int64).tobytes())
                h.update(b"".join(encoded))
            else:
                for item in items:
                    _feed(h, item)
        else:
            array = np.ascontiguousarray(value)
            h.update(b"A" + array.dtype.str.encode() + str(array.shape).encode() + b":")
            h.update(array.tobytes())
    elif isinstance(value, pd.DataFrame):
        h.update(b"P%d:" % value.shape[1])
        _feed(h, [str(c) for c in value.columns])
        _feed(h, value.index.to_numpy())
        for column in value.columns:
            _feed(h, value[column].to_numpy())
    elif isinstance(value, pd.Series):
        h.update(b"Q")
        _feed(h, value.index.to_numpy())
        _feed(h, value.to_numpy())
    elif isinstance(value, dt.date | dt.datetime | dt.time):
        _feed(h, f"{type(value).__name__}:{value.isoformat()}")
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = dataclasses.fields(value)
        h.update(b"C" + type(value).__qualname__.encode() + b"%d:" % len(fields))
        for f in fields:
            _feed(h, f.name)
            _feed(h, getattr(value, f.name))
    elif isinstance(value, dict):
        items = sorted(value.items(), key=lambda kv: repr(kv[0]))
        h.update(b"M%d:" % len(items))
        for key, item in items:
            _feed(h, key)
            _feed(h, item)
    elif isinstance(value, list | tuple) and value and all(type(v) is float for v in value):
        # a list of numbers (a predicted profile) in one update, as its float64 bytes
        h.update(b"R%d:" % len(value) + np.asarray(value, np.float64).tobytes())
    elif isinstance(value, list | tuple):
        h.update(b"L%d:" % len(value))
        for item in value:
            _feed(h, item)
    else:
        raise Unhashable(f"cannot key a picture input of type {type(value).__name__}")


@cache
def _drawing_code_digest() -> str:
    """The source of the drawing modules and matplotlib's version: a changed drawing gets a
    new key even for unchanged data (e.g. after an upgrade, for a client's kept ETag)."""
    import matplotlib

    h = hashlib.sha256(f"matplotlib {matplotlib.__version__}".encode())
    for name in DRAWING_MODULES:
        try:
            h.update(inspect.getsource(importlib.import_module(name)).encode())
        except (OSError, TypeError):  # no source (e.g. a zipped install): the name only
            h.update(name.encode())
    return h.hexdigest()


def picture_key(job: PictureJob) -> str | None:
    """The hex key of a picture (its inputs and drawing code), or None when an input cannot
    be keyed."""
    h = hashlib.sha256(_drawing_code_digest().encode())
    _feed(h, f"{job.build.__module__}.{job.build.__qualname__}")
    try:
        _feed(h, job.args)
        _feed(h, job.kwargs)
    except Unhashable as exc:
        log.warning("picture %s not cached: %s", job.build.__qualname__, exc)
        return None
    return h.hexdigest()[:40]


class RenderedCache:
    """Rendered pictures by key, least recently used dropped beyond ``max_bytes``; a picture
    being drawn is drawn once, concurrent requests for it wait for it."""

    def __init__(self, max_bytes: int = CACHE_MAX_BYTES,
                 max_item_bytes: int = MAX_CACHED_PICTURE_BYTES) -> None:
        self.max_bytes = max_bytes
        self.max_item_bytes = max_item_bytes
        self._data: OrderedDict[str, bytes] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()
        self._drawing: dict[str, threading.Lock] = {}
        self.hits = 0
        self.misses = 0

    def get(self, key: str) -> bytes | None:
        with self._lock:
            content = self._data.get(key)
            if content is not None:
                self._data.move_to_end(key)
                self.hits += 1
            return content

    def put(self, key: str, content: bytes) -> None:
        if len(content) > min(self.max_item_bytes, self.max_bytes):
            return
        with self._lock:
            old = self._data.pop(key, None)
            self._bytes -= len(old) if old is not None else 0
            self._data[key] = content
            self._bytes += len(content)
            while self._bytes > self.max_bytes:
                _, dropped = self._data.popitem(last=False)
                self._bytes -= len(dropped)

    def get_or_render(self, key: str, render: Callable[[], bytes]) -> bytes:
        content = self.get(key)
        if content is not None:
            return content
        with self._lock:
            drawing = self._drawing.setdefault(key, threading.Lock())
        try:
            with drawing:
                content = self.get(key)
                if content is None:
                    with self._lock:
                        self.misses += 1
                    content = render()
                    self.put(key, content)
        finally:
            with self._lock:
                self._drawing.pop(key, None)
        return content

    def clear(self) -> None:
        with self._lock:
            self._data.clear()
            self._bytes = 0
            self.hits = self.misses = 0

    @property
    def size_bytes(self) -> int:
        return self._bytes

    def __len__(self) -> int:
        return len(self._data)


#: The process's rendered pictures.
RENDERED = RenderedCache()


def render(job: PictureJob) -> bytes:
    """The picture's bytes, from the cache when its inputs were drawn before."""
    key = picture_key(job)
    if key is None:
        return job.build(*job.args, **job.kwargs)
    return RENDERED.get_or_render(key, lambda: job.build(*job.args, **job.kwargs))


def _matches(if_none_match: str | None, etag: str) -> bool:
    """RFC 9110 §13.1.2: ``*`` or any listed entity tag equal by weak comparison."""
    if not if_none_match:
        return False
    if if_none_match.strip() == "*":
        return True
    opaque = etag.removeprefix("W/")
    return any(tag.strip().removeprefix("W/") == opaque for tag in if_none_match.split(","))


def picture_response(request: Request, job: PictureJob, media_type: str) -> Response:
    """200 with the picture, its ETag and Cache-Control, or 304 when ``If-None-Match``
    names the current ETag (nothing drawn)."""
    key = picture_key(job)
    if key is None:
        return Response(content=job.build(*job.args, **job.kwargs), media_type=media_type,
                        headers={"Cache-Control": "private, no-store"})
    headers = {"ETag": f'"{key}"', "Cache-Control": CACHE_CONTROL}
    if _matches(request.headers.get("if-none-match"), headers["ETag"]):
        return Response(status_code=304, headers=headers)
    content = RENDERED.get_or_render(key, lambda: job.build(*job.args, **job.kwargs))
    return Response(content=content, media_type=media_type, headers=headers)


#: The OpenAPI entry of a picture's conditional answer.
NOT_MODIFIED: dict[int | str, dict[str, Any]] = {
    304: {"description": "Not Modified: If-None-Match names the picture's current ETag",
          "headers": {"ETag": {"description": "the picture's strong entity tag",
                               "schema": {"type": "string"}}}}}
