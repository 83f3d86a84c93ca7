"""What every request and response body of the ``/v1`` contract (pydantic v2) shares: the strict
base model, the measurement filter and the limits on mileages and profile points.

Numbers must be finite (NaN/inf are refused), unknown fields are refused, and enumerations
accept only their documented values, so every bad input is a 422 naming its field. The
bodies themselves live one resource a module (``route_schemas``, ``measurement_schemas``,
``model_schemas`` ...).
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict

FilterValue = str | int | float | bool | None
Filter = dict[str, FilterValue | list[FilterValue]]


#: Largest mileage [km] accepted anywhere (a wheel runs a few million km in its life).
MAX_MILEAGE_KM = 1e8
#: Most points of one measured profile (instruments give a few hundred to a few thousand).
MAX_PROFILE_POINTS = 20_000


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
