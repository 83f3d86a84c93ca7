"""``/v1/coefficient-fits``: seed 000's wear-coefficient calibration as background jobs.

``POST`` validates the request (vehicle, route, measured wear or measurement, methods, zones and
bounds), stores it as a queued job and answers 202 at once; the app's job runner (the one of
``/v1/simulations``) fits the coefficients with each method and writes the progress per method;
``GET /v1/coefficient-fits/{id}`` reads status, progress, error and, once done, the comparison
table (seed 000 Table 2), the coefficients and the fitted wear curve.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Request

from wearcast.service import coefficient_fit_store as store
from wearcast.service.deps import SessionDep

router = APIRouter(tags=["coefficient fits"])


@router.post("/coefficient-fits", response_model=store.CoefficientFitOut, status_code=202)
def create_coefficient_fit(body: store.CoefficientFitIn, session: SessionDep,
                           request: Request) -> store.CoefficientFitOut:
    """Queue a calibration; poll ``GET /v1/coefficient-fits/{id}`` for its progress."""
    return store.submit(session, request.app.state.simulations, body)


@router.get("/coefficient-fits", response_model=list[store.CoefficientFitOut])
def list_coefficient_fits(session: SessionDep, limit: Annotated[int, Query(ge=1, le=1000)] = 100
                          ) -> list[store.CoefficientFitOut]:
    """The newest fits first, without their results."""
    return store.list_fits(session, limit)


@router.get("/coefficient-fits/{fit_id}", response_model=store.CoefficientFitOut)
def get_coefficient_fit(fit_id: int, session: SessionDep,
                        include_result: bool = True) -> store.CoefficientFitOut:
    return store.get_fit(session, fit_id, include_result)
