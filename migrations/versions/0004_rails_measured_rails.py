"""measured rails (MiniProf .ban / rail parts of .mpt), points as in the file

Revision ID: 0004_rails
Revises: 0003_service
Create Date: 2026-11-25 13:00:00.000000
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = '0004_rails'
down_revision: str | None = '0003_service'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table('rails',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('name', sa.String(length=200), nullable=False),
    sa.Column('source_file', sa.String(length=500), nullable=False),
    sa.Column('part', sa.Integer(), nullable=False),
    sa.Column('sha256', sa.String(length=64), nullable=False),
    sa.Column('kind', sa.String(length=20), nullable=False),
    sa.Column('layout', sa.String(length=20), nullable=False),
    sa.Column('origin', sa.String(length=20), nullable=False),
    sa.Column('header', sa.JSON(), nullable=False),
    sa.Column('measured_on', sa.Date(), nullable=True),
    sa.Column('instrument_serial', sa.String(length=100), nullable=True),
    sa.Column('n_points', sa.Integer(), nullable=False),
    sa.Column('x_mm', sa.LargeBinary(), nullable=False),
    sa.Column('y_mm', sa.LargeBinary(), nullable=False),
    sa.Column('added_points', sa.JSON(), nullable=False),
    sa.Column('point_notes', sa.JSON(), nullable=False),
    sa.Column('gauge_side', sa.String(length=20), nullable=False),
    sa.Column('gauge_side_source', sa.String(length=20), nullable=False),
    sa.Column('y_down', sa.Boolean(), nullable=False),
    sa.Column('inclination', sa.Float(), nullable=True),
    sa.Column('reference', sa.String(length=100), nullable=False),
    sa.Column('warnings', sa.JSON(), nullable=False),
    sa.Column('raw_path', sa.String(length=200), nullable=True),
    sa.Column('created_at', sa.DateTime(timezone=True), server_default=sa.func.now(),
              nullable=False),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_rails')),
    sa.UniqueConstraint('sha256', 'part', name='uq_rails_sha256_part')
    )
    with op.batch_alter_table('rails', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_rails_sha256'), ['sha256'], unique=False)


def downgrade() -> None:
    with op.batch_alter_table('rails', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_rails_sha256'))
    op.drop_table('rails')
