"""Request and response bodies of the discrepancy diagnosis (``POST /v1/models/{id}/diagnose``).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field, model_validator

from wearcast.physics.vocabulary import (
    BogieType,
    Region,
    Wheelset,
)
from wearcast.service.dataclass_schemas import from_dataclass, from_dataclasses
from wearcast.service.model_schemas import ModelOut
from wearcast.service.schema_base import FieldsError, Filter, Strict
from wearcast.statistics.discrepancy import Diagnosis
from wearcast.statistics.findings import Finding, Gain
from wearcast.statistics.physics_diagnosis import PhysicsDiagnosis


class ProgressionAreasIn(Strict):
    bogie_type: BogieType
    wheelset: Wheelset
    region: Region
    areas_mm2: list[float] = Field(min_length=2, max_length=10_000, description=(
        "simulated wear area at each of mileage_km [mm²]"))


class ExpectedProgressionIn(Strict):
    """The wear-area progression a simulation of the route expects (e.g. a wear-loop
    simulation's areas per step): the finder's baseline then grows as it does instead of
    linearly in mileage (``statistics.discrepancy_progression``)."""

    mileage_km: list[float] = Field(min_length=2, max_length=10_000)
    areas: list[ProgressionAreasIn] = Field(min_length=1, max_length=64)

    @model_validator(mode="after")
    def _same_lengths(self) -> ExpectedProgressionIn:
        for i, a in enumerate(self.areas):
            if len(a.areas_mm2) != len(self.mileage_km):
                raise FieldsError([f"areas[{i}].areas_mm2"],
                                  f"areas[{i}].areas_mm2 has {len(a.areas_mm2)} values for "
                                 f"{len(self.mileage_km)} mileages")
        return self


class DiagnoseIn(Strict):
    """``POST /v1/models/{id}/diagnose``.

    ``filter`` selects the measurements to diagnose (default: every profile measurement on a
    stored route); the model's calibration measurements are always added (flagged as such).
    ``save_as`` stores the model extended by the verdict's cause as a new model.
    """

    filter: Filter = Field(default_factory=dict)
    save_as: str | None = Field(default=None, min_length=1, max_length=200)
    causes: list[str] | None = Field(default=None, min_length=1, description=(
        "cause codes to try (default: the whole catalogue)"))
    seed: int = Field(default=0, ge=0, description="random seed of the folds and bootstrap")
    expected_progression: ExpectedProgressionIn | None = Field(default=None, description=(
        "a simulated wear-area progression of the route per bogie type, wheelset and region "
        "(hybrid models): the null grows as it does instead of linearly in mileage"))
    expected_progression_simulations: list[int] | None = Field(
        default=None, min_length=1, max_length=32, description=(
            "ids of finished wear-loop simulations of the route (POST /v1/simulations, one per "
            "bogie type and axle, e.g. both sides): the expected progression is derived from "
            "their wear areas (statistics.discrepancy_progression.progression_from_simulations)"))

    @model_validator(mode="after")
    def _one_progression(self) -> DiagnoseIn:
        if self.expected_progression is not None and \
                self.expected_progression_simulations is not None:
            raise FieldsError(["expected_progression", "expected_progression_simulations"],
                              "give expected_progression or expected_progression_simulations, "
                              "not both")
        return self


@from_dataclass(Gain)
class GainOut(BaseModel):
    """A finding's gain: the fields of ``statistics.findings.Gain``."""


@from_dataclass(Finding)
class FindingOut(BaseModel):
    """One cause the finder tried: the fields of ``statistics.findings.Finding``."""


class _DataOut(BaseModel):
    """The service's own fields on what the finder was given (in the answer after the hybrid
    result's fields)."""

    excluded: dict[str, int] = Field(default_factory=dict, description=(
        "measurements left out, by reason"))
    expected_progression: dict[str, Any] | None = Field(default=None, description=(
        "the null's expected progression when one was given: its source and the factor "
        "g = A / (k s) per bogie type/wheelset/region at its mileages; null: linear in mileage"))


class _SavedOut(BaseModel):
    """The service's own fields on ``save_as`` (last in the answer)."""

    saved_model: ModelOut | None = None
    save_reason: str | None = Field(default=None, description="why save_as saved nothing")


# The answer of both finders (hybrid and physics models): the model's id, then every published
# field of ``discrepancy.Diagnosis`` and ``physics_diagnosis.PhysicsDiagnosis`` (their shared
# ``findings.FinderResult`` first), typed, defaulted and described by the dataclasses
# (``dataclass_schemas.from_dataclasses``), with the service's own fields among them. No
# docstring: the published schema has no description.
@from_dataclasses(Diagnosis, _DataOut, PhysicsDiagnosis, _SavedOut)
class DiagnosisOut(BaseModel):
    model_id: int
