"""The import pipeline: readers → profile processing → bulk inserts, one transaction per batch.

``import_upload`` streams the records of an upload (long CSV, parameter CSV, MiniProf files
with a manifest, or a zip of these; :mod:`wearcast.service.readers`), processes each profile
(cleaning, alignment, wear curve, wear areas, recomputed Sd/Sh/qR;
:func:`wearcast.statistics.processing.process_profile`) and inserts the measurements in chunks
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
creates nothing and returns the first batch with ``duplicate=True``. A measurement whose
(wheel_id, mileage_km) is already stored (or appears twice in the upload) is skipped and
counted in ``duplicates``. Any error rolls the whole batch back (and removes the raw file it
stored) and is reported with file, line, field and reason.

This module holds the upload's transaction (checksum, idempotency, raw files, batch); the
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
import zipfile
import zlib
from pathlib import Path
from typing import Any, BinaryIO

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service import rawfiles
from wearcast.service.errors import ApiError, Conflict, Unprocessable

# service.model_store imports the processing under its former name from here (that module is
# not edited on this branch); new code imports import_pool.process_with_reference.
from wearcast.service.import_pool import process_with_reference as _process_arrays  # noqa: F401
from wearcast.service.import_result import ImportResult, duplicate_result
from wearcast.service.import_staging import DEFAULT_CHUNK, Progress, stage_records, write_stage
from wearcast.service.readers.bundle import ZipLimits
from wearcast.service.readers.errors import ImportFileError


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


def _limits(settings: Any) -> ZipLimits:
    return ZipLimits(max_members=settings.max_zip_members,
                     max_member_bytes=settings.max_decompressed_bytes,
                     max_total_bytes=settings.max_decompressed_bytes,
                     max_line_bytes=settings.max_line_bytes, max_columns=settings.max_columns)


def import_upload(session: Session, raw_dir: Path, stream: BinaryIO, file_name: str, *,
                  manifest: bytes | None = None, manifest_name: str | None = None,
                  idempotency_key: str | None = None, chunk_size: int = DEFAULT_CHUNK,
                  progress: Progress | None = None, settings: Any = None) -> ImportResult:
    """Import one upload atomically; see the module docstring for the rules.

    The records are read, checked and processed before the batch's transaction starts
    (:mod:`wearcast.service.import_staging`), so the write lock is held only for the
    inserts. ``settings`` (default: the serving app's, else the environment's) gives the
    limits: zip members and decompressed size, CSV line length and columns, points per
    profile (422 naming the limit).
    """
    from wearcast.service import idempotency

    if settings is None:
        from wearcast.service.auth import current_settings
        from wearcast.service.settings import Settings

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
            return duplicate_result(session, found)
        done_batch = idempotency.claim(session, idempotency_key, checksum)
        if done_batch is not None:
            batch_row = session.get(db.ImportBatch, done_batch)
            if batch_row is not None:
                return duplicate_result(session, batch_row)
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
                    progress: Progress | None, settings: Any) -> ImportResult:
    found = _existing_batch(session, checksum=checksum)
    if found is not None:
        return duplicate_result(session, found)
    stored_files: list[rawfiles.StoredFile] = []
    stage = None
    try:
        stored_files.append(rawfiles.store(raw_dir, stream, file_sha))
        if manifest is not None:
            stored_files.append(rawfiles.store(raw_dir, io.BytesIO(manifest),
                                               hashlib.sha256(manifest).hexdigest()))
        from wearcast.service.readers.bundle import iter_upload

        records = iter_upload(stream, file_name, manifest=manifest, limits=_limits(settings))
        stage = stage_records(session, records, chunk_size=chunk_size,
                              tmp_dir=raw_dir.parent / "tmp",
                              max_points=settings.max_points_per_profile,
                              max_id_length=settings.max_id_length, progress=progress)
        session.rollback()  # end the reads; the write transaction starts below
        if stage.counts.records == 0:
            raise Unprocessable("file", f"{file_name} holds no measurements")
        batch = db.ImportBatch(checksum_sha256=checksum, idempotency_key=idempotency_key,
                               file_name=file_name, n_records=0, n_created=0, n_duplicates=0,
                               n_points=0)
        session.add(batch)
        session.flush()
        for role, stored, name in zip(("file", "manifest"), stored_files,
                                      (file_name, manifest_name or "manifest.csv"),
                                      strict=False):
            session.add(db.RawFile(batch_id=batch.id, role=role, name=name,
                                   sha256=stored.sha256, size_bytes=stored.size_bytes,
                                   storage_path=stored.relative_path))
        session.flush()
        counts = write_stage(session, stage, batch.id)
        batch.n_records, batch.n_created = counts.records, counts.created
        batch.n_duplicates, batch.n_points = counts.duplicates, counts.points
        session.commit()
    except ImportFileError as exc:
        _abort(session, raw_dir, stored_files)
        raise import_file_error(exc) from exc
    except DAMAGED_UPLOAD as exc:
        _abort(session, raw_dir, stored_files)
        raise Unprocessable("file", f"{file_name} is damaged or not readable: "
                            f"{type(exc).__name__}: {str(exc)[:200]}") from exc
    except IntegrityError as exc:
        _abort(session, raw_dir, stored_files)
        found = _existing_batch(session, checksum=checksum, key=idempotency_key)
        if found is not None:  # a concurrent import of the same content won the race
            return duplicate_result(session, found)
        raise Conflict("file", f"{file_name} conflicts with data stored meanwhile; "
                       "try again") from exc
    except BaseException:
        _abort(session, raw_dir, stored_files)
        raise
    finally:
        if stage is not None:
            stage.close()
    return ImportResult(batch_id=batch.id, duplicate=False, file_name=file_name,
                        records=counts.records, created=counts.created,
                        duplicates=counts.duplicates, points=counts.points,
                        warnings=counts.listed(), warnings_total=counts.warnings_total)


def _abort(session: Session, raw_dir: Path, stored_files: list[rawfiles.StoredFile]) -> None:
    session.rollback()
    for stored in stored_files:
        rawfiles.discard(raw_dir, stored)

