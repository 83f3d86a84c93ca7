"""planning: measured wheel diameter, vehicle fleet and mileage per day, fleets, lathe plans

Revision ID: 0005_planner
Revises: 0004_rails
Create Date: 2026-11-25 12:40:00.000000
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = '0005_planner'
down_revision: str | None = '0004_rails'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table('measurements', schema=None) as batch_op:
        batch_op.add_column(sa.Column('diameter_mm', sa.Float(), nullable=True))
    with op.batch_alter_table('vehicles', schema=None) as batch_op:
        batch_op.add_column(sa.Column('fleet_id', sa.String(length=200), nullable=True))
        batch_op.add_column(sa.Column('km_per_day', sa.Float(), nullable=True))
        batch_op.create_index(batch_op.f('ix_vehicles_fleet_id'), ['fleet_id'], unique=False)
    op.create_table('fleets',
    sa.Column('fleet_id', sa.String(length=200), nullable=False),
    sa.Column('limits', sa.JSON(), nullable=False),
    sa.Column('created_at', sa.DateTime(timezone=True), server_default=sa.func.now(),
              nullable=False),
    sa.PrimaryKeyConstraint('fleet_id', name=op.f('pk_fleets'))
    )
    op.create_table('plans',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('fleet_id', sa.String(length=200), nullable=True),
    sa.Column('spec', sa.JSON(), nullable=False),
    sa.Column('result', sa.JSON(), nullable=False),
    sa.Column('created_at', sa.DateTime(timezone=True), server_default=sa.func.now(),
              nullable=False),
    sa.PrimaryKeyConstraint('id', name=op.f('pk_plans'))
    )
    with op.batch_alter_table('plans', schema=None) as batch_op:
        batch_op.create_index(batch_op.f('ix_plans_fleet_id'), ['fleet_id'], unique=False)


def downgrade() -> None:
    with op.batch_alter_table('plans', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_plans_fleet_id'))
    op.drop_table('plans')
    op.drop_table('fleets')
    with op.batch_alter_table('vehicles', schema=None) as batch_op:
        batch_op.drop_index(batch_op.f('ix_vehicles_fleet_id'))
        batch_op.drop_column('km_per_day')
        batch_op.drop_column('fleet_id')
    with op.batch_alter_table('measurements', schema=None) as batch_op:
        batch_op.drop_column('diameter_mm')
