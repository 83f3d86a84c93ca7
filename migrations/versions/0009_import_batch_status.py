"""import batches: a status (pending | complete | discarding) and a heartbeat; the
measurements of a batch that is not complete are invisible to every read

Revision ID: 0009_import_batch_status
Revises: 0008_bigint_ids
Create Date: 2026-11-26 04:30:00.000000
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = '0009_import_batch_status'
down_revision: str | None = '0008_bigint_ids'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table('import_batches', schema=None) as batch_op:
        batch_op.add_column(sa.Column('status', sa.String(length=20),
                                      server_default='complete', nullable=False))
        batch_op.add_column(sa.Column('heartbeat_at', sa.DateTime(timezone=True),
                                      nullable=True))
        batch_op.create_index(batch_op.f('ix_import_batches_status'), ['status'], unique=False)


def downgrade() -> None:
    # a batch that is not complete was never visible: its rows go with it
    op.execute("DELETE FROM measurements WHERE batch_id IN "
               "(SELECT id FROM import_batches WHERE status <> 'complete')")
    op.execute("DELETE FROM raw_files WHERE batch_id IN "
               "(SELECT id FROM import_batches WHERE status <> 'complete')")
    op.execute("DELETE FROM import_batches WHERE status <> 'complete'")
    with op.batch_alter_table('import_batches', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_import_batches_status'))
        batch_op.drop_column('heartbeat_at')
        batch_op.drop_column('status')
