"""The import pipeline: readers → profile processing → bulk inserts under a pending batch.

``import_upload`` streams the records of an upload (long CSV, parameter CSV, MiniProf files
with a manifest, or a zip of these; :mod:`wearcast.service.readers`), processes each profile
(cleaning, alignment, wear curve, wear areas, recomputed Sd/Sh/qR;
:func:`wearcast.statistics.processing.process_profile`, for free-fit profiles a chunk at a time
by :func:`wearcast.statistics.processing_batch.process_profiles_free` with the same results to
round-off) and inserts the measurements in chunks
with ``session.execute(insert(...), rows)`` — no ORM object per row, points and wear curves as
little-endian float32 blobs — so memory stays bounded however large the upload.

Placement and warnings: a MiniProf profile (``ProfileRecord.instrument_datum``) is placed by
the instrument's own datum and aligned to its reference by a vertical shift only
(``process_profile(alignment="datum")``); other profiles by the free rigid fit. The stored
points are always the file's. Each measurement keeps its warnings (header versus recomputed
Sd/Sh/qR, reference mismatch, datum found or guessed, points dropped by cleaning) and the
import answer lists them per file and line. A shape that does not fit its declared reference
(:mod:`wearcast.statistics.reference_check`) is stored with ``reference_fits = False`` and
without wear areas or wear curve, so it stays out of wear statistics until a reference that
fits is given (:func:`apply_reference`).

Idempotency: a batch is identified by the SHA-256 of its content (file, and manifest when
given) and optionally by an ``Idempotency-Key``; importing the same content or key again
creates nothing and returns the first batch with ``duplicate=True`` (409 while the first
import still runs). A measurement whose (wheel_id, mileage_km) is already stored (or appears
twice in the upload) is skipped and counted in ``duplicates``.

Atomic without one long transaction: the batch is opened ``pending`` in a short transaction,
its measurements are inserted chunk by chunk, each chunk a short transaction of its own (so
on SQLite another write waits for one chunk at most, not for the whole upload), and it is
flipped to ``complete`` in one last short transaction
(:mod:`wearcast.service.pending_batches`). Until then none of it is visible to any read
(:mod:`wearcast.service.batch_visibility`). Any error discards the pending batch and all it
wrote (and the raw file it stored) and is reported with file, line, field and reason; a
batch left pending by a killed process is discarded at the next start
(:mod:`wearcast.service.housekeeping`).

This module holds the upload's steps (checksum, idempotency, raw files, batch); the
records are read by :mod:`wearcast.service.readers`, checked, processed and inserted chunk by
chunk by :mod:`wearcast.service.import_staging` (wheels: :mod:`~wearcast.service.import_registry`,
processing: :mod:`~wearcast.service.import_pool`, rows and warnings:
:mod:`~wearcast.service.measurement_rows`), answered by :mod:`~wearcast.service.import_result`,
and :func:`~wearcast.service.wheel_reference.apply_reference` re-takes a wheel against a
reference.
"""

from __future__ import annotations

import hashlib
import io
import logging
import zipfile
import zlib
from pathlib import Path
from typing import BinaryIO

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service import rawfiles
from wearcast.service.batch_visibility import COMPLETE, seeing_pending
from wearcast.service.errors import ApiError, Conflict, Unprocessable

# service.model_store imports the processing under its former name from here (that module is
# not edited on this branch); new code imports import_pool.process_with_reference.
from wearcast.service.import_pool import process_with_reference as _process_arrays  # noqa: F401
from wearcast.service.import_result import ImportResult, duplicate_result
from wearcast.service.import_staging import DEFAULT_CHUNK, Progress, write_records
from wearcast.service.pending_batches import complete_batch, discard_batch, open_batch
from wearcast.service.readers.bundle import ZipLimits
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.settings import Settings

log = logging.getLogger(__name__)

def import_file_error(exc: ImportFileError) -> ApiError:
    """A reader's error as a 422 naming file, line, field and reason."""
    field = exc.field or "file"
    return Unprocessable(field, exc.reason, file=exc.file, line=exc.line)


def _existing_batch(session: Session, *, checksum: str | None = None,
                    key: str | None = None) -> db.ImportBatch | None:
    if key is not None:
        found = session.scalar(select(db.ImportBatch).where(db.ImportBatch.idempotency_key == key))
        if found is not None:
            return found
    if checksum is not None:
        return session.scalar(select(db.ImportBatch)
                              .where(db.ImportBatch.checksum_sha256 == checksum))
    return None



#: Errors of a damaged or unsupported upload raised while it is read (a zip member with a bad
#: CRC, a truncated deflate stream, an encrypted member, bytes that are not UTF-8 text).
DAMAGED_UPLOAD = (zipfile.BadZipFile, zlib.error, EOFError, NotImplementedError,
                  UnicodeDecodeError, zipfile.LargeZipFile)


def _limits(settings: Settings) -> ZipLimits:
    return ZipLimits(max_members=settings.max_zip_members,
                     max_member_bytes=settings.max_decompressed_bytes,
                     max_total_bytes=settings.max_decompressed_bytes,
                     max_line_bytes=settings.max_line_bytes, max_columns=settings.max_columns)


def import_upload(session: Session, raw_dir: Path, stream: BinaryIO, file_name: str, *,
                  manifest: bytes | None = None, manifest_name: str | None = None,
                  idempotency_key: str | None = None, chunk_size: int = DEFAULT_CHUNK,
                  progress: Progress | None = None, settings: Settings | None = None
                  ) -> ImportResult:
    """Import one upload atomically; see the module docstring for the rules.

    The records are read, checked and processed outside any write transaction and inserted
    in short chunk transactions under a pending batch
    (:mod:`wearcast.service.import_staging`), so the write lock is held for one chunk at a
    time. ``settings`` (default: the serving app's, else the environment's) gives the
    limits: zip members and decompressed size, CSV line length and columns, points per
    profile (422 naming the limit).
    """
    from wearcast.service import idempotency

    if settings is None:
        from wearcast.service.auth import current_settings

        settings = current_settings.get() or Settings()
    if idempotency_key is not None and not 1 <= len(idempotency_key) <= 200:
        raise Unprocessable("Idempotency-Key", "must be 1 to 200 characters")
    file_sha, size = rawfiles.sha256_of_stream(stream)
    if size == 0:
        raise Unprocessable("file", f"{file_name} is empty")
    digest = hashlib.sha256(file_sha.encode())
    if manifest is not None:
        digest.update(b"\0manifest\0" + hashlib.sha256(manifest).hexdigest().encode())
    checksum = digest.hexdigest()
    if idempotency_key is not None:
        found = _existing_batch(session, key=idempotency_key)
        if found is not None:
            if found.checksum_sha256 != checksum:
                raise Unprocessable("Idempotency-Key", "this key was used for a different "
                                    "request (another file or manifest); use a new key")
            return _answer_existing(session, found)
        done_batch = idempotency.claim(session, idempotency_key, checksum)
        if done_batch is not None:
            batch_row = session.get(db.ImportBatch, done_batch)
            if batch_row is not None:
                return _answer_existing(session, batch_row)
    try:
        result = _import_claimed(session, raw_dir, stream, file_name, file_sha, checksum,
                                 manifest, manifest_name, idempotency_key, chunk_size,
                                 progress, settings)
    except BaseException:
        if idempotency_key is not None:
            idempotency.release(session, idempotency_key)
        raise
    if idempotency_key is not None:
        idempotency.complete(session, idempotency_key, result.batch_id)
    return result


def _import_claimed(session: Session, raw_dir: Path, stream: BinaryIO, file_name: str,
                    file_sha: str, checksum: str, manifest: bytes | None,
                    manifest_name: str | None, idempotency_key: str | None, chunk_size: int,
                    progress: Progress | None, settings: Settings) -> ImportResult:
    found = _existing_batch(session, checksum=checksum)
    if found is not None:
        return _answer_existing(session, found)
    session.rollback()  # end the reads: the batch is opened in a transaction of its own
    stored_files: list[rawfiles.StoredFile] = []
    batch_id: int | None = None
    try:
        stored_files.append(rawfiles.store(raw_dir, stream, file_sha))
        if manifest is not None:
            stored_files.append(rawfiles.store(raw_dir, io.BytesIO(manifest),
                                               hashlib.sha256(manifest).hexdigest()))
        from wearcast.service.import_csv_blocks import parse_in_workers, read_profiles
        from wearcast.service.readers.bundle import iter_upload

        batch_id = open_batch(session, checksum=checksum, idempotency_key=idempotency_key,
                              file_name=file_name, raw_files=[
            {"role": role, "name": name, "sha256": stored.sha256,
             "size_bytes": stored.size_bytes, "storage_path": stored.relative_path}
            for role, stored, name in zip(("file", "manifest"), stored_files,
                                          (file_name, manifest_name or "manifest.csv"),
                                          strict=False)])
        records = iter_upload(stream, file_name, manifest=manifest, limits=_limits(settings),
                              profile_reader=read_profiles if parse_in_workers(
                                  settings.import_parse_in_workers) else None)
        with seeing_pending(session):
            written = write_records(session, records, batch_id, chunk_size=chunk_size,
                                    max_points=settings.max_points_per_profile,
                                    max_id_length=settings.max_id_length, progress=progress)
            if written.counts.records == 0:
                raise Unprocessable("file", f"{file_name} holds no measurements")
            counts = complete_batch(session, batch_id, written)
    except ImportFileError as exc:
        _abort(session, raw_dir, stored_files, batch_id)
        raise import_file_error(exc) from exc
    except DAMAGED_UPLOAD as exc:
        _abort(session, raw_dir, stored_files, batch_id)
        raise Unprocessable("file", f"{file_name} is damaged or not readable: "
                            f"{type(exc).__name__}: {str(exc)[:200]}") from exc
    except IntegrityError as exc:
        _abort(session, raw_dir, stored_files, batch_id)
        found = _existing_batch(session, checksum=checksum, key=idempotency_key)
        if found is not None:  # a concurrent import of the same content came first
            return _answer_existing(session, found)
        raise Conflict("file", f"{file_name} conflicts with data stored meanwhile; "
                       "try again") from exc
    except BaseException:
        _abort(session, raw_dir, stored_files, batch_id)
        raise
    return ImportResult(batch_id=batch_id, duplicate=False, file_name=file_name,
                        records=counts.records, created=counts.created,
                        duplicates=counts.duplicates, points=counts.points,
                        warnings=counts.listed(), warnings_total=counts.warnings_total)


def _answer_existing(session: Session, found: db.ImportBatch) -> ImportResult:
    """The first import's answer (``duplicate``), or 409 while that import still runs."""
    if found.status != COMPLETE:
        error: ApiError = Conflict("file", f"the same content is being imported now (batch "
                                   f"{found.id}); retry when it has finished")
        error.headers = {"Retry-After": "5"}
        raise error
    return duplicate_result(session, found)


def _abort(session: Session, raw_dir: Path, stored_files: list[rawfiles.StoredFile],
           batch_id: int | None) -> None:
    """Undo a failed import: its open transaction, its pending batch and what that batch
    wrote (:func:`~wearcast.service.pending_batches.discard_batch`), its raw files."""
    session.rollback()
    if batch_id is not None:
        try:
            discard_batch(session, batch_id)
        except Exception:  # the next start removes it (housekeeping); keep the first error
            session.rollback()
            log.exception("could not discard pending import batch %s", batch_id)
            return
    for stored in stored_files:
        rawfiles.discard(raw_dir, stored)

