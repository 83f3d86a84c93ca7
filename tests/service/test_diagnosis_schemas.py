"""The diagnosis answer (``service.diagnosis_schemas.DiagnosisOut``) publishes every public field
of both finders' results (``discrepancy.Diagnosis``, ``physics_diagnosis.PhysicsDiagnosis``)
as the cores type and describe them, and nothing else but the service's own fields.

The rule for a result's internal fields, stated here on its own: a dataclass field kept out of
both the repr and the equality of its result (``field(repr=False, compare=False)``) is working
data (a report's residual frame), not published; every other field is.
"""

from __future__ import annotations

import dataclasses
import json
import typing
from typing import Any

import pandas as pd
import pytest

from wearcast.service.dataclass_schemas import attribute_docstrings, json_type
from wearcast.service.diagnosis_schemas import DiagnosisOut
from wearcast.statistics.discrepancy import Diagnosis
from wearcast.statistics.findings import FinderResult, Finding, Gain
from wearcast.statistics.physics_diagnosis import PhysicsDiagnosis

CORES = (FinderResult, Diagnosis, PhysicsDiagnosis)
#: The fields only the service knows: the diagnosed model, what it left out or gave the
#: finder, and what ``save_as`` stored.
SERVICE_FIELDS = ("model_id", "excluded", "expected_progression", "saved_model", "save_reason")


def _public(core: type) -> list[str]:
    return [f.name for f in dataclasses.fields(core) if f.repr or f.compare]


def _internal(core: type) -> list[str]:
    return [f.name for f in dataclasses.fields(core) if not f.repr and not f.compare]


def _finding() -> Finding:
    gain = Gain(2.0, 1.0, 0.5, 0.25, 0.75, calibrated_error=2.5, metric="log_area")
    return Finding("flange_lubrication", "flange wear down 50 %", {"p_value": 0.01},
                   {"parameters": {"factor": 0.5}}, gain, True, True)


def _hybrid() -> Diagnosis:
    return Diagnosis("flange_lubrication", (_finding(),), {"season": "one date"}, 40, 8,
                     "vehicle", residuals=pd.DataFrame({"e": [0.1, -0.2]}),
                     covariates={"x": [1, 2]}, predictions={"a": [[1.0, 2.0]]},
                     selected=("flange_lubrication",), runner_up="traction",
                     margin=float("nan"), margin_p_value=0.02, candidates=(),
                     unexplained=({"by": "route", "size": 0.1},), nuisance={"vehicle": 0.2},
                     null_test="sign flips")


def _physics() -> PhysicsDiagnosis:
    return PhysicsDiagnosis("ambiguous", (_finding(),), {}, 30, 6, "vehicle",
                            {"wear_scale": 1.2, "rms_mm": 0.1, "series": ["FT_mm"]},
                            runner_up="traction", margin=0.01, margin_p_value=0.4,
                            candidates=("flange_lubrication", "traction"), at_reach=("null",))


@pytest.mark.parametrize("core", CORES)
def test_every_public_field_of_a_finder_result_is_in_the_answer(core: type) -> None:
    missing = set(_public(core)) - set(DiagnosisOut.model_fields)
    assert not missing, f"{core.__name__} fields missing from DiagnosisOut: {sorted(missing)}"


@pytest.mark.parametrize("core", CORES)
def test_no_internal_field_is_published(core: type) -> None:
    assert not set(_internal(core)) & set(DiagnosisOut.model_fields)


def test_the_report_data_of_the_hybrid_result_is_internal() -> None:
    # the rule holds the report's working data back: none of it is a public field
    assert set(_internal(Diagnosis)) >= {"residuals"}
    assert "residuals" not in _hybrid().to_dict()


def test_the_answer_has_nothing_but_core_and_service_fields() -> None:
    core = {name for c in CORES for name in _public(c)}
    assert set(DiagnosisOut.model_fields) == core | set(SERVICE_FIELDS)
    assert not core & set(SERVICE_FIELDS)


@pytest.mark.parametrize("core", [Diagnosis, PhysicsDiagnosis])
def test_a_core_field_is_typed_and_described_as_its_core_writes_it(core: type) -> None:
    hints = typing.get_type_hints(core)
    docs = {**attribute_docstrings(FinderResult), **attribute_docstrings(core)}
    props = DiagnosisOut.model_json_schema(mode="serialization")["properties"]
    for name in _public(core):
        out = DiagnosisOut.model_fields[name]
        on_every_core = all(name in _public(c) for c in (Diagnosis, PhysicsDiagnosis))
        want = json_type(hints[name])
        if out.annotation != want:  # only a field that one finder lacks may be null there
            assert not on_every_core and out.annotation == want | None, name
            assert out.default is None, name
        if name in docs:
            assert props[name]["description"] == docs[name], name


@pytest.mark.parametrize("result", [_hybrid, _physics])
def test_to_dict_writes_exactly_the_public_fields(result: Any) -> None:
    r = result()
    assert list(r.to_dict()) == _public(type(r))


@pytest.mark.parametrize("result", [_hybrid, _physics])
def test_the_answer_carries_the_core_to_dict_unchanged(result: Any) -> None:
    r = result()
    core = json.loads(json.dumps(r.to_dict()))
    out = DiagnosisOut.model_validate({"model_id": 7, **r.to_dict()})
    body = json.loads(out.model_dump_json())
    assert {k: body[k] for k in core} == core
    assert body["model_id"] == 7 and body["saved_model"] is None
    # the other finder's fields take their defaults: null or empty, never missing
    other = set(DiagnosisOut.model_fields) - set(core) - set(SERVICE_FIELDS)
    assert all(body[k] in (None, "", [], {}) for k in other), other
