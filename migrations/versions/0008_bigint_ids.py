"""64-bit ids on PostgreSQL: every id column (and column holding an id) becomes BIGINT, the
range the OpenAPI publishes (SQLite's INTEGER is 64-bit already: nothing to do there)

Before, an id between 2**31 and 2**63 in a path or body was schema-valid but made PostgreSQL
refuse the lookup ("integer out of range"): a 422 naming no field instead of a 404.

Revision ID: 0008_bigint_ids
Revises: 0007_physics_models
Create Date: 2026-11-26 02:00:00.000000
"""

from __future__ import annotations

from collections.abc import Sequence

from alembic import op

revision: str = '0008_bigint_ids'
down_revision: str | None = '0007_physics_models'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: (table, column) of every id and id reference
ID_COLUMNS = (
    ("api_keys", "id"), ("api_keys", "created_by"),
    ("audit_records", "id"), ("audit_records", "api_key_id"),
    ("idempotency_keys", "batch_id"),
    ("import_batches", "id"),
    ("raw_files", "id"), ("raw_files", "batch_id"),
    ("measurements", "id"), ("measurements", "batch_id"),
    ("routes", "id"),
    ("wear_tables", "id"), ("wear_table_rows", "id"), ("wear_table_rows", "wear_table_id"),
    ("models", "id"), ("models", "route_id"), ("models", "wear_table_id"),
    ("model_calibration_measurements", "model_id"),
    ("model_calibration_measurements", "measurement_id"),
    ("simulations", "id"), ("simulations", "owner_key_id"),
    ("rails", "id"), ("reference_profiles", "id"), ("plans", "id"),
)


def _retype(sql_type: str) -> None:
    if op.get_bind().dialect.name != "postgresql":
        return
    for table, column in ID_COLUMNS:
        op.execute(f'ALTER TABLE "{table}" ALTER COLUMN "{column}" TYPE {sql_type}')
    for table, column in ID_COLUMNS:
        if column == "id":  # the sequence numbering new rows follows the column
            op.execute(f"DO $$ DECLARE s text := pg_get_serial_sequence('\"{table}\"', "
                       f"'{column}'); BEGIN IF s IS NOT NULL THEN "
                       f"EXECUTE format('ALTER SEQUENCE %s AS {sql_type}', s); END IF; END $$")


def upgrade() -> None:
    _retype("BIGINT")


def downgrade() -> None:
    _retype("INTEGER")
