"""Values made writable as JSON: nested values with numpy scalars and arrays made plain
Python (:func:`json_value`), numbers with non-finite floats as null (one number, or a
numpy array as a list), and a dataclass's fields (:func:`fields_json`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np


def finite_or_none(value: Any) -> float | None:
    """A finite float, or None (for None, NaN and infinities): a nullable number."""
    if value is None:
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def finite_list_or_none(values: np.ndarray) -> list[float | None]:
    """``values`` as a list of floats, None where not finite (one pass when all are)."""
    values = np.asarray(values, dtype=float)
    if np.isfinite(values).all():
        return values.tolist()
    return [finite_or_none(v) for v in values.tolist()]


def json_value(value: Any, *, infinity_as_text: bool = False) -> Any:
    """``value`` with numpy scalars and arrays made plain Python, mappings' keys made strings,
    tuples made lists and non-finite floats made None (ready for ``json.dumps``); with
    ``infinity_as_text`` infinities become ``"inf"``/``"-inf"`` instead (a stored model's
    state keeps them)."""
    if isinstance(value, Mapping):
        return {str(k): json_value(v, infinity_as_text=infinity_as_text)
                for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_value(v, infinity_as_text=infinity_as_text) for v in value]
    if isinstance(value, np.ndarray):
        return json_value(value.tolist(), infinity_as_text=infinity_as_text)
    if isinstance(value, np.generic):
        return json_value(value.item(), infinity_as_text=infinity_as_text)
    if isinstance(value, float) and not math.isfinite(value):
        if infinity_as_text and not math.isnan(value):
            return "inf" if value > 0 else "-inf"
        return None
    return value


def fields_json(obj: Any) -> dict[str, Any]:
    """Every field of the dataclass instance ``obj``, in the dataclass's order, as
    :func:`json_value` writes it (a nested dataclass as its own fields): the JSON form the
    HTTP answers derived from the dataclass publish (``service.dataclass_schemas``)."""
    out = {}
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        is_instance = dataclasses.is_dataclass(value) and not isinstance(value, type)
        out[f.name] = fields_json(value) if is_instance else json_value(value)
    return out
