"""A measured wheel profile sent in a request, and the measured wheel and rail a physics request
may use in place of the preset's S1002 on its nominal rail.
"""

from __future__ import annotations

from pydantic import Field, model_validator

from wearcast.service.schema_base import (
    MAX_PROFILE_POINTS,
    StoredId,
    Strict,
    at_most_one,
)


class MeasuredProfileIn(Strict):
    """A measured wheel profile given as points in the wheel frame [mm] (y from the tape
    circle, back face at -70; z up, 0 at the tape circle), placed by its own datum."""

    y_mm: list[float] = Field(min_length=20, max_length=MAX_PROFILE_POINTS)
    z_mm: list[float] = Field(min_length=20, max_length=MAX_PROFILE_POINTS)
    mileage_km: float = Field(0.0, ge=0)
    reference_profile: str = "S1002"


class RailIdIn(Strict):
    """The stored measured rail a physics request may lay in place of the preset's nominal
    rail."""

    rail_id: StoredId | None = Field(default=None, description=(
        "a stored measured rail (GET /v1/rails) in place of the preset's nominal rail, on "
        "both sides, placed by its gauge point"))


class MeasuredProfilesIn(RailIdIn):
    """The measured wheel and rail a physics request may use instead of the preset's S1002 on
    its nominal rail (``POST /v1/wear-tables/compute``, ``POST /v1/simulations``)."""

    measurement_id: StoredId | None = Field(default=None, description=(
        "a stored profile measurement whose wheel replaces the preset's S1002 on every wheel "
        "(a table) or starts the simulated wheel (a simulation), placed by the instrument's "
        "datum when the import found one"))
    wheel_id: str | None = Field(default=None, min_length=1, max_length=200, description=(
        "as measurement_id, with the wheel's latest measured profile"))
    profile: MeasuredProfileIn | None = Field(default=None, description=(
        "as measurement_id, with a profile sent in the request"))

    @model_validator(mode="after")
    def _at_most_one_wheel(self) -> MeasuredProfilesIn:
        at_most_one(self, "wheel_id", "measurement_id", "profile")
        return self


class TrackRailIdsIn(RailIdIn):
    """:class:`RailIdIn` with a high and a low rail of their own, for the requests that run a
    vehicle through curves (``POST /v1/wear-tables/compute``, ``POST /v1/simulations``,
    ``POST /v1/models`` with ``kind: "physics"``; not the one-wheel contact, which takes one
    rail). ``service.rail_store.requested_rails`` resolves and checks all three."""

    high_rail_id: StoredId | None = Field(default=None, description=(
        "a stored measured rail as the high (outer) rail of every curve, placed by its gauge "
        "point; the low rail is low_rail_id, else rail_id, else the preset's nominal rail; "
        "tangent track runs on rail_id (or the nominal rail)"))
    low_rail_id: StoredId | None = Field(default=None, description=(
        "as high_rail_id, the low (inner) rail of every curve"))


class TrackRailsIn(MeasuredProfilesIn, TrackRailIdsIn):
    """:class:`MeasuredProfilesIn` with a high and a low rail of their own
    (:class:`TrackRailIdsIn`) for the requests that run one wheel's evolution or a table
    through curves (``POST /v1/wear-tables/compute``, ``POST /v1/simulations``)."""
