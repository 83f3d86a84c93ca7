"""Checks of the tables (pandas DataFrames) the statistics core is given: a frame, with its
columns, and at least one row. Errors name the field (``"field: reason"``), as everywhere in
the statistics core.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import pandas as pd


def check_frame(frame: Any, columns: Sequence[str], *, field: str, what: str,
                no_rows: str = "no rows") -> None:
    """Raise ValueError unless ``frame`` is a DataFrame with ``columns`` and a row:
    ``"{field}: must be a pandas DataFrame"``, ``"{column}: column missing from {what}"``,
    ``"{field}: {no_rows}"``."""
    if not isinstance(frame, pd.DataFrame):
        raise ValueError(f"{field}: must be a pandas DataFrame")
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise ValueError(f"{missing[0]}: column missing from {what}")
    if frame.empty:
        raise ValueError(f"{field}: {no_rows}")
