"""wheels and vehicles: the import batch that registered them, so that the wheels and
vehicles of a pending import are as invisible as its measurements

Revision ID: 0011_registered_batch
Revises: 0010_audit_action_index
Create Date: 2026-11-26 08:00:00.000000
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = '0011_registered_batch'
down_revision: str | None = '0010_audit_action_index'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

_ID = sa.Integer().with_variant(sa.BigInteger(), "postgresql")


def upgrade() -> None:
    for table in ('vehicles', 'wheels'):
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.add_column(sa.Column('registered_batch_id', _ID, nullable=True))
            batch_op.create_index(batch_op.f(f'ix_{table}_registered_batch_id'),
                                  ['registered_batch_id'], unique=False)


def downgrade() -> None:
    for table in ('wheels', 'vehicles'):
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.drop_index(batch_op.f(f'ix_{table}_registered_batch_id'))
            batch_op.drop_column('registered_batch_id')
