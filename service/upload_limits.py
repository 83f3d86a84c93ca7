"""Bounds on uploaded text files, checked while the bytes stream past (so memory stays
bounded on hostile input): the longest line and the number of header columns.

:class:`GuardedStream` wraps a binary stream for the CSV readers; a line longer than
``max_line_bytes`` (a 2 GiB cell) or a header with more than ``max_columns`` names (a million
columns) raises :class:`~wearcast.service.readers.errors.ImportFileError` naming the file, the
line and the limit, after at most ``max_line_bytes`` more bytes have been read.
"""

from __future__ import annotations

import io
from typing import IO, Any

from wearcast.service.readers.errors import ImportFileError

NEWLINE = b"\n"


class GuardedStream(io.RawIOBase):
    """A read-only binary stream that refuses over-long lines and over-wide headers."""

    def __init__(self, inner: IO[bytes], name: str, max_line_bytes: int,
                 max_columns: int) -> None:
        super().__init__()
        self.inner = inner
        self.name = name
        self.max_line_bytes = max_line_bytes
        self.max_columns = max_columns
        self._reset()

    def _reset(self) -> None:
        self._carry = 0          # bytes of the current (unfinished) line seen so far
        self._line = 1           # 1-based number of the current line
        self._header_done = False
        self._header_commas = 0

    # -- checks -------------------------------------------------------------------------
    def _fail(self, what: str, limit: str, value: int) -> None:
        raise ImportFileError(self.name, f"{what} (limit {limit} = {value:,})",
                              line=self._line, field="file")

    def _scan(self, data: bytes) -> None:
        limit = self.max_line_bytes
        if not self._header_done:
            end = data.find(NEWLINE)
            head = data if end < 0 else data[:end]
            self._header_commas += head.count(b",") + head.count(b";")
            if self._header_commas + 1 > self.max_columns:
                self._fail("the header has more columns than accepted", "max_columns",
                           self.max_columns)
            self._header_done = end >= 0
        # every run of limit + 1 bytes must hold a newline; jump from newline to the last
        # newline of the next such window (one C-level search per ~limit bytes)
        position = -1
        carry = self._carry
        n = len(data)
        while True:
            window_end = min(n, position + 1 + (limit + 1 - carry))
            found = data.rfind(NEWLINE, position + 1, window_end)
            if found < 0:
                if carry + (n - position - 1) > limit:
                    self._fail("a line is longer than accepted", "max_line_bytes", limit)
                self._carry = carry + (n - position - 1)
                break
            self._line += data.count(NEWLINE, position + 1, found + 1)
            position, carry = found, 0
            if position == n - 1:
                self._carry = 0
                break

    # -- io -----------------------------------------------------------------------------
    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return bool(self.inner.seekable())

    def tell(self) -> int:
        return self.inner.tell()

    def seek(self, offset: int, whence: int = io.SEEK_SET) -> int:
        position = self.inner.seek(offset, whence)
        if position == 0:
            self._reset()
        return position

    def read(self, size: int | None = -1) -> bytes:
        if size is None or size < 0:
            chunks = []
            while chunk := self.read(1 << 20):
                chunks.append(chunk)
            return b"".join(chunks)
        data = self.inner.read(size)
        if data:
            self._scan(data)
        return data

    def readinto(self, buffer: Any) -> int:
        data = self.read(len(buffer))
        buffer[:len(data)] = data
        return len(data)

    def readline(self, size: int | None = -1) -> bytes:
        cap = self.max_line_bytes + 1 if size is None or size < 0 else size
        line = self.inner.readline(cap)
        if line:
            self._scan(line)
        return line


def guarded(stream: IO[bytes], name: str, max_line_bytes: int, max_columns: int) -> IO[bytes]:
    return GuardedStream(stream, name, max_line_bytes, max_columns)  # type: ignore[return-value]
