"""What every request and response body of the ``/v1`` contract (pydantic v2) shares: the strict
base model, the measurement filter and the limits on mileages and profile points.

Numbers must be finite (NaN/inf are refused), unknown fields are refused, and enumerations
accept only their documented values, so every bad input is a 422 naming its field. The
bodies themselves live one resource a module (``route_schemas``, ``measurement_schemas``,
``model_schemas`` ...).
"""

from __future__ import annotations

import datetime as dt
import functools
import re
import types
import typing
from collections.abc import Sequence
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationInfo, field_validator

FilterValue = str | int | float | bool | None
Filter = dict[str, FilterValue | list[FilterValue]]


#: Largest mileage [km] accepted anywhere (a wheel runs a few million km in its life).
MAX_MILEAGE_KM = 1e8
#: Most points of one measured profile (instruments give a few hundred to a few thousand).
MAX_PROFILE_POINTS = 20_000


_ISO_DATE = re.compile(r"[0-9]{4}-[0-9]{2}-[0-9]{2}")


def _iso_date_only(value: Any) -> Any:
    """Refuse what pydantic would read as a date but the contract's ``format: date`` does not
    allow: a number or a string of digits (read as Unix seconds: ``today=0`` is 1970-01-01),
    a date-time."""
    if isinstance(value, dt.date) and not isinstance(value, dt.datetime):
        return value
    if isinstance(value, str) and _ISO_DATE.fullmatch(value):
        return value
    raise ValueError(f"{str(value)[:40]!r} is not a date as YYYY-MM-DD")


#: A calendar date given as ``YYYY-MM-DD`` only (the published ``format: date``), in bodies
#: and in query strings.
IsoDate = Annotated[dt.date, BeforeValidator(_iso_date_only)]


def _json_integer_only(value: Any) -> Any:
    """Refuse what pydantic would read as an integer but JSON Schema's ``integer`` does not
    allow: ``true``/``false`` and strings (``"1"``); ``1.0`` is an integer, ``1.5`` is refused
    by the integer check itself."""
    if isinstance(value, bool | str):
        raise ValueError(f"{value!r} is not an integer id (give a JSON number such as 12)")
    return value


#: The id of a stored row named in a body (``rail_id``, ``measurement_id`` ...): a JSON
#: integer from 1 to 2**62; ``true`` or ``"1"`` are refused rather than read as the id 1.
#: (The bounds come before the validator: after it, pydantic would publish them as ``ge``/``le``
#: instead of ``minimum``/``maximum``.)
StoredId = Annotated[int, Field(ge=1, le=2**62), BeforeValidator(_json_integer_only)]


def exactly_one(body: Any, *fields: str) -> None:
    """The rule "give exactly one of these fields" (a route by id or inline, a wear or a
    measurement, ...): :class:`FieldsError` naming all of them when none or several are given."""
    given = [f for f in fields if getattr(body, f) is not None]
    if len(given) != 1:
        raise FieldsError(fields, f"give either {' or '.join(fields)} (exactly one)")


def at_most_one(body: Any, *fields: str) -> None:
    """The rule "give at most one of these fields": :class:`FieldsError` naming those given."""
    given = [f for f in fields if getattr(body, f) is not None]
    if len(given) > 1:
        raise FieldsError(given, f"give at most one of {', '.join(fields)} (got "
                          f"{', '.join(given)})")


class FieldsError(ValueError):
    """A rule across fields that a request breaks, raised from a model validator: the 422
    names each of ``fields`` (relative to the model) with the reason, where a plain
    ``ValueError`` would name only the model (``body``)."""

    def __init__(self, fields: Sequence[str], reason: str) -> None:
        super().__init__(reason)
        self.fields = tuple(fields)


@functools.cache
def _takes_bool(annotation: Any) -> bool:
    """Whether a field's type admits ``true``/``false`` anywhere in it (``bool``, ``Any``, an
    unknown type; a union, a container or an ``Annotated`` that holds one)."""
    if annotation is bool or annotation is Any:
        return True
    if annotation is None or annotation is types.NoneType:
        return False
    args = typing.get_args(annotation)
    origin = typing.get_origin(annotation)
    if origin is typing.Literal:
        return any(isinstance(a, bool) for a in args)
    if origin is Annotated:
        return _takes_bool(args[0])
    if args:
        return any(_takes_bool(a) for a in args if a is not Ellipsis)
    if isinstance(annotation, type):
        if issubclass(annotation, BaseModel):
            return False  # its own fields are checked by its own validator
        return not issubclass(annotation, int | float | str | bytes | dt.date)
    return True


class Strict(BaseModel):
    """Unknown fields, NaN and infinities refused; and ``true``/``false`` where the schema
    says number, integer or string (pydantic would read ``true`` as 1 or 1.0: a rail, a route
    or a mileage the client did not name), in the field itself or as an item of its list."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_for_numbers(cls, value: Any, info: ValidationInfo) -> Any:
        if isinstance(value, bool | list) and info.field_name in cls.model_fields:
            items = value if isinstance(value, list) else [value]
            annotation: Any = cls.model_fields[info.field_name].annotation
            if any(isinstance(v, bool) for v in items) and not _takes_bool(annotation):
                where = "an item is" if isinstance(value, list) else "is"
                raise ValueError(f"{where} true or false where the schema takes no boolean")
        return value
