"""``/v1/routes``: railway routes as curve classes or segments."""

from __future__ import annotations

from fastapi import APIRouter, Response

from wearcast.service import route_store
from wearcast.service.deps import SessionDep
from wearcast.service.json_response import json_response
from wearcast.service.route_schemas import RouteIn, RouteOut

router = APIRouter(tags=["routes"])


@router.post("/routes", response_model=RouteOut, status_code=201)
def create_route(body: RouteIn, session: SessionDep) -> RouteOut:
    return route_store.route_out(route_store.create_route(session, body))


@router.get("/routes", response_model=list[RouteOut])
def list_routes(session: SessionDep) -> Response:
    return json_response([route_store.route_out(row)
                          for row in route_store.list_routes(session)])


@router.get("/routes/{id_or_name}", response_model=RouteOut)
def get_route(id_or_name: str, session: SessionDep) -> Response:
    return json_response(route_store.route_out(
        route_store.get_route(session, id_or_name, "id_or_name")))
