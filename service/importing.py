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
"""

from __future__ import annotations

import hashlib
import io
import math
import multiprocessing
import os
import threading
import zipfile
import zlib
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from itertools import islice
from pathlib import Path
from typing import Any, BinaryIO, TypeAlias

import numpy as np
from sqlalchemy import insert, select, tuple_
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service import rawfiles
from wearcast.service.errors import ApiError, Conflict, NotFound, Unprocessable
from wearcast.service.import_worker import Processed, RefTuple, process_arrays, process_batch
from wearcast.service.readers.bundle import ZipLimits
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.records import ParameterRecord, ProfileRecord
from wearcast.service.reference_store import (
    OWN_BASELINE,
    ReferenceSpec,
    is_own_baseline,
    own_baseline_spec,
    resolve_reference,
)

Record: TypeAlias = ProfileRecord | ParameterRecord
Progress = Callable[[int], None]

DEFAULT_CHUNK = 500
#: Header Sd/Sh/qR farther than this [mm] from the recomputed ones are reported.
HEADER_TOLERANCE_MM = 0.3
#: At most this many warnings are listed in an import answer (all are stored).
MAX_WARNINGS = 1000
#: Chunks with at least this many new profiles are processed by a pool of worker processes;
#: smaller ones (single posts, the example fleet, tests) stay in the calling process.
PARALLEL_MIN_PROFILES = 256


@dataclass(frozen=True)
class ImportResult:
    """What an import did: ``created`` measurements stored, ``duplicates`` skipped."""

    batch_id: int
    duplicate: bool
    file_name: str
    records: int
    created: int
    duplicates: int
    points: int
    warnings: tuple[dict[str, Any], ...] = ()
    warnings_total: int = 0

    def as_dict(self) -> dict[str, Any]:
        out = dict(self.__dict__)
        out["warnings"] = list(self.warnings)
        return out


def import_file_error(exc: ImportFileError) -> ApiError:
    """A reader's error as a 422 naming file, line, field and reason."""
    field = exc.field or "file"
    return Unprocessable(field, exc.reason, file=exc.file, line=exc.line)


def f32(values: Any) -> bytes:
    """Compact blob of an array: little-endian float32."""
    return np.ascontiguousarray(values, dtype="<f4").tobytes()


def from_f32(blob: bytes | None) -> np.ndarray | None:
    return None if blob is None else np.frombuffer(blob, dtype="<f4").astype(float)


def _finite_or_none(value: Any) -> float | None:
    if value is None:
        return None
    number = float(value)
    return number if math.isfinite(number) else None


class _Registry:
    """Per-import caches of wheels, vehicles and route names, checked for consistency."""

    def __init__(self, session: Session, defer_writes: bool = False) -> None:
        self.session = session
        self.wheels: dict[str, tuple[str, str, int, str]] = {}
        self.vehicles: set[str] = set()
        self.routes: dict[str, str] = {}
        self.references: dict[str, ReferenceSpec] = {}
        self.own_wheels: set[str] = set()
        #: with ``defer_writes`` new wheels are kept here and inserted by ``write_new``
        self.defer_writes = defer_writes
        self.new_wheels: dict[str, dict[str, Any]] = {}
        for route_id, name in session.execute(select(db.Route.id, db.Route.name)):
            self.routes[str(route_id)] = name
            self.routes[name] = name

    def reference(self, record: ProfileRecord) -> ReferenceSpec:
        """The record's declared reference, resolved once per name; the own baseline is
        processed against S1002 first and re-referenced after the batch is stored."""
        name = record.meta.reference_profile
        if is_own_baseline(name):
            name = "S1002"
        spec = self.references.get(name)
        if spec is None:
            try:
                spec = resolve_reference(self.session, name)
            except Unprocessable as exc:
                meta = record.meta
                raise ImportFileError(meta.source_file, exc.reason,
                                      line=record.manifest_line or meta.source_line,
                                      field="reference_profile") from None
            self.references[name] = spec
        return spec

    def route_name(self, ref: str | None) -> str | None:
        return None if ref is None else self.routes.get(str(ref), str(ref))

    def ensure_wheels(self, records: list[Record]) -> None:
        wanted = {r.meta.wheel_id for r in records} - self.wheels.keys()
        if wanted:
            for row in self.session.execute(
                select(db.Wheel.wheel_id, db.Wheel.vehicle_id, db.Wheel.bogie_type,
                       db.Wheel.axle, db.Wheel.side).where(db.Wheel.wheel_id.in_(wanted))
            ):
                self.wheels[row[0]] = (row[1], row[2], row[3], row[4])
                self.vehicles.add(row[1])
        new_wheels: dict[str, dict[str, Any]] = {}
        for record in records:
            meta = record.meta
            position = (meta.vehicle_id, meta.bogie_type, int(meta.axle), meta.side)
            known = self.wheels.get(meta.wheel_id)
            if known is None:
                self.wheels[meta.wheel_id] = position
                new_wheels[meta.wheel_id] = {
                    "wheel_id": meta.wheel_id, "vehicle_id": meta.vehicle_id,
                    "bogie_type": meta.bogie_type, "axle": int(meta.axle), "side": meta.side}
                continue
            for name, have, got in zip(("vehicle_id", "bogie_type", "axle", "side"), known,
                                       position, strict=True):
                if have != got:
                    raise ImportFileError(
                        meta.source_file, f"wheel {meta.wheel_id!r} is stored with {name} "
                        f"{have!r}, this measurement says {got!r}",
                        line=meta.source_line, field=name)
        if not new_wheels:
            return
        if self.defer_writes:
            self.new_wheels.update(new_wheels)
            return
        vehicles = {w["vehicle_id"] for w in new_wheels.values()} - self.vehicles
        if vehicles:
            stored = set(self.session.scalars(
                select(db.Vehicle.vehicle_id).where(db.Vehicle.vehicle_id.in_(vehicles))))
            fresh = sorted(vehicles - stored)
            if fresh:
                self.session.execute(insert(db.Vehicle), [{"vehicle_id": v} for v in fresh])
            self.vehicles |= vehicles
        self.session.execute(insert(db.Wheel), list(new_wheels.values()))


#: What the measurements row keeps of a processed profile.
_Processed = Processed


def ref_tuple(spec: ReferenceSpec | None) -> RefTuple | None:
    """A resolved reference as the plain tuple the processing (and its workers) take."""
    return None if spec is None else (spec.name, spec.kind, spec.y_mm, spec.z_mm)


def _process_arrays(y_mm: np.ndarray, z_mm: np.ndarray, spec: ReferenceSpec | None = None,
                    datum: bool = False) -> Processed | str:
    """The processed profile, or the reason it cannot be used (see
    :func:`wearcast.service.import_worker.process_arrays`); ``spec`` is the declared
    reference (default S1002)."""
    return process_arrays(y_mm, z_mm, ref_tuple(spec), datum)


_POOL: ProcessPoolExecutor | None = None
_POOL_WORKERS = 0
_POOL_LOCK = threading.Lock()


def _pool() -> ProcessPoolExecutor | None:
    """A process pool of one worker per core (spawned once, on the first large chunk).

    ``spawn`` rather than ``fork``: the service runs threads, and forking a threaded process
    can inherit held locks. None on a single core or when ``WEARCAST_IMPORT_WORKERS=0``.
    """
    global _POOL, _POOL_WORKERS
    configured = os.environ.get("WEARCAST_IMPORT_WORKERS", "").strip()  # empty: unset
    workers = int(configured) if configured else (os.cpu_count() or 1)
    if workers <= 1:
        return None
    with _POOL_LOCK:
        if _POOL is None:
            _POOL = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"))
            _POOL_WORKERS = workers
        return _POOL


def _discard_pool() -> None:
    global _POOL
    with _POOL_LOCK:
        if _POOL is not None:
            _POOL.shutdown(wait=False, cancel_futures=True)
        _POOL = None


def _submit(records: list[ProfileRecord], registry: _Registry | None = None
            ) -> Callable[[], list[_Processed]]:
    """Start processing a chunk's profiles; the returned callable waits for the results.

    Large chunks go to the worker pool, so the caller can parse and insert meanwhile; a pool
    that cannot run (e.g. a script without a ``__main__`` guard under ``spawn``) falls back to
    processing in this process. The callable raises the ImportFileError of the first unusable
    profile, naming its file and line.
    """
    specs = [registry.reference(r) if registry is not None else None for r in records]
    arrays = [(r.y_mm, r.z_mm, ref_tuple(spec), r.instrument_datum)
              for r, spec in zip(records, specs, strict=True)]
    pool = _pool() if len(records) >= PARALLEL_MIN_PROFILES else None
    futures = []
    if pool is not None:
        size = -(-len(arrays) // (_POOL_WORKERS * 2))
        try:
            futures = [pool.submit(process_batch, arrays[i:i + size])
                       for i in range(0, len(arrays), size)]
        except (BrokenProcessPool, RuntimeError):
            _discard_pool()
            futures = []

    def results() -> list[_Processed]:
        try:
            done = [r for f in futures for r in f.result()] if futures else None
        except BrokenProcessPool:
            _discard_pool()
            done = None
        if done is None:
            done = process_batch(arrays)
        for record, result in zip(records, done, strict=True):
            if isinstance(result, str):
                meta = record.meta
                raise ImportFileError(meta.source_file, f"profile of wheel {meta.wheel_id!r} "
                                      f"at {meta.mileage_km:g} km cannot be used: {result}",
                                      line=meta.source_line, field="z_mm")
        return done  # type: ignore[return-value]

    return results


def measurement_row(record: Record, batch_id: int | None, registry: _Registry,
                    processed: _Processed | None = None) -> dict[str, Any]:
    """The ``measurements`` row of one record.

    ``processed`` is the profile's (processed profile, measured Sd/Sh/qR) when already
    computed (see :func:`_submit`); otherwise it is computed here.
    """
    meta = record.meta
    row: dict[str, Any] = {
        "batch_id": batch_id, "wheel_id": meta.wheel_id, "mileage_km": float(meta.mileage_km),
        "measured_on": meta.measured_on, "route_id": registry.route_name(meta.route_id),
        "running_mode": meta.running_mode, "instrument_id": meta.instrument_id,
        "load_t": meta.load_t, "reference_profile": meta.reference_profile,
        "diameter_mm": meta.diameter_mm,
        "covariates": dict(meta.covariates), "source_file": meta.source_file or None,
        "source_line": meta.source_line,
    }
    empty = dict.fromkeys(
        ("y_mm", "z_mm", "wear_mm", "wear_grid_start_mm", "wear_grid_step_mm",
         "flange_area_mm2", "tread_area_mm2", "lateral_shift_mm", "vertical_shift_mm",
         "rotation_rad", "rms_residual_mm", "instrument_parameters", "reported_sd_mm",
         "reported_sh_mm", "reported_qr_mm"))
    row.update(empty)
    if isinstance(record, ParameterRecord):
        row.update(kind="parameters", n_points=0, sd_mm=float(record.sd_mm),
                   sh_mm=float(record.sh_mm), qr_mm=float(record.qr_mm),
                   reported_sd_mm=float(record.sd_mm), reported_sh_mm=float(record.sh_mm),
                   reported_qr_mm=float(record.qr_mm))
        return row
    p = processed if processed is not None else _submit([record], registry)()[0]
    reported = record.instrument_parameters or {}
    row.update(
        kind="profile", n_points=int(len(record.y_mm)), y_mm=f32(record.y_mm),
        z_mm=f32(record.z_mm), **_wear_columns(p),
        sd_mm=_finite_or_none(p.sd_mm), sh_mm=_finite_or_none(p.sh_mm),
        qr_mm=_finite_or_none(p.qr_mm),
        lateral_shift_mm=p.lateral_shift_mm, vertical_shift_mm=p.vertical_shift_mm,
        rotation_rad=p.rotation_rad, rms_residual_mm=p.rms_residual_mm,
        instrument_parameters=dict(reported) or None,
        reported_sd_mm=_finite_or_none(reported.get("sd_mm")),
        reported_sh_mm=_finite_or_none(reported.get("sh_mm")),
        reported_qr_mm=_finite_or_none(reported.get("qr_mm")),
        placement=p.placement,
        warnings=measurement_warnings(record, p) or None,
    )
    return row


def _wear_columns(p: _Processed) -> dict[str, Any]:
    """Wear curve, areas and reference fit of a processed profile; a shape that does not
    fit its reference keeps no wear curve or areas (excluded from wear statistics)."""
    fits = bool(p.reference_fits)
    return {
        "wear_mm": f32(p.wear_mm) if fits else None,
        "wear_grid_start_mm": p.grid_start_mm, "wear_grid_step_mm": p.grid_step_mm,
        "flange_area_mm2": _finite_or_none(p.flange_area_mm2) if fits else None,
        "tread_area_mm2": _finite_or_none(p.tread_area_mm2) if fits else None,
        "reference_profile": p.reference, "reference_fits": fits,
    }


def _warning(code: str, level: str, message: str) -> dict[str, Any]:
    return {"code": code, "level": level, "message": message}


def _datum_header_notes(header: dict[str, str] | None) -> list[str]:
    """What the file's own datum entries say (MiniProf ``Xoffset``/``Yoffset``, reference
    points): the exported points already carry the offsets the instrument software applied,
    so they are reported, not applied again."""
    if not header:
        return ["the file carries no datum offsets or reference points"]
    out = []
    offsets = {k: header[k] for k in ("Xoffset", "Yoffset") if k in header}
    if offsets:
        try:
            nonzero = {k: float(v) for k, v in offsets.items() if float(v) != 0.0}
        except ValueError:
            nonzero = {}
            out.append(f"unreadable datum offsets {offsets}")
        if nonzero:
            out.append("the file's datum offsets " + ", ".join(f"{k} = {v:g} mm" for k, v in
                                                                nonzero.items())
                       + " are taken as already applied to the exported points (check)")
        else:
            out.append("the file's datum offsets Xoffset/Yoffset are 0")
    refs = sorted(k for k in header if k.startswith("RefPoint"))
    if refs:
        out.append(f"{len(refs)} instrument reference points in the header "
                   f"({refs[0]} = {header[refs[0]]})")
    return out


def measurement_warnings(record: ProfileRecord, p: _Processed) -> list[dict[str, Any]]:
    """What the import had to find, guess or drop for one profile (see module docstring)."""
    out: list[dict[str, Any]] = []
    header = record.header_parameters
    if header is not None:
        recomputed = {"sd_mm": p.sd_mm, "sh_mm": p.sh_mm, "qr_mm": p.qr_mm}
        diffs = {k: float(header[k]) - v for k, v in recomputed.items() if math.isfinite(v)}
        if any(abs(d) > HEADER_TOLERANCE_MM for d in diffs.values()):
            what = ("the old-style template's placeholders" if header.get("placeholder")
                    else "the instrument's values")
            out.append(_warning("header_parameters", "warning", (
                f"header Sd/Sh/qR {float(header['sd_mm']):.2f}/{float(header['sh_mm']):.2f}/"
                f"{float(header['qr_mm']):.2f} mm ({what}) disagree with the points' "
                f"{p.sd_mm:.2f}/{p.sh_mm:.2f}/{p.qr_mm:.2f} mm by "
                + "/".join(f"{diffs.get(k, float('nan')):+.2f}" for k in recomputed)
                + f" mm (tolerance {HEADER_TOLERANCE_MM:g} mm); the points' values are stored")))
    if not p.reference_fits:
        out.append(_warning("reference_mismatch", "warning", (
            f"shape does not fit the declared reference {p.reference}: "
            + "; ".join(p.reference_reasons) + ". Stored and flagged; wear areas and wear "
            "curve are kept out of statistics until a reference is given "
            "(PUT /v1/wheels/{wheel_id}/reference)")))
    placement = p.placement or {}
    if placement.get("alignment") == "datum":
        found = placement.get("back_face_found")
        notes = list(placement.get("notes") or [])
        notes += _datum_header_notes(record.datum_header)
        out.append(_warning("datum_found" if found else "datum_guessed",
                            "info" if found else "warning", "; ".join(notes)))
        out.append(_warning("wear_alignment", "info", (
            f"wear taken against {p.reference} after a vertical shift of "
            f"{p.vertical_shift_mm:+.2f} mm on the unworn flange back (lateral shift "
            f"{p.lateral_shift_mm:.2f} mm, rotation {p.rotation_rad * 1e3:.2f} mrad, RMS "
            f"{p.rms_residual_mm:.2f} mm); the stored points are not moved")))
    if p.n_removed:
        out.append(_warning("points_dropped", "info", (
            f"cleaning dropped {p.n_removed} of {p.n_raw} points: "
            + "; ".join(p.cleaning_notes))))
    return out


@dataclass
class _Counts:
    records: int = 0
    created: int = 0
    duplicates: int = 0
    points: int = 0
    warnings: list[dict[str, Any]] = field(default_factory=list)
    infos: list[dict[str, Any]] = field(default_factory=list)
    warnings_total: int = 0

    def listed(self) -> tuple[dict[str, Any], ...]:
        """Warnings for the answer: level ``warning`` first, then ``info``, at most
        ``MAX_WARNINGS``."""
        return tuple((self.warnings + self.infos)[:MAX_WARNINGS])


def collect_warnings(counts: _Counts, registry: _Registry, records: list[Record],
                     rows: list[dict[str, Any]]) -> None:
    """Count the rows' warnings into ``counts`` (the answer lists warnings before infos, each
    in file order, up to ``MAX_WARNINGS``) and note the wheels whose baseline is their own
    first measurement."""
    for record, row in zip(records, rows, strict=True):
        if is_own_baseline(record.meta.reference_profile):
            registry.own_wheels.add(record.meta.wheel_id)
        for warning in row.get("warnings") or ():
            counts.warnings_total += 1
            kept = counts.warnings if warning["level"] == "warning" else counts.infos
            if len(kept) < MAX_WARNINGS:
                line = (record.manifest_line if isinstance(record, ProfileRecord)
                        and record.manifest_line is not None else record.meta.source_line)
                kept.append({"file": record.meta.source_file or None, "line": line,
                             "wheel_id": record.meta.wheel_id,
                             "mileage_km": record.meta.mileage_km, **warning})


def store_records(session: Session, records: Iterable[Record], batch_id: int | None, *,
                  chunk_size: int = DEFAULT_CHUNK, progress: Progress | None = None,
                  ) -> tuple[_Counts, list[int]]:
    """Insert the records (chunked bulk inserts) inside the session's open transaction.

    Returns the counts and, when ``batch_id`` is None, the new measurement ids (single posts).
    Duplicates of stored measurements or of earlier records in ``records`` are skipped.
    """
    registry = _Registry(session)
    counts = _Counts()
    seen: set[tuple[str, float]] = set()
    new_ids: list[int] = []
    iterator: Iterator[Record] = iter(records)

    def insert_rows(fresh: list[Record], processed: Callable[[], list[_Processed]]) -> None:
        if not fresh:
            return
        profiles = [r for r in fresh if isinstance(r, ProfileRecord)]
        done = dict(zip(map(id, profiles), processed(), strict=True))
        rows = [measurement_row(r, batch_id, registry, done.get(id(r))) for r in fresh]
        collect_warnings(counts, registry, fresh, rows)
        counts.points += sum(r["n_points"] for r in rows)
        if batch_id is None:
            for row in rows:
                new_ids.append(session.execute(
                    insert(db.Measurement).returning(db.Measurement.id), [row]).scalar_one())
        else:
            session.execute(insert(db.Measurement), rows)
        counts.created += len(rows)

    # A chunk's profiles are processed (in worker processes when large) while the next chunk
    # is parsed and checked for duplicates; its rows are inserted after that.
    pending: tuple[list[Record], Callable[[], list[_Processed]], int] | None = None
    while chunk := list(islice(iterator, chunk_size)):
        counts.records += len(chunk)
        keys = [(r.meta.wheel_id, float(r.meta.mileage_km)) for r in chunk]
        stored = {tuple(row) for row in session.execute(
            select(db.Measurement.wheel_id, db.Measurement.mileage_km).where(
                tuple_(db.Measurement.wheel_id, db.Measurement.mileage_km).in_(set(keys)))
        ).all()}
        fresh: list[Record] = []
        for record, key in zip(chunk, keys, strict=True):
            if key in stored or key in seen:
                counts.duplicates += 1
                continue
            seen.add(key)
            fresh.append(record)
        if fresh:
            registry.ensure_wheels(fresh)
        handle = _submit([r for r in fresh if isinstance(r, ProfileRecord)], registry)
        if pending is not None:
            insert_rows(pending[0], pending[1])
            if progress is not None:
                progress(pending[2])
        pending = (fresh, handle, len(chunk))
    if pending is not None:
        insert_rows(pending[0], pending[1])
        if progress is not None:
            progress(pending[2])
    for wheel_id in sorted(registry.own_wheels):
        session.flush()
        apply_reference(session, wheel_id, OWN_BASELINE, commit=False)
    return counts, new_ids


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


def _duplicate(session: Session, batch: db.ImportBatch) -> ImportResult:
    """The answer to a repeated import: nothing created, the first import's warnings."""
    counts = _Counts()
    for source, line, wheel, mileage, stored in session.execute(
            select(db.Measurement.source_file, db.Measurement.source_line,
                   db.Measurement.wheel_id, db.Measurement.mileage_km,
                   db.Measurement.warnings)
            .where(db.Measurement.batch_id == batch.id).order_by(db.Measurement.id)):
        for warning in stored or ():
            counts.warnings_total += 1
            kept = counts.warnings if warning.get("level") == "warning" else counts.infos
            if len(kept) < MAX_WARNINGS:
                kept.append({"file": source, "line": line, "wheel_id": wheel,
                             "mileage_km": mileage, **warning})
    return ImportResult(batch_id=batch.id, duplicate=True, file_name=batch.file_name,
                        records=batch.n_records, created=0, duplicates=batch.n_records,
                        points=0, warnings=counts.listed(),
                        warnings_total=counts.warnings_total)


def iter_records(stream: BinaryIO, file_name: str, manifest: bytes | None,
                 manifest_name: str | None) -> Iterator[Record]:
    """The records of an upload, from the readers (streamed)."""
    from wearcast.service.readers.bundle import iter_upload

    yield from iter_upload(stream, file_name, manifest=manifest)


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
    from wearcast.service.import_staging import stage_records, write_stage

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
            return _duplicate(session, found)
        done_batch = idempotency.claim(session, idempotency_key, checksum)
        if done_batch is not None:
            batch_row = session.get(db.ImportBatch, done_batch)
            if batch_row is not None:
                return _duplicate(session, batch_row)
    try:
        result = _import_claimed(session, raw_dir, stream, file_name, file_sha, checksum,
                                 manifest, manifest_name, idempotency_key, chunk_size,
                                 progress, settings, stage_records, write_stage)
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
                    progress: Progress | None, settings: Any, stage_records: Any,
                    write_stage: Any) -> ImportResult:
    found = _existing_batch(session, checksum=checksum)
    if found is not None:
        return _duplicate(session, found)
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
            return _duplicate(session, found)
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


def apply_reference(session: Session, wheel_id: str, name: str, *, commit: bool = True
                    ) -> dict[str, Any]:
    """Re-take every profile measurement of a wheel against the reference ``name`` (a
    catalogue name, an uploaded reference, or ``own`` for the wheel's first measurement):
    wear curve, areas, reference fit and warnings are recomputed; the points are not
    touched. Returns a summary per measurement."""
    if session.get(db.Wheel, wheel_id) is None:
        raise NotFound("wheel_id", f"wheel {wheel_id!r} is not stored")
    if is_own_baseline(name):
        found = own_baseline_spec(session, wheel_id)
        if found is None:
            raise Unprocessable("reference_profile", f"wheel {wheel_id!r} has no profile "
                                "measurement to serve as its own baseline")
        spec, baseline_id = found
        stored_name = f"own:{baseline_id}"
    else:
        spec = resolve_reference(session, name)
        stored_name = spec.name
    rows = session.scalars(select(db.Measurement).where(
        db.Measurement.wheel_id == wheel_id, db.Measurement.kind == "profile")
        .order_by(db.Measurement.mileage_km)).all()
    out = []
    for m in rows:
        y, z = from_f32(m.y_mm), from_f32(m.z_mm)
        datum = bool((m.placement or {}).get("alignment") == "datum")
        p = _process_arrays(np.asarray(y), np.asarray(z), spec, datum)
        if isinstance(p, str):
            raise Unprocessable("reference_profile", f"measurement {m.id} cannot be taken "
                                f"against {stored_name}: {p}")
        p = p._replace(reference=stored_name)
        for key, value in _wear_columns(p).items():
            setattr(m, key, value)
        m.lateral_shift_mm, m.vertical_shift_mm = p.lateral_shift_mm, p.vertical_shift_mm
        m.rotation_rad, m.rms_residual_mm = p.rotation_rad, p.rms_residual_mm
        m.placement = p.placement
        # what the import found in the file (header, datum, cleaning) stays; the reference
        # fit and the wear alignment are taken anew
        redone = ("reference_mismatch", "wear_alignment")
        kept = [w for w in (m.warnings or []) if w.get("code") not in redone]
        record = ProfileRecord(meta=_meta_stub(m), y_mm=np.asarray(y), z_mm=np.asarray(z))
        m.warnings = kept + [w for w in measurement_warnings(record, p)
                             if w["code"] in redone] or None
        out.append({"measurement_id": m.id, "mileage_km": m.mileage_km,
                    "reference_profile": stored_name, "reference_fits": m.reference_fits,
                    "flange_area_mm2": m.flange_area_mm2, "tread_area_mm2": m.tread_area_mm2,
                    "warnings": m.warnings or []})
    if commit:
        session.commit()
    return {"wheel_id": wheel_id, "reference_profile": stored_name, "measurements": out}


def _meta_stub(m: db.Measurement) -> Any:
    from wearcast.service.readers.records import MeasurementMeta

    wheel = m.wheel_id
    return MeasurementMeta(wheel_id=wheel, vehicle_id="", bogie_type="motor", axle=1,
                           side="left", mileage_km=m.mileage_km,
                           reference_profile=m.reference_profile)
