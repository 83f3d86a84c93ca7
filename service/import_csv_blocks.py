"""Long profile CSVs parsed in the import pool's worker processes, a block of whole
measurements at a time.

Parsing the text is the importing process's largest cost (about half of it with the
pandas C parser). Here the importing process only cuts the file into blocks of about
:data:`BLOCK_BYTES` that end at a measurement boundary (the last line whose
(``wheel_id``, ``mileage_km``) differs from the next one's, found by reading the block's last
lines back to front) and counts their lines; the worker processes parse them
(:func:`wearcast.service.readers.long_csv.parse_block`, the reader of a whole file, so the
same rules, records and errors) while the importing process inserts. Results are taken in
file order, so records come in file order and the first problem of the file is the one
reported (file, line, field). Across blocks, the importing process checks that no
measurement reappears (the same error as the reader's).

When it pays: the import runs at about min(1 / importer CPU, cores / total CPU) profiles per
second (CPU per profile). Measured with a warm pool (``benchmarks/bench_import.py --warm``,
2 cores, 10,000 profiles), parsing in the workers takes the importing process from 0.5 to
0.29 ms per profile but the workers from 0.25 to 0.60 ms (the block goes through a pipe and
is parsed in pieces of a few MB): with 2 cores the total CPU bounds the rate and the import
is no faster (measured 10-20 % slower on a loaded machine); from 3 cores on the importing
process is the bound and parsing in the workers raises it (by the formula about 2,200 →
3,400 profiles/s). So :func:`parse_in_workers` says yes from :data:`MIN_WORKERS` pool
workers on; the ``import_parse_in_workers`` setting forces either way.

A file that fits in one block, or a pool that cannot run (one core,
``WEARCAST_IMPORT_WORKERS=0``, a broken pool), is parsed in this process with the same
results. At most :data:`IN_FLIGHT_PER_WORKER` blocks per worker are read ahead, so memory
stays bounded however long the file.
"""

from __future__ import annotations

import csv
from collections import deque
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import IO

from wearcast.service import import_pool
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.long_csv import BlockRecords, parse_block, read_header, reappeared
from wearcast.service.readers.records import (
    PROFILE_COLUMNS,
    REQUIRED_META_COLUMNS,
    ProfileRecord,
    check_header,
)

#: Bytes read per block before it is cut back to its last measurement boundary (about 240
#: measurements of 400 points; a measurement longer than this makes its block longer).
BLOCK_BYTES = 8 * 1024**2
#: Blocks read ahead per pool worker (parsing or parsed, not yet taken).
IN_FLIGHT_PER_WORKER = 2

#: Pool workers from which long CSVs are parsed in the workers by default (see the module
#: docstring).
MIN_WORKERS = 3

_Key = tuple[str, float | str]


def parse_in_workers(setting: bool | None = None) -> bool:
    """Whether long CSVs are parsed in the pool's workers: the ``import_parse_in_workers``
    setting when given, else when the pool would have at least :data:`MIN_WORKERS` workers."""
    if setting is not None:
        return setting
    return import_pool.configured_workers() >= MIN_WORKERS


def _line_key(line: bytes, wheel_at: int, mileage_at: int) -> _Key | None:
    """(wheel_id, mileage_km) of a body line as the reader compares them (wheel id stripped,
    mileage as a number when it is one); None for a blank line (the reader skips it)."""
    text = line.decode("utf-8", "replace").rstrip("\r")
    fields = next(csv.reader([text])) if '"' in text else text.split(",")
    if all(not f for f in fields):
        return None
    wheel = fields[wheel_at].strip() if wheel_at < len(fields) else ""
    raw = fields[mileage_at].strip() if mileage_at < len(fields) else ""
    try:
        return wheel, float(raw)
    except ValueError:
        return wheel, raw  # the parser names the bad value


def measurement_cut(data: bytes, wheel_at: int, mileage_at: int, first: int = 0) -> int:
    """The offset after the last line of ``data`` that ends a measurement: the lines after it
    belong to the last measurement of ``data``, which may go on beyond it; -1 when every
    complete line from offset ``first`` on may belong to that one measurement (the block must
    grow)."""
    stop = data.rfind(b"\n")
    last: _Key | None = None
    while stop >= first:
        start = max(data.rfind(b"\n", 0, stop) + 1, first)
        key = _line_key(data[start:stop], wheel_at, mileage_at)
        if key is not None:
            if last is None:
                last = key
            elif key != last:
                return stop + 1
        stop = start - 1
    return -1


def line_count(data: bytes, end: int | None = None) -> int:
    """Lines ended in ``data[:end]`` as the CSV parser counts them (``\\n``, ``\\r\\n`` or a
    lone ``\\r``)."""
    end = len(data) if end is None else end
    count = data.count(b"\n", 0, end)
    if data.find(b"\r", 0, end) >= 0:
        count += data.count(b"\r", 0, end) - data.count(b"\r\n", 0, end)
    return count


#: A block of whole measurements: (file line of its first line, head, body, end); its bytes
#: are ``head + body[:end]`` (joined by the parser, so the importing process copies neither).
Block = tuple[int, bytes, bytes, int]


def blocks(stream: IO[bytes], wheel_at: int, mileage_at: int, block_bytes: int = BLOCK_BYTES
           ) -> Iterator[Block]:
    """The CSV body (the stream positioned after the header line) in blocks of whole
    measurements (:data:`Block`), each cut after the last measurement boundary of its
    last read of about ``block_bytes``."""
    line = 2
    head = b""
    while True:
        body = stream.read(block_bytes)
        if not body:
            if head:
                yield line, head, b"", 0
            return
        # the first line of ``body`` may continue the last line of ``head``: not a candidate
        start = body.find(b"\n") + 1 if head else 0
        cut = measurement_cut(body, wheel_at, mileage_at, start) if start or not head else -1
        if cut <= 0:  # every complete line may be of one measurement: read on
            head += body
            continue
        yield line, head, body, cut
        line += line_count(head) + line_count(body, cut)
        if head.endswith(b"\r") and body.startswith(b"\n"):
            line -= 1  # a \r\n split between the two reads
        head = body[cut:]


def read_profiles(stream: IO[bytes], file_name: str, block_bytes: int | None = None
                  ) -> Iterator[ProfileRecord]:
    """The records of a long profile CSV (the stream at its start), as
    :func:`~wearcast.service.readers.long_csv.iter_profile_records` yields them, parsed a
    block at a time in the import pool's workers (see the module docstring);
    ``block_bytes`` defaults to :data:`BLOCK_BYTES`."""
    columns = read_header(stream, file_name)
    check_header(columns, file_name, REQUIRED_META_COLUMNS + PROFILE_COLUMNS)
    parts = blocks(stream, columns.index("wheel_id"), columns.index("mileage_km"),
                   block_bytes or BLOCK_BYTES)
    seen: dict[tuple[str, float], int] = {}
    first = next(parts, None)
    second = next(parts, None) if first is not None else None
    pool = import_pool.worker_pool() if second is not None else None
    limit = max(IN_FLIGHT_PER_WORKER * import_pool.pool_workers(), 1)
    queue: deque[tuple[Callable[[], BlockRecords], Block]] = deque()
    futures: list[Future[BlockRecords]] = []
    try:
        yield from _taken(queue, futures, parts, [b for b in (first, second) if b is not None],
                          file_name, columns, pool, limit, seen)
    finally:  # an import that stops early (an error) leaves no parsing behind
        for future in futures:
            future.cancel()


def _taken(queue: deque[tuple[Callable[[], BlockRecords], Block]],
           futures: list[Future[BlockRecords]], parts: Iterator[Block], started: list[Block],
           file_name: str, columns: list[str], pool: ProcessPoolExecutor | None, limit: int,
           seen: dict[tuple[str, float], int]) -> Iterator[ProfileRecord]:
    """The records of the blocks, parsed in ``pool`` (None: here), in file order."""

    def submit(block: Block) -> None:
        nonlocal pool
        future: Future[BlockRecords] | None = None
        if pool is not None:
            try:
                future = pool.submit(parse_block, file_name, columns, *block)
                futures[:] = [f for f in futures if not f.done()] + [future]
            except (BrokenProcessPool, RuntimeError):
                import_pool.discard_pool()
                pool = None
        queue.append(((future.result if future is not None else
                       lambda: parse_block(file_name, columns, *block)), block))

    for block in started:
        submit(block)
    while True:
        while len(queue) < limit and (part := next(parts, None)) is not None:
            submit(part)
        if not queue:
            return
        result, block = queue.popleft()
        try:
            records, problem = result()
        except BrokenProcessPool:
            import_pool.discard_pool()
            pool = None
            records, problem = parse_block(file_name, columns, *block)
        del block
        for record in records:
            meta = record.meta
            key = (meta.wheel_id, meta.mileage_km)
            if key in seen:
                raise reappeared(file_name, meta, seen[key])
            seen[key] = meta.source_line or 0
            yield record
        if problem is not None:
            where, reason, at, field = problem
            raise ImportFileError(where, reason, line=at, field=field)
