"""The HTTP bodies derived from the core's dataclasses (``service.dataclass_schemas``): one field
per dataclass field, in its order, typed as the core writes it as JSON and described by the
field's attribute docstring; the answer of a diagnosis is the core's ``to_dict`` byte for byte.
An answer of several cores (``from_dataclasses``) lists their fields part by part, keeps their
defaults and refuses a field declared differently or written again in the service.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import Any

import pytest
from pydantic import BaseModel, Field, ValidationError

from wearcast.service.dataclass_schemas import (
    attribute_docstrings,
    from_dataclass,
    from_dataclasses,
    json_type,
)
from wearcast.service.diagnosis_schemas import DiagnosisOut, FindingOut, GainOut
from wearcast.statistics.findings import Finding, Gain


@dataclass(frozen=True)
class _Inner:
    depth_mm: float
    """worn depth [mm]"""


@dataclass(frozen=True)
class _Outer:
    name: str
    """what it is"""
    inner: _Inner
    values_mm: tuple[float, ...]
    added_km: float | None = None
    """a field added later: in the derived model without a line in the service"""


@from_dataclass(_Inner)
class _InnerOut(BaseModel):
    pass


@from_dataclass(_Outer)
class _OuterOut(BaseModel):
    """The outer thing."""


def _finding(**gain: Any) -> Finding:
    g = Gain(**{"before_error": 2.0, "after_error": 1.0, "relative": 0.5, "ci95_low": 0.25,
                "ci95_high": 0.75, "metric": "log_area", **gain})
    return Finding("flange_lubrication", "flange wear down 50 %", {"p_value": 0.01},
                   {"parameters": {"factor": 0.5}}, g, True, False)


@pytest.mark.parametrize(("model", "core"), [(FindingOut, Finding), (GainOut, Gain)])
def test_the_answer_has_exactly_the_core_fields_in_their_order(model: type[BaseModel],
                                                                core: type) -> None:
    assert list(model.model_fields) == [f.name for f in dataclasses.fields(core)]
    schema = model.model_json_schema(mode="serialization")
    assert schema["required"] == list(model.model_fields)
    docs = attribute_docstrings(core)
    for name, prop in schema["properties"].items():
        assert prop["description"] == docs[name] and docs[name], name


def test_the_gain_numbers_are_nullable_the_flags_and_texts_not() -> None:
    props = GainOut.model_json_schema(mode="serialization")["properties"]
    for name in ("before_error", "after_error", "relative", "ci95_low", "ci95_high",
                 "calibrated_error"):
        assert props[name]["anyOf"] == [{"type": "number"}, {"type": "null"}], name
    assert props["metric"]["type"] == "string"
    finding = FindingOut.model_json_schema(mode="serialization")
    assert finding["properties"]["significant"]["type"] == "boolean"
    assert finding["properties"]["gain"]["$ref"].endswith("/GainOut")


def test_the_http_finding_is_the_core_to_dict_byte_for_byte() -> None:
    finding = _finding(relative=math.nan, ci95_high=math.inf, calibrated_error=3.0)
    core = finding.to_dict()
    assert core["gain"]["relative"] is None and core["gain"]["ci95_high"] is None
    http = FindingOut.model_validate(core).model_dump_json()
    assert http == json.dumps(core, separators=(",", ":"), ensure_ascii=False)
    assert list(json.loads(http)["gain"]) == [f.name for f in dataclasses.fields(Gain)]


def test_a_missing_core_field_is_refused_not_left_out() -> None:
    body = _finding().to_dict()
    del body["material"]
    with pytest.raises(ValidationError, match="material"):
        FindingOut.model_validate(body)


def test_a_field_added_to_the_dataclass_is_in_the_derived_model() -> None:
    assert list(_OuterOut.model_fields) == ["name", "inner", "values_mm", "added_km"]
    schema = _OuterOut.model_json_schema(mode="serialization")
    assert schema["description"] == "The outer thing."
    props = schema["properties"]
    assert props["added_km"]["description"] == (
        "a field added later: in the derived model without a line in the service")
    assert props["added_km"]["anyOf"] == [{"type": "number"}, {"type": "null"}]
    assert "description" not in props["values_mm"]  # no attribute docstring, none invented
    assert props["values_mm"]["items"]["anyOf"] == [{"type": "number"}, {"type": "null"}]
    assert props["inner"]["$ref"].endswith("/_InnerOut")
    out = _OuterOut.model_validate({"name": "a", "inner": {"depth_mm": None},
                                    "values_mm": [1.0, None], "added_km": 2.0})
    assert out.model_dump() == {"name": "a", "inner": {"depth_mm": None},
                                "values_mm": [1.0, None], "added_km": 2.0}


def test_a_nested_dataclass_needs_its_model_derived_first() -> None:
    @dataclass(frozen=True)
    class Underived:
        x: float

    with pytest.raises(TypeError, match="Underived"):
        json_type(Underived)
    assert json_type(_Inner) is _InnerOut
    assert json_type(dict[str, float]) == dict[str, float | None]


def test_the_diagnosis_answer_takes_the_core_findings() -> None:
    item = DiagnosisOut.model_json_schema(mode="serialization")["properties"]["findings"]
    assert item["items"]["$ref"].endswith("/FindingOut")


@dataclass(frozen=True)
class _Hybrid:
    verdict: str
    """what the finder names"""
    report: tuple[float, ...] = field(default=(), repr=False, compare=False)
    selected: tuple[str, ...] = ()
    """causes named"""
    margin: float | None = None


@dataclass(frozen=True)
class _Physics:
    verdict: str
    null_fit: dict[str, Any]
    """the null's fit"""
    margin: float | None = None
    spread: dict[str, float] = field(default_factory=lambda: {"a": 1.0})


class _Service(BaseModel):
    excluded: dict[str, int] = Field(default_factory=dict)


@from_dataclasses(_Hybrid, _Service, _Physics)
class _AnswerOut(BaseModel):
    model_id: int


def test_an_answer_of_several_cores_lists_their_fields_part_by_part() -> None:
    assert list(_AnswerOut.model_fields) == [
        "model_id", "verdict", "selected", "margin", "excluded", "null_fit", "spread"]
    schema = _AnswerOut.model_json_schema(mode="serialization")
    assert schema["required"] == ["model_id", "verdict"]  # on every core, no default
    assert "description" not in schema  # the decorated class has no docstring
    props = schema["properties"]
    assert props["verdict"]["description"] == "what the finder names"
    assert props["null_fit"]["description"] == "the null's fit"


def test_an_answer_of_several_cores_keeps_their_defaults() -> None:
    out = _AnswerOut.model_validate({"model_id": 1, "verdict": "none"})
    # a field one core lacks and has no default there is null; the others' defaults kept,
    # as the core writes them (a tuple as a list), a fresh copy each time
    assert out.model_dump() == {"model_id": 1, "verdict": "none", "selected": [],
                                "margin": None, "excluded": {}, "null_fit": None,
                                "spread": {"a": 1.0}}
    assert _AnswerOut.model_fields["null_fit"].annotation == dict[str, Any] | None
    out.spread["a"] = 2.0
    assert _AnswerOut.model_validate({"model_id": 1, "verdict": "x"}).spread == {"a": 1.0}


def test_an_internal_field_is_not_published() -> None:
    assert "report" not in _AnswerOut.model_fields


def test_a_field_declared_differently_by_two_cores_is_refused() -> None:
    @dataclass(frozen=True)
    class Other:
        margin: str = ""

    with pytest.raises(TypeError, match="margin"):
        from_dataclasses(_Hybrid, Other)(type("Out", (BaseModel,), {}))

    @dataclass(frozen=True)
    class Described:
        verdict: str
        """another description"""

    with pytest.raises(TypeError, match="verdict"):
        from_dataclasses(_Hybrid, Described)(type("Out", (BaseModel,), {}))


def test_a_core_field_written_again_in_the_service_is_refused() -> None:
    class Again(BaseModel):
        margin: float | None = None

    with pytest.raises(TypeError, match="margin"):
        from_dataclasses(_Hybrid, Again)(type("Out", (BaseModel,), {}))
    with pytest.raises(TypeError, match="verdict"):
        from_dataclasses(_Hybrid)(type("Out", (BaseModel,), {"__annotations__": {
            "verdict": str}}))
