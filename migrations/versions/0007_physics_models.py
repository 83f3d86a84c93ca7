"""physics models: a model's kind (hybrid | physics); a physics model has no wear table,
measure or running mode

Revision ID: 0007_physics_models
Revises: 0006_measured
Create Date: 2026-11-25 19:00:00.000000
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = '0007_physics_models'
down_revision: str | None = '0006_measured'
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table('models', schema=None) as batch_op:
        batch_op.add_column(sa.Column('kind', sa.String(length=20), server_default='hybrid',
                                      nullable=False))
        batch_op.alter_column('measure', existing_type=sa.String(length=20), nullable=True)
        batch_op.alter_column('running_mode', existing_type=sa.String(length=20),
                              nullable=True)
        batch_op.alter_column('wear_table_id', existing_type=sa.Integer(), nullable=True)


def downgrade() -> None:
    op.execute("DELETE FROM model_calibration_measurements WHERE model_id IN "
               "(SELECT id FROM models WHERE kind = 'physics')")
    op.execute("DELETE FROM models WHERE kind = 'physics'")
    with op.batch_alter_table('models', schema=None) as batch_op:
        batch_op.alter_column('wear_table_id', existing_type=sa.Integer(), nullable=False)
        batch_op.alter_column('running_mode', existing_type=sa.String(length=20),
                              nullable=False)
        batch_op.alter_column('measure', existing_type=sa.String(length=20), nullable=False)
        batch_op.drop_column('kind')
