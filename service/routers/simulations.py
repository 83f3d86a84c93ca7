"""``/v1/simulations``: wear-loop simulations run as background jobs with progress.

``POST`` validates the request, stores it as a queued job and answers 202 at once; a worker
of the app's :class:`~wearcast.service.jobs.JobRunner` runs it and
writes its progress; ``GET /v1/simulations/{id}`` reads status, progress, error and, once
done, the result.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Request

from wearcast.service import simulation_store
from wearcast.service.deps import SessionDep
from wearcast.service.simulation_schemas import SimulationIn, SimulationOut

router = APIRouter(tags=["simulations"])


@router.post("/simulations", response_model=SimulationOut, status_code=202)
def create_simulation(body: SimulationIn, session: SessionDep,
                      request: Request) -> SimulationOut:
    """Queue a wear-loop simulation; poll ``GET /v1/simulations/{id}`` for its progress."""
    return simulation_store.submit(session, request.app.state.simulations, body)


@router.get("/simulations", response_model=list[SimulationOut])
def list_simulations(session: SessionDep,
                     limit: Annotated[int, Query(ge=1, le=1000)] = 100) -> list[SimulationOut]:
    """The newest simulations first, without their results."""
    return simulation_store.list_simulations(session, limit)


@router.get("/simulations/{simulation_id}", response_model=SimulationOut)
def get_simulation(simulation_id: int, session: SessionDep,
                   include_result: bool = True) -> SimulationOut:
    return simulation_store.get_simulation(session, simulation_id, include_result)
