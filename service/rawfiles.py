"""Raw uploaded files, kept content-addressed on disk: ``<data_dir>/raw/<sha[:2]>/<sha256>``.

Files are written before the import transaction commits (streamed, so memory stays bounded);
a file written for an import that then fails is removed again, and identical content is stored
once whatever its name. The database row (``raw_files``) records name, size and sha256.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

CHUNK_BYTES = 1 << 20


@dataclass(frozen=True)
class StoredFile:
    sha256: str
    size_bytes: int
    relative_path: str
    created: bool  # False when identical content was already stored


def sha256_of_stream(stream: BinaryIO) -> tuple[str, int]:
    """SHA-256 (hex) and size [bytes] of a seekable stream, read from its start."""
    stream.seek(0)
    digest = hashlib.sha256()
    size = 0
    while chunk := stream.read(CHUNK_BYTES):
        digest.update(chunk)
        size += len(chunk)
    stream.seek(0)
    return digest.hexdigest(), size


def store(raw_dir: Path, stream: BinaryIO, sha256: str) -> StoredFile:
    """Copy ``stream`` under its content address (atomic rename; no-op if already there)."""
    relative = f"{sha256[:2]}/{sha256}"
    target = raw_dir / relative
    stream.seek(0)
    if target.exists():
        return StoredFile(sha256, target.stat().st_size, relative, created=False)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=".upload-")
    try:
        with os.fdopen(fd, "wb") as out:
            shutil.copyfileobj(stream, out, CHUNK_BYTES)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    finally:
        stream.seek(0)
    return StoredFile(sha256, target.stat().st_size, relative, created=True)


def discard(raw_dir: Path, stored: StoredFile) -> None:
    """Remove a file this import created (used when the import rolls back)."""
    if stored.created:
        (raw_dir / stored.relative_path).unlink(missing_ok=True)
