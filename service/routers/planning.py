"""``/v1/fleets``, ``/v1/vehicles``, ``/v1/fleet``, ``/v1/plans``: maintenance planning.

Fleet limits and vehicle attributes (PUT), the fleet state (every wheel's latest state,
remaining km to each limit and the dates; JSON or CSV), one wheel's history, forecast,
profile and turning options, and lathe plans (POST to compute and store; GET as JSON or CSV).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Response

from wearcast.service import planning_store
from wearcast.service.deps import SessionDep
from wearcast.service.id_text import decimal_id
from wearcast.service.planning_schemas import FleetIn, PlanIn, VehicleIn
from wearcast.service.schema_base import IsoDate

router = APIRouter(tags=["planning"])
Format = Literal["json", "csv"]
#: ``format=csv`` answers ``text/csv``: published beside the JSON answer.
_CSV_ANSWER: dict[int | str, dict[str, Any]] = {
    200: {"content": {"text/csv": {"schema": {"type": "string"}}}}}


def _route_ref(value: str | None) -> int | str | None:
    number = None if value is None else decimal_id(value)
    return value if number is None else number


@router.put("/fleets/{fleet_id}")
def put_fleet(fleet_id: str, body: FleetIn, session: SessionDep) -> dict[str, Any]:
    return planning_store.put_fleet(session, fleet_id, body)


@router.get("/fleets/{fleet_id}")
def get_fleet(fleet_id: str, session: SessionDep) -> dict[str, Any]:
    return planning_store.get_fleet(session, fleet_id)


@router.put("/vehicles/{vehicle_id}")
def put_vehicle(vehicle_id: str, body: VehicleIn, session: SessionDep) -> dict[str, Any]:
    return planning_store.put_vehicle(session, vehicle_id, body)


@router.get("/fleet/state", response_model=None, responses=_CSV_ANSWER)
def fleet_state(session: SessionDep, fleet_id: str | None = None,
                model_id: int | None = None, route_id: str | None = None,
                today: IsoDate | None = None, format: Format = "json"
                ) -> dict[str, Any] | Response:
    """Every wheel's latest state and remaining km to each limit (P10/P50/P90) and dates."""
    payload = planning_store.state_payload(session, fleet_id, model_id, _route_ref(route_id),
                                           today)
    if format == "csv":
        return Response(planning_store.state_csv(payload), media_type="text/csv")
    return payload


@router.get("/fleet/wheels/{wheel_id}")
def wheel_detail(wheel_id: str, session: SessionDep, fleet_id: str | None = None,
                 model_id: int | None = None, route_id: str | None = None,
                 today: IsoDate | None = None) -> dict[str, Any]:
    """One wheel: history, forecast lines, latest profile over its targets, turning options."""
    return planning_store.wheel_detail(session, wheel_id, fleet_id, model_id,
                                       _route_ref(route_id), today)


@router.post("/plans", status_code=201)
def create_plan(body: PlanIn, session: SessionDep) -> dict[str, Any]:
    return planning_store.create_plan(session, body)


@router.get("/plans")
def list_plans(session: SessionDep) -> list[dict[str, Any]]:
    return planning_store.list_plans(session)


@router.get("/plans/{plan_id}", response_model=None, responses=_CSV_ANSWER)
def get_plan(plan_id: int, session: SessionDep,
             format: Annotated[Format, Query()] = "json") -> dict[str, Any] | Response:
    plan = planning_store.get_plan(session, plan_id)
    if format == "csv":
        return Response(planning_store.plan_csv(plan), media_type="text/csv",
                        headers={"Content-Disposition":
                                 f'attachment; filename="plan-{plan_id}.csv"'})
    return plan
