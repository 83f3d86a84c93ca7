"""Response bodies derived from the core's dataclasses, so that a result the core computes and
its HTTP answer are one list of fields.

``@from_dataclass(Finding)`` on ``class FindingOut(BaseModel)`` gives ``FindingOut`` one field
per ``dataclasses.fields(Finding)``, in their order, typed as the core writes the value as JSON
(:func:`json_type`, the rules of ``statistics.json_values.json_value``) and described by the
field's attribute docstring in the dataclass. A field added to the dataclass is in the answer
and in the published contract without a line written here; every derived field is required
(the answer always carries it, null where the value is).
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import inspect
import operator
import textwrap
import types
import typing
from collections.abc import Callable
from typing import Any, TypeVar

from pydantic import BaseModel, Field, create_model

ModelT = TypeVar("ModelT", bound=BaseModel)

#: The response model derived from each core dataclass (a nested dataclass field takes it).
_DERIVED: dict[type, type[BaseModel]] = {}


def attribute_docstrings(cls: type) -> dict[str, str]:
    """The docstring written under each annotated attribute of ``cls``'s class body (the
    attribute docstrings of PEP 257, as Sphinx reads a dataclass's fields), by name, its
    white space folded to single spaces."""
    try:
        source = textwrap.dedent(inspect.getsource(cls))
    except (OSError, TypeError):
        return {}
    node = ast.parse(source).body[0]
    if not isinstance(node, ast.ClassDef):
        return {}
    docs = {}
    for stmt, after in zip(node.body, node.body[1:], strict=False):
        if (isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name)
                and isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant)
                and isinstance(after.value.value, str)):
            docs[stmt.target.id] = " ".join(after.value.value.split())
    return docs


def json_type(annotation: Any) -> Any:
    """The type of a core field's value once written as JSON (``json_value``): a float may be
    null (NaN and infinities are written as null), a tuple is a list, a nested dataclass is
    its own derived model (derive it first); every other type is its own."""
    if annotation is float:
        return float | None
    if isinstance(annotation, type) and dataclasses.is_dataclass(annotation):
        if annotation not in _DERIVED:
            raise TypeError(f"{annotation.__name__}: derive its response model "
                            "(@from_dataclass) before a model that holds it")
        return _DERIVED[annotation]
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin in (types.UnionType, typing.Union):
        return functools.reduce(operator.or_, [json_type(a) for a in args])
    if origin is tuple:
        items = args[:1] if len(args) == 2 and args[1] is Ellipsis else args
        return list[functools.reduce(operator.or_, [json_type(a) for a in items])]  # type: ignore[misc]
    if origin is list:
        return list[json_type(args[0])]  # type: ignore[misc]
    if origin is dict:
        return dict[str, json_type(args[1])]  # type: ignore[misc]
    return annotation


def from_dataclass(core: type) -> Callable[[type[ModelT]], type[ModelT]]:
    """Class decorator: the response model it decorates, with one required field for each
    field of the dataclass ``core`` (:func:`json_type`, described by its attribute docstring;
    the model's own docstring, else ``core``'s, describes the model)."""
    if not dataclasses.is_dataclass(core):
        raise TypeError(f"{core!r} is not a dataclass")

    def derive(cls: type[ModelT]) -> type[ModelT]:
        hints = typing.get_type_hints(core)
        docs = attribute_docstrings(core)
        fields: dict[str, Any] = {
            f.name: (json_type(hints[f.name]), Field(description=docs.get(f.name)))
            for f in dataclasses.fields(core)}
        model = create_model(cls.__name__, __base__=cls, __module__=cls.__module__,
                             __doc__=cls.__doc__ or core.__doc__, **fields)
        _DERIVED[core] = model
        return model

    return derive
