"""Request and response bodies of routes (``/v1/routes``): curve classes or segments.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar, Self

from pydantic import BaseModel, Field, field_validator, model_validator

from wearcast.physics.vocabulary import Direction
from wearcast.service.schema_base import FieldsError, Strict, exactly_one


class _CurveNeedsDirection(Strict):
    """A curve (``radius_m`` given) names the side it bends towards; a tangent need not."""

    if TYPE_CHECKING:  # the fields are the subclasses' (their order stays theirs)
        radius_m: float | None
        direction: Direction | None
    #: What one item is called in the error message.
    _item: ClassVar[str] = "a curve"

    @model_validator(mode="after")
    def _direction_for_curves(self) -> Self:
        if self.radius_m is not None and self.direction is None:
            raise FieldsError(["direction"],
                              f"{self._item} (radius_m given) needs a direction: left or right")
        return self


class RouteClassIn(_CurveNeedsDirection):
    _item: ClassVar[str] = "a curve class"

    radius_m: float | None = Field(default=None, gt=0, description="radius [m]; null = tangent")
    direction: Direction | None = Field(default=None, description="side the track bends towards")
    cant_mm: float = Field(default=0.0, ge=0, le=250, description="cant [mm]")
    speed_kmh: float = Field(gt=0, le=500, description="running speed [km/h]")
    share: float = Field(ge=0, le=1, description="share of the route's length [-]")


class SegmentIn(_CurveNeedsDirection):
    _item: ClassVar[str] = "a curved segment"

    length_m: float = Field(gt=0, description="segment length [m]")
    radius_m: float | None = Field(default=None, gt=0, description="radius [m]; null = tangent")
    direction: Direction | None = None
    cant_mm: float = Field(default=0.0, ge=0, le=250)
    speed_kmh: float = Field(gt=0, le=500)


class RouteSpec(Strict):
    """A route given inline: curve classes or segments (exactly one of them)."""

    classes: list[RouteClassIn] | None = Field(default=None, min_length=1)
    segments: list[SegmentIn] | None = Field(default=None, min_length=1)
    attributes: dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _one_of(self) -> RouteSpec:
        exactly_one(self, "classes", "segments")
        return self


class RouteIn(RouteSpec):
    name: str = Field(min_length=1, max_length=200)

    @field_validator("name")
    @classmethod
    def _not_numeric(cls, name: str) -> str:
        if name.strip().isdigit():
            raise ValueError("a route name must not be a bare number (numbers are route ids)")
        return name.strip()


class RouteClassOut(BaseModel):
    radius_m: float | None
    direction: str | None
    cant_mm: float
    speed_kmh: float
    share: float


class RouteOut(BaseModel):
    id: int
    name: str
    classes: list[RouteClassOut]
    segments: list[dict[str, Any]] | None = None
    attributes: dict[str, Any]
