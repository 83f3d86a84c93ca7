"""measured wheels: reference fit, placement and warnings per measurement; user reference
profiles

Revision ID: 0006_measured
Revises: 0005_planner
Create Date: 2026-11-25 12:30:00.000000
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = '0006_measured'
down_revision: str | None = '0005_planner'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table('measurements', schema=None) as batch_op:
        batch_op.add_column(sa.Column('reference_fits', sa.Boolean(), nullable=True))
        batch_op.add_column(sa.Column('placement', sa.JSON(), nullable=True))
        batch_op.add_column(sa.Column('warnings', sa.JSON(), nullable=True))
    op.create_table('reference_profiles',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('name', sa.String(length=100), nullable=False),
    sa.Column('description', sa.String(length=500), nullable=True),
    sa.Column('source', sa.String(length=500), nullable=True),
    sa.Column('n_points', sa.Integer(), nullable=False),
    sa.Column('y_mm', sa.LargeBinary(), nullable=False),
    sa.Column('z_mm', sa.LargeBinary(), nullable=False),
    sa.Column('sd_mm', sa.Float(), nullable=True),
    sa.Column('sh_mm', sa.Float(), nullable=True),
    sa.Column('qr_mm', sa.Float(), nullable=True),
    sa.Column('created_at', sa.DateTime(timezone=True), server_default=sa.func.now(),
              nullable=False),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_reference_profiles')),
    sa.UniqueConstraint('name', name=op.f('uq_reference_profiles_name'))
    )


def downgrade() -> None:
    op.drop_table('reference_profiles')
    with op.batch_alter_table('measurements', schema=None) as batch_op:
        batch_op.drop_column('warnings')
        batch_op.drop_column('placement')
        batch_op.drop_column('reference_fits')
