"""Values made writable as JSON: numpy arrays and scalars as plain lists and numbers,
non-finite floats as null (or the strings ``"inf"``/``"-inf"`` in a stored state).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np


def jsonable(value: Any) -> Any:
    """``value`` with numpy arrays and scalars as lists and numbers, dict keys as strings,
    NaN as null and infinities as ``"inf"``/``"-inf"`` (a stored model's state)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


def finite_or_none(value: Any) -> float | None:
    """A finite float, or None (for None, NaN and infinities): a nullable number."""
    if value is None:
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def finite_list_or_none(values: np.ndarray) -> list[float | None]:
    """``values`` as a list of floats, None where not finite (one pass when all are)."""
    if np.isfinite(values).all():
        return values.tolist()
    return [finite_or_none(v) for v in values.tolist()]
