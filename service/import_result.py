"""The answer of an import: what it created and skipped, and the warnings it lists.

:class:`ImportResult` is what :func:`wearcast.service.importing.import_upload` returns (and the
HTTP import answer carries). While the records are stored, :class:`ImportCounts` counts them and
keeps the warnings to list: level ``warning`` before ``info``, each in file order, at most
:data:`MAX_WARNINGS` (every warning stays stored with its measurement). A repeated import
answers with the first import's batch and warnings (:func:`duplicate_result`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.import_registry import ImportRegistry
from wearcast.service.readers.bundle import Record
from wearcast.service.readers.records import ProfileRecord
from wearcast.service.reference_store import is_own_baseline

#: At most this many warnings are listed in an import answer (all are stored).
MAX_WARNINGS = 1000


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


@dataclass
class ImportCounts:
    """Records read, measurements created, duplicates skipped, points stored, and the warnings
    to list (``warnings`` of level warning, ``infos`` of level info; ``warnings_total`` all)."""

    records: int = 0
    created: int = 0
    duplicates: int = 0
    points: int = 0
    warnings: list[dict[str, Any]] = field(default_factory=list)
    infos: list[dict[str, Any]] = field(default_factory=list)
    warnings_total: int = 0

    def add_warning(self, warning: dict[str, Any], file: str | None, line: int | None,
                    wheel_id: str, mileage_km: float) -> None:
        """Count one warning of a measurement; keep it for the answer while there is room."""
        self.warnings_total += 1
        kept = self.warnings if warning.get("level") == "warning" else self.infos
        if len(kept) < MAX_WARNINGS:
            kept.append({"file": file, "line": line, "wheel_id": wheel_id,
                         "mileage_km": mileage_km, **warning})

    def listed(self) -> tuple[dict[str, Any], ...]:
        """Warnings for the answer: level ``warning`` first, then ``info``, at most
        ``MAX_WARNINGS``."""
        return tuple((self.warnings + self.infos)[:MAX_WARNINGS])


def collect_warnings(counts: ImportCounts, registry: ImportRegistry, records: list[Record],
                     rows: list[dict[str, Any]]) -> None:
    """Count the rows' warnings into ``counts`` (the answer lists warnings before infos, each
    in file order, up to ``MAX_WARNINGS``) and note the wheels whose baseline is their own
    first measurement."""
    for record, row in zip(records, rows, strict=True):
        if is_own_baseline(record.meta.reference_profile):
            registry.own_wheels.add(record.meta.wheel_id)
        line = (record.manifest_line if isinstance(record, ProfileRecord)
                and record.manifest_line is not None else record.meta.source_line)
        for warning in row.get("warnings") or ():
            counts.add_warning(warning, record.meta.source_file or None, line,
                               record.meta.wheel_id, record.meta.mileage_km)


def duplicate_result(session: Session, batch: db.ImportBatch) -> ImportResult:
    """The answer to a repeated import: nothing created, the first import's warnings."""
    counts = ImportCounts()
    for source, line, wheel, mileage, stored in session.execute(
            select(db.Measurement.source_file, db.Measurement.source_line,
                   db.Measurement.wheel_id, db.Measurement.mileage_km,
                   db.Measurement.warnings)
            .where(db.Measurement.batch_id == batch.id).order_by(db.Measurement.id)):
        for warning in stored or ():
            counts.add_warning(warning, source, line, wheel, mileage)
    return ImportResult(batch_id=batch.id, duplicate=True, file_name=batch.file_name,
                        records=batch.n_records, created=0, duplicates=batch.n_records,
                        points=0, warnings=counts.listed(),
                        warnings_total=counts.warnings_total)
