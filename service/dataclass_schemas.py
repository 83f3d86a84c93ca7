"""Response bodies derived from the core's dataclasses, so that a result the core computes and
its HTTP answer are one list of fields.

``@from_dataclass(Finding)`` on ``class FindingOut(BaseModel)`` gives ``FindingOut`` one field
per ``dataclasses.fields(Finding)``, in their order, typed as the core writes the value as JSON
(:func:`json_type`, the rules of ``statistics.json_values.json_value``) and described by the
field's attribute docstring in the dataclass. A field added to the dataclass is in the answer
and in the published contract without a line written here; every derived field is required
(the answer always carries it, null where the value is).

``@from_dataclasses(Diagnosis, ..., PhysicsDiagnosis, ...)`` makes one answer of several
results (the hybrid and the physics diagnosis answer with one body): the fields of the class
body, then part by part the fields of each dataclass not taken yet and those of each pydantic
model listed (the service's own fields, where the answer lists them). There a core field keeps
its core's default, so that the answer of a result without it is still whole (:func:`_default`).

A field kept out of both its dataclass's repr and its equality (``field(repr=False,
compare=False)``) is the result's working data (a report's residual frame), not the result:
no answer publishes it (:func:`published_fields`).
"""

from __future__ import annotations

import ast
import copy
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

from wearcast.statistics.json_values import json_value

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


def field_docstrings(core: type) -> dict[str, str]:
    """The attribute docstrings of the dataclass ``core``'s fields, those written in its base
    classes' bodies included (a subclass's own docstring of a field wins)."""
    docs: dict[str, str] = {}
    for cls in reversed(core.__mro__):
        if dataclasses.is_dataclass(cls):
            docs.update(attribute_docstrings(cls))
    return docs


def published_fields(core: type) -> list[dataclasses.Field[Any]]:
    """The fields of the dataclass ``core`` that its answers publish, in its order: all but the
    internal ones, a field that is in neither its repr nor its equality (``field(repr=False,
    compare=False)``: data the result carries for a report or a figure, not the result)."""
    return [f for f in dataclasses.fields(core) if f.repr or f.compare]


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
        docs = field_docstrings(core)
        fields: dict[str, Any] = {
            f.name: (json_type(hints[f.name]), Field(description=docs.get(f.name)))
            for f in published_fields(core)}
        model = create_model(cls.__name__, __base__=cls, __module__=cls.__module__,
                             __doc__=cls.__doc__ or core.__doc__, **fields)
        _DERIVED[core] = model
        return model

    return derive


def _default(f: dataclasses.Field[Any]) -> dict[str, Any]:
    """The ``Field`` default of the answer's field from the core field ``f``: its default as
    ``json_value`` writes it (a tuple as a list), a list or a dict one as a factory of a fresh
    copy; {} when ``f`` has none."""
    if f.default is not dataclasses.MISSING:
        value = f.default
    elif f.default_factory is not dataclasses.MISSING:
        value = f.default_factory()
    else:
        return {}
    written = json_value(value)
    if isinstance(written, list | dict):
        return {"default_factory": functools.partial(copy.deepcopy, written)}
    return {"default": written}


def from_dataclasses(*parts: type) -> Callable[[type[ModelT]], type[ModelT]]:
    """Class decorator: one response model for the results of several dataclasses.

    After the fields of the decorated class's body, each of ``parts`` in turn adds its fields:
    a dataclass (a core result) its published fields (:func:`published_fields`) not added
    yet, a pydantic model (the service's own fields) its fields as declared. A core field is
    typed by :func:`json_type` and described by its attribute docstring; it keeps its core's
    default (:func:`_default`); without one it is required when every dataclass of ``parts``
    has it, else nullable and null by default (the answers of the others leave it null).
    A field on several dataclasses must be declared alike there (the same type and default,
    no two different docstrings): a ``TypeError`` at import otherwise. The model's
    description is the decorated class's docstring (none without one).
    """
    cores = [p for p in parts if dataclasses.is_dataclass(p)]
    for part in parts:
        if not (dataclasses.is_dataclass(part)
                or (isinstance(part, type) and issubclass(part, BaseModel))):
            raise TypeError(f"{part!r} is neither a dataclass nor a pydantic model")

    def core_field(name: str) -> tuple[Any, Any]:
        """(json type, Field) of the core field ``name``, checked alike on every core."""
        declared = []
        for core in cores:
            of = {f.name: f for f in published_fields(core)}
            if name in of:
                f = of[name]
                declared.append((core, json_type(typing.get_type_hints(core)[name]),
                                 _default(f), field_docstrings(core).get(name)))
        core0, kind, default, _ = declared[0]
        for core, other_kind, other_default, _ in declared[1:]:
            if other_kind != kind or _default_value(other_default) != _default_value(default):
                raise TypeError(f"{name}: declared as {kind} = {_default_value(default)!r} in "
                                f"{core0.__name__} but as {other_kind} = "
                                f"{_default_value(other_default)!r} in {core.__name__}")
        docs = {d for *_, d in declared if d}
        if len(docs) > 1:
            raise TypeError(f"{name}: described differently by the dataclasses: {sorted(docs)}")
        if not default and len(declared) < len(cores):
            kind, default = kind | None, {"default": None}
        return kind, Field(description=docs.pop() if docs else None, **default)

    def derive(cls: type[ModelT]) -> type[ModelT]:
        fields: dict[str, Any] = {}
        service = set(cls.model_fields)  # the fields the service declares itself
        for part in parts:
            if dataclasses.is_dataclass(part):
                names = [f.name for f in published_fields(part)]
                added = {n: core_field(n) for n in names if n not in fields}
            else:
                model = typing.cast(type[BaseModel], part)
                added = {n: (info.annotation, info) for n, info in model.model_fields.items()}
            clash = (service | set(fields)) & set(added)
            if clash:
                raise TypeError(f"{cls.__name__}: {sorted(clash)} of {part.__name__} declared "
                                "twice (a core field is derived, never written in the service)")
            fields.update(added)
            if not dataclasses.is_dataclass(part):
                service |= set(added)
        return create_model(cls.__name__, __base__=cls, __module__=cls.__module__,
                            __doc__=cls.__doc__, **fields)

    return derive


def _default_value(default: dict[str, Any]) -> Any:
    """The value a ``Field`` default of :func:`_default` gives (``MISSING`` for none)."""
    if "default_factory" in default:
        return default["default_factory"]()
    return default.get("default", dataclasses.MISSING)
