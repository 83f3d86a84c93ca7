"""Storage schema (SQLAlchemy 2 declarative tables).

The schema is created only by the Alembic migrations (``wearcast.migrations``); this module is
the metadata they are checked against. Profile points and wear curves are stored as compact
little-endian float32 blobs (``ndarray.astype('<f4').tobytes()``); the wear curve is sampled on
the grid named by ``wear_grid_start_mm``/``wear_grid_step_mm`` and the blob's length.
Instrument-reported Sd/Sh/qR are kept beside the ones recomputed from the points; the
recomputed ones are taken on the cleaned profile in the instrument's own (back-face
referenced) frame, as the instrument does, not on the profile aligned to the reference.
"""

from __future__ import annotations

import datetime as dt
from typing import Any

from sqlalchemy import (
    JSON,
    BigInteger,
    Boolean,
    Date,
    DateTime,
    Float,
    ForeignKey,
    Index,
    Integer,
    LargeBinary,
    MetaData,
    String,
    Text,
    UniqueConstraint,
    false,
    func,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

NAMING_CONVENTION = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}


#: Row ids (and columns holding them): 64-bit, the range the OpenAPI publishes for every id.
#: SQLite's INTEGER is 64-bit already (and an INTEGER PRIMARY KEY must stay spelled so to be
#: the rowid); PostgreSQL's INTEGER is 32-bit, so there an id is a BIGINT (migration 0008).
IdInteger = Integer().with_variant(BigInteger(), "postgresql")


class Base(DeclarativeBase):
    metadata = MetaData(naming_convention=NAMING_CONVENTION)
    type_annotation_map = {dict[str, Any]: JSON, list[Any]: JSON}


class ImportBatch(Base):
    """One upload: its checksum (content of file + manifest) and idempotency key are unique."""

    __tablename__ = "import_batches"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    checksum_sha256: Mapped[str] = mapped_column(String(64), unique=True)
    idempotency_key: Mapped[str | None] = mapped_column(String(200), unique=True)
    file_name: Mapped[str] = mapped_column(String(500))
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())
    n_records: Mapped[int] = mapped_column(Integer, default=0)
    n_created: Mapped[int] = mapped_column(Integer, default=0)
    n_duplicates: Mapped[int] = mapped_column(Integer, default=0)
    n_points: Mapped[int] = mapped_column(Integer, default=0)
    #: ``pending`` while its import inserts the measurements chunk by chunk (each chunk its
    #: own short transaction; the measurements of a batch that is not ``complete`` are
    #: invisible to every read, :mod:`wearcast.service.batch_visibility`), ``complete`` once
    #: the import has flipped it in one last short transaction, ``discarding`` while a failed
    #: or abandoned one is removed (:mod:`wearcast.service.pending_batches`).
    status: Mapped[str] = mapped_column(String(20), default="complete",
                                        server_default="complete", index=True)
    #: When the import of a pending batch last wrote (a batch silent for
    #: ``pending_batches.STALE_S`` belongs to a dead process and is removed).
    heartbeat_at: Mapped[dt.datetime | None] = mapped_column(DateTime(timezone=True))


class RawFile(Base):
    """An uploaded file, kept on disk under ``<data_dir>/raw/<sha[:2]>/<sha>``."""

    __tablename__ = "raw_files"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    batch_id: Mapped[int] = mapped_column(ForeignKey("import_batches.id", ondelete="CASCADE"),
                                          index=True)
    role: Mapped[str] = mapped_column(String(20))  # "file" or "manifest"
    name: Mapped[str] = mapped_column(String(500))
    sha256: Mapped[str] = mapped_column(String(64), index=True)
    size_bytes: Mapped[int] = mapped_column(Integer)
    storage_path: Mapped[str] = mapped_column(String(200))


class Vehicle(Base):
    """A vehicle; ``fleet_id`` and ``km_per_day`` (its mileage per day) are planning
    attributes, both optional."""

    __tablename__ = "vehicles"
    vehicle_id: Mapped[str] = mapped_column(String(200), primary_key=True)
    fleet_id: Mapped[str | None] = mapped_column(String(200), index=True)
    km_per_day: Mapped[float | None] = mapped_column(Float)
    #: The import batch that registered it: hidden while that batch is not complete
    #: (``service/batch_visibility.py``); None once seen by a complete batch. No foreign key:
    #: the batch may be discarded while another import's measurements keep the row.
    registered_batch_id: Mapped[int | None] = mapped_column(IdInteger, index=True)


class Fleet(Base):
    """A fleet's maintenance limits (overrides of the defaults, JSON) for planning."""

    __tablename__ = "fleets"
    fleet_id: Mapped[str] = mapped_column(String(200), primary_key=True)
    limits: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())


class Plan(Base):
    """A lathe plan: its request (``spec``) and the computed plan (``result``)."""

    __tablename__ = "plans"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    fleet_id: Mapped[str | None] = mapped_column(String(200), index=True)
    spec: Mapped[dict[str, Any]] = mapped_column(JSON)
    result: Mapped[dict[str, Any]] = mapped_column(JSON, deferred=True)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())


class Wheel(Base):
    """A wheel and its fixed position: vehicle, bogie type, axle (1|2), side."""

    __tablename__ = "wheels"
    wheel_id: Mapped[str] = mapped_column(String(200), primary_key=True)
    vehicle_id: Mapped[str] = mapped_column(ForeignKey("vehicles.vehicle_id"), index=True)
    bogie_type: Mapped[str] = mapped_column(String(20))
    axle: Mapped[int] = mapped_column(Integer)
    side: Mapped[str] = mapped_column(String(10))
    #: As :attr:`Vehicle.registered_batch_id`.
    registered_batch_id: Mapped[int | None] = mapped_column(IdInteger, index=True)


class Measurement(Base):
    """One measured wheel profile (or parameter-only record) at a mileage."""

    __tablename__ = "measurements"
    __table_args__ = (UniqueConstraint("wheel_id", "mileage_km",
                                       name="uq_measurements_wheel_id_mileage_km"),)
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    batch_id: Mapped[int | None] = mapped_column(ForeignKey("import_batches.id"), index=True)
    wheel_id: Mapped[str] = mapped_column(ForeignKey("wheels.wheel_id"), index=True)
    mileage_km: Mapped[float] = mapped_column(Float)
    kind: Mapped[str] = mapped_column(String(20))  # "profile" or "parameters"
    measured_on: Mapped[dt.date | None] = mapped_column(Date)
    route_id: Mapped[str | None] = mapped_column(String(200), index=True)
    running_mode: Mapped[str | None] = mapped_column(String(20))
    instrument_id: Mapped[str | None] = mapped_column(String(200))
    load_t: Mapped[float | None] = mapped_column(Float)
    diameter_mm: Mapped[float | None] = mapped_column(Float)  # measured tape-circle diameter
    reference_profile: Mapped[str] = mapped_column(String(100), default="S1002")
    covariates: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict)
    source_file: Mapped[str | None] = mapped_column(String(500))
    source_line: Mapped[int | None] = mapped_column(Integer)
    instrument_parameters: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    n_points: Mapped[int] = mapped_column(Integer, default=0)
    y_mm: Mapped[bytes | None] = mapped_column(LargeBinary)
    z_mm: Mapped[bytes | None] = mapped_column(LargeBinary)
    wear_mm: Mapped[bytes | None] = mapped_column(LargeBinary)
    wear_grid_start_mm: Mapped[float | None] = mapped_column(Float)
    wear_grid_step_mm: Mapped[float | None] = mapped_column(Float)
    flange_area_mm2: Mapped[float | None] = mapped_column(Float)
    tread_area_mm2: Mapped[float | None] = mapped_column(Float)
    sd_mm: Mapped[float | None] = mapped_column(Float)
    sh_mm: Mapped[float | None] = mapped_column(Float)
    qr_mm: Mapped[float | None] = mapped_column(Float)
    reported_sd_mm: Mapped[float | None] = mapped_column(Float)
    reported_sh_mm: Mapped[float | None] = mapped_column(Float)
    reported_qr_mm: Mapped[float | None] = mapped_column(Float)
    lateral_shift_mm: Mapped[float | None] = mapped_column(Float)
    vertical_shift_mm: Mapped[float | None] = mapped_column(Float)
    rotation_rad: Mapped[float | None] = mapped_column(Float)
    rms_residual_mm: Mapped[float | None] = mapped_column(Float)
    #: False when the shape does not fit ``reference_profile`` (wear areas then stay NULL).
    reference_fits: Mapped[bool | None] = mapped_column(Boolean)
    #: How the points were placed: datum found/guessed, tilt, alignment kind.
    placement: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    #: Import warnings of this measurement: [{"code", "message"}].
    warnings: Mapped[list[Any] | None] = mapped_column(JSON)


class Route(Base):
    """A route as curve classes (shares sum to 1) with free attributes."""

    __tablename__ = "routes"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), unique=True)
    classes: Mapped[list[Any]] = mapped_column(JSON)
    segments: Mapped[list[Any] | None] = mapped_column(JSON)
    attributes: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())


class WearTable(Base):
    """A curve-radius table of wear measures (uploaded or computed).

    ``kind`` is ``uploaded`` or ``computed``; a computed table keeps its request (``spec``)
    and the raw per-contact quantities behind it (``contacts``: pandas ``split`` orient,
    ``{"columns": [...], "data": [[...], ...]}``; loaded only when asked for). ``sha256`` is
    the hash of the table's content (the uploaded bytes, or the canonical CSV of a computed
    table), the key of the compiled-table cache.
    """

    __tablename__ = "wear_tables"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    name: Mapped[str] = mapped_column(String(200))
    source: Mapped[str] = mapped_column(String(500))
    sha256: Mapped[str] = mapped_column(String(64))
    n_rows: Mapped[int] = mapped_column(Integer)
    kind: Mapped[str] = mapped_column(String(20), default="uploaded",
                                      server_default="uploaded")
    spec: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    contacts: Mapped[dict[str, Any] | None] = mapped_column(JSON, deferred=True)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())


class WearTableRow(Base):
    __tablename__ = "wear_table_rows"
    __table_args__ = (Index("ix_wear_table_rows_table", "wear_table_id"),)
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    wear_table_id: Mapped[int] = mapped_column(ForeignKey("wear_tables.id", ondelete="CASCADE"))
    bogie_type: Mapped[str] = mapped_column(String(20))
    wheelset: Mapped[str] = mapped_column(String(20))
    rail: Mapped[str] = mapped_column(String(20))
    radius_m: Mapped[float | None] = mapped_column(Float)
    region: Mapped[str] = mapped_column(String(20))
    measure: Mapped[str] = mapped_column(String(20))
    value: Mapped[float] = mapped_column(Float)


class Model(Base):
    """A calibrated model: the request (spec) and the fitted state.

    ``kind`` is the model family (migration 0007): ``hybrid`` (seed 001's statistical model,
    also when the discrepancy finder extended it; ``state["kind"] == "extended"`` then) or
    ``physics`` (the whole-vehicle wear loop with a calibrated wear-coefficient scale;
    ``service.physics_model_store``), which has no wear table, measure or running mode.
    """

    __tablename__ = "models"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    name: Mapped[str] = mapped_column(String(200))
    kind: Mapped[str] = mapped_column(String(20), default="hybrid", server_default="hybrid")
    measure: Mapped[str | None] = mapped_column(String(20))
    running_mode: Mapped[str | None] = mapped_column(String(20))
    wear_table_id: Mapped[int | None] = mapped_column(ForeignKey("wear_tables.id"))
    route_id: Mapped[int] = mapped_column(ForeignKey("routes.id"))
    spec: Mapped[dict[str, Any]] = mapped_column(JSON)
    state: Mapped[dict[str, Any]] = mapped_column(JSON)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())


class ModelCalibrationMeasurement(Base):
    """Which measurements a model was calibrated on."""

    __tablename__ = "model_calibration_measurements"
    model_id: Mapped[int] = mapped_column(ForeignKey("models.id", ondelete="CASCADE"),
                                          primary_key=True)
    measurement_id: Mapped[int] = mapped_column(ForeignKey("measurements.id"), primary_key=True)


class Simulation(Base):
    """A wear-loop simulation job: its request, status, progress (0-1), error and result.

    ``status`` is ``queued``, ``running``, ``done``, ``failed`` or ``cancelled``; ``result`` is
    ``WearSimulation.to_dict()`` once done (loaded only when asked for).
    """

    __tablename__ = "simulations"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    name: Mapped[str | None] = mapped_column(String(200))
    spec: Mapped[dict[str, Any]] = mapped_column(JSON)
    status: Mapped[str] = mapped_column(String(20), index=True)
    progress: Mapped[float] = mapped_column(Float, default=0.0)
    message: Mapped[str | None] = mapped_column(String(500))
    error: Mapped[str | None] = mapped_column(Text)
    result: Mapped[dict[str, Any] | None] = mapped_column(JSON, deferred=True)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())
    started_at: Mapped[dt.datetime | None] = mapped_column(DateTime(timezone=True))
    finished_at: Mapped[dt.datetime | None] = mapped_column(DateTime(timezone=True))
    # job control (migration 0003_service): who owns it, a cancel request, its time limit,
    # and the last sign of life of the worker running it
    owner_key_id: Mapped[int | None] = mapped_column(IdInteger, index=True)
    cancel_requested: Mapped[bool] = mapped_column(Boolean, default=False,
                                                   server_default=false())
    timeout_s: Mapped[float | None] = mapped_column(Float)
    heartbeat_at: Mapped[dt.datetime | None] = mapped_column(DateTime(timezone=True))
    attempts: Mapped[int] = mapped_column(Integer, default=0, server_default="0")



class Rail(Base):
    """A measured rail head (or a rig roller standing in for a rail), points AS IN THE FILE.

    ``x_mm``/``y_mm`` the instrument's X, Y (little-endian float64 blobs, file order, every
    point, also those a note says were added: ``added_points`` lists their indices);
    ``gauge_side`` (``negative_x``/``positive_x``) and ``y_down`` say how they turn into the
    rail frame (mirror / sign only). One row per file content and part (``part`` 0 for
    single-profile files): a repeated import finds it. ``reference`` is the head the wear
    measures are taken against by default (``60E1``, ``UIC60``, ``60E2`` or ``rail:<id>``);
    ``inclination`` the stated laying inclination (None: the vehicle's); ``raw_path`` the
    uploaded file under ``<data_dir>/raw`` (content-addressed, as measurement imports).
    """

    __tablename__ = "rails"
    __table_args__ = (UniqueConstraint("sha256", "part", name="uq_rails_sha256_part"),)
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    name: Mapped[str] = mapped_column(String(200))
    source_file: Mapped[str] = mapped_column(String(500))
    part: Mapped[int] = mapped_column(Integer, default=0)
    sha256: Mapped[str] = mapped_column(String(64), index=True)
    kind: Mapped[str] = mapped_column(String(20))
    layout: Mapped[str] = mapped_column(String(20))
    origin: Mapped[str] = mapped_column(String(20))
    header: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict)
    measured_on: Mapped[dt.date | None] = mapped_column(Date)
    instrument_serial: Mapped[str | None] = mapped_column(String(100))
    n_points: Mapped[int] = mapped_column(Integer)
    x_mm: Mapped[bytes] = mapped_column(LargeBinary)
    y_mm: Mapped[bytes] = mapped_column(LargeBinary)
    added_points: Mapped[list[Any]] = mapped_column(JSON, default=list)
    point_notes: Mapped[list[Any]] = mapped_column(JSON, default=list)
    gauge_side: Mapped[str] = mapped_column(String(20))
    gauge_side_source: Mapped[str] = mapped_column(String(20))
    y_down: Mapped[bool] = mapped_column(Boolean)
    inclination: Mapped[float | None] = mapped_column(Float)
    reference: Mapped[str] = mapped_column(String(100), default="60E1")
    warnings: Mapped[list[Any]] = mapped_column(JSON, default=list)
    raw_path: Mapped[str | None] = mapped_column(String(200))
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())


class ReferenceProfile(Base):
    """A user-given reference (new) wheel profile: points in the wheel frame [mm] (float32
    blobs), from a drawing or a measured new wheel; the S1002 family is built in
    (:mod:`wearcast.physics.profiles.references`) and not stored."""

    __tablename__ = "reference_profiles"
    id: Mapped[int] = mapped_column(IdInteger, primary_key=True)
    name: Mapped[str] = mapped_column(String(100), unique=True)
    description: Mapped[str | None] = mapped_column(String(500))
    source: Mapped[str | None] = mapped_column(String(500))
    n_points: Mapped[int] = mapped_column(Integer)
    y_mm: Mapped[bytes] = mapped_column(LargeBinary)
    z_mm: Mapped[bytes] = mapped_column(LargeBinary)
    sd_mm: Mapped[float | None] = mapped_column(Float)
    sh_mm: Mapped[float | None] = mapped_column(Float)
    qr_mm: Mapped[float | None] = mapped_column(Float)
    created_at: Mapped[dt.datetime] = mapped_column(DateTime(timezone=True),
                                                    server_default=func.now())


# API keys, audit trail, idempotency keys share this metadata (migration 0003_service)
from wearcast.service import models_access as _models_access  # noqa: E402,F401
