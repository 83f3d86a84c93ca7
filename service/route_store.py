"""Railway routes in storage: create (from curve classes or segments), list, resolve by id or name.

The curve classes and their validation come from :mod:`wearcast.statistics.routes`
(segments are binned as in seed 003 §5.3).
"""

from __future__ import annotations

from typing import Any

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from wearcast.service import models_db as db
from wearcast.service.errors import Conflict, NotFound, Unprocessable, from_value_error
from wearcast.service.id_text import decimal_id
from wearcast.service.route_schemas import RouteIn, RouteOut, RouteSpec
from wearcast.statistics import routes as stat_routes


def build_route(spec: RouteSpec, name: str, field: str = "") -> stat_routes.Route:
    """The statistics-core route for a request's classes or segments (422 naming the field)."""
    try:
        if spec.classes is not None:
            classes = []
            for i, c in enumerate(spec.classes):
                try:
                    classes.append(stat_routes.RouteClass(**c.model_dump()))
                except ValueError as exc:
                    raise from_value_error(exc, f"{field}classes[{i}]".lstrip(".")) from exc
            return stat_routes.Route(name=name, classes=tuple(classes))
        segments = [s.model_dump() for s in spec.segments or []]
        return stat_routes.route_from_segments(segments, name=name)
    except ValueError as exc:
        raise from_value_error(exc, field.rstrip(".")) from exc


def loop_classes(classes: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Stored classes as the wear loop's jobs take them (a tangent's direction ``left``,
    unused)."""
    return [{k: c.get(k) for k in ("radius_m", "cant_mm", "speed_kmh", "direction", "share")}
            | {"direction": c.get("direction") or "left"} for c in classes]


def rebinned_classes(segments: list[dict[str, Any]], n_class: int,
                     field: str = "curve_classes") -> list[dict[str, Any]]:
    """A stored route's segments binned into ``n_class`` classes as :func:`create_route` bins
    them (``route_from_segments``' defaults otherwise), in the loop's form
    (:func:`loop_classes`)."""
    try:
        route = stat_routes.route_from_segments(segments, n_class=int(n_class))
    except ValueError as exc:
        raise Unprocessable(field, str(exc)) from exc
    return loop_classes([c.to_dict() for c in route.classes])


def create_route(session: Session, body: RouteIn) -> db.Route:
    """Store a route; 409 when its name is taken."""
    route = build_route(body, body.name)
    if session.scalar(select(db.Route.id).where(db.Route.name == body.name)) is not None:
        raise Conflict("name", f"a route named {body.name!r} exists already")
    row = db.Route(
        name=body.name,
        classes=[c.to_dict() for c in route.classes],
        segments=[s.model_dump() for s in body.segments] if body.segments else None,
        attributes=body.attributes,
    )
    session.add(row)
    try:
        session.commit()
    except IntegrityError as exc:
        session.rollback()
        raise Conflict("name", f"a route named {body.name!r} exists already") from exc
    return row


def find_route(session: Session, id_or_name: int | str) -> db.Route | None:
    """A stored route by its id (an int or a string of digits) or its unique name."""
    number = id_or_name if isinstance(id_or_name, int) else decimal_id(id_or_name)
    if number is not None:
        row = session.get(db.Route, number)
        if row is not None:
            return row
    return session.scalar(select(db.Route).where(db.Route.name == str(id_or_name)))


def get_route(session: Session, id_or_name: int | str, field: str = "route_id") -> db.Route:
    row = find_route(session, id_or_name)
    if row is None:
        raise NotFound(field, f"no route with id or name {id_or_name!r}")
    return row


def to_domain(row: db.Route) -> stat_routes.Route:
    return stat_routes.Route.from_dict({"name": row.name, "classes": row.classes})


def resolve(session: Session, route_id: int | str | None, route: RouteSpec | None,
            ) -> tuple[stat_routes.Route, db.Route | None]:
    """The route a request names (by id/name) or gives inline."""
    if route_id is not None:
        row = get_route(session, route_id)
        return to_domain(row), row
    if route is None:
        raise Unprocessable("route_id", "give either route_id or route")
    return build_route(route, "inline", "route."), None


def list_routes(session: Session) -> list[db.Route]:
    return list(session.scalars(select(db.Route).order_by(db.Route.id)))


def route_out(row: db.Route) -> RouteOut:
    data: dict[str, Any] = {"id": row.id, "name": row.name, "classes": row.classes,
                            "segments": row.segments, "attributes": row.attributes or {}}
    return RouteOut.model_validate(data)
