"""audit records: an index on (action, id), so that every serving process can find the newest
removal (delete or supersede) cheaply and forget its cached copies of removed rows

Revision ID: 0010_audit_action_index
Revises: 0009_import_batch_status
Create Date: 2026-11-26 07:30:00.000000
"""

from __future__ import annotations

from collections.abc import Sequence

from alembic import op

revision: str = '0010_audit_action_index'
down_revision: str | None = '0009_import_batch_status'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table('audit_records', schema=None) as batch_op:
        batch_op.create_index('ix_audit_records_action_id', ['action', 'id'], unique=False)


def downgrade() -> None:
    with op.batch_alter_table('audit_records', schema=None) as batch_op:
        batch_op.drop_index('ix_audit_records_action_id')
