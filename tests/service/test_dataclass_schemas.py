"""The HTTP bodies derived from the core's dataclasses (``service.dataclass_schemas``): one field
per dataclass field, in its order, typed as the core writes it as JSON and described by the
field's attribute docstring; the answer of a diagnosis is the core's ``to_dict`` byte for byte.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from typing import Any

import pytest
from pydantic import BaseModel, ValidationError

from wearcast.service.dataclass_schemas import attribute_docstrings, from_dataclass, json_type
from wearcast.service.diagnosis_schemas import DiagnosisOut, FindingOut, GainOut
from wearcast.statistics.discrepancy import Diagnosis
from wearcast.statistics.findings import FinderResult, Finding, Gain
from wearcast.statistics.physics_diagnosis import PhysicsDiagnosis

#: Fields of the finders' results that the diagnosis answer leaves out, and why.
NOT_PUBLISHED = {
    "residuals": "the report's residual frame (GET .../diagnose/report draws it)",
    "covariates": "the report's covariates per residual row",
    "predictions": "the report's predicted-vs-measured pairs",
}


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


@pytest.mark.parametrize("core", [FinderResult, Diagnosis, PhysicsDiagnosis])
def test_the_diagnosis_answer_carries_every_finder_field(core: type) -> None:
    """``DiagnosisOut`` is written by hand (it adds the service's own fields and serves both
    finders); every field of the finders' results is in it or named in NOT_PUBLISHED."""
    names = {f.name for f in dataclasses.fields(core)}
    assert names - set(NOT_PUBLISHED) <= set(DiagnosisOut.model_fields)
