"""The FastAPI application: ``create_app()`` wires the database, security, limits, error
handlers, jobs and routers.

Every router in :data:`ROUTERS` is served under ``/v1`` behind the API-key dependency
(:func:`wearcast.service.auth.require_key`); only ``/v1/health`` is open. The middleware of
:mod:`wearcast.service.middleware` and the problem-details handlers of
:mod:`wearcast.service.errors` apply to every route, and :func:`problem_openapi` publishes
the error answers of every operation.
"""

from __future__ import annotations

import logging
from typing import Any

from fastapi import Depends, FastAPI
from fastapi.openapi.utils import get_openapi

from wearcast.service.db import Database
from wearcast.service.errors import PROBLEM_MEDIA_TYPE, Problem, install_handlers
from wearcast.service.id_text import INT64_MAX, INT64_MIN
from wearcast.service.middleware import MAX_QUERY_VALUE_CHARS
from wearcast.service.settings import Settings

log = logging.getLogger(__name__)
#: Error statuses any operation can answer, and those of secured operations only.
COMMON_ERRORS = {400: "Malformed request", 404: "Not found", 405: "Method not allowed",
                 409: "Conflict with stored data", 413: "A size limit was passed",
                 422: "Input that cannot be used (the fields and reasons)",
                 500: "Server failure", 503: "Database busy or unavailable"}
SECURED_ERRORS = {401: "No valid API key", 403: "The key lacks the scope (or a cross-site "
                  "write)", 429: "Rate limit; see Retry-After"}


def _router_modules() -> list[Any]:
    from wearcast.service.routers import (
        admin,
        coefficient_fits,
        contact,
        jobs,
        measurements,
        models,
        planning,
        rails,
        references,
        routes,
        simulations,
        wear_tables,
    )

    return [measurements, routes, wear_tables, models, simulations, coefficient_fits, rails,
            planning, references, jobs, admin, contact]


def create_app(settings: Settings | None = None, *, migrate: bool = True) -> FastAPI:
    """An app serving the ``/v1`` contract on the database named by ``settings``.

    ``migrate`` brings the schema to the newest revision first (the only way it is created).
    With ``migrate`` the app is taken to be the one process serving the database: jobs left
    running by a previous process are queued again (or failed after a second interruption)
    and queued ones are started (:class:`wearcast.service.jobs.JobRunner`; with several
    processes the runners' sweeps find lost jobs by their heartbeat), and an admin key is
    made sure to exist (``WEARCAST_API_KEY``, or one created and printed on the first
    start).
    """
    from fastapi.middleware.cors import CORSMiddleware

    from wearcast.service import job_store
    from wearcast.service.admin_store import clear_caches
    from wearcast.service.auth import KeyCache, bootstrap_admin_key, require_key
    from wearcast.service.housekeeping import clean_after_restart, stop_import_workers
    from wearcast.service.jobs import JobRunner
    from wearcast.service.middleware import (
        AuditTrail,
        ProblemGuard,
        RateLimiter,
        RequestGuard,
        check_request_values,
    )
    from wearcast.service.removal_watch import RemovalWatch
    from wearcast.service.routers import health

    settings = settings or Settings()
    database = Database(settings)
    if migrate:
        database.migrate()
    if migrate:  # (``wearcast serve`` does this before starting worker processes)
        bootstrap_admin_key(database.session_factory, settings)
    app = FastAPI(title="wearcast", version="0.1.0",
                  description="Wheel-profile wear and reprofiling-mileage prediction. Every "
                  "route but /v1/health needs 'Authorization: Bearer <API key>'; errors are "
                  "RFC 9457 problem details (application/problem+json).")
    app.state.database = database
    app.state.settings = settings
    app.state.key_cache = KeyCache()
    app.state.rate_limiter = RateLimiter(settings.rate_limit_per_second,
                                         settings.rate_limit_burst)
    runner = JobRunner(database, settings)
    app.state.jobs = runner
    app.state.simulations = runner  # the name the simulation and fit routes use
    if migrate:  # this process starts the service: jobs left running by the last one died
        clean_after_restart(database.session_factory, settings.data_dir)
        runner.recover(all_running=True)
        if job_store.queued_ids(database.session_factory):
            runner.start()
    app.router.add_event_handler("startup", runner.start)
    app.router.add_event_handler("shutdown", runner.shutdown)
    app.router.add_event_handler("shutdown", stop_import_workers)
    removals = RemovalWatch(database.session_factory, clear_caches)
    app.state.removal_watch = removals
    app.router.add_event_handler("startup", removals.start)
    app.router.add_event_handler("shutdown", removals.stop)
    install_handlers(app)
    app.include_router(health.router, prefix="/v1")
    secured = [Depends(require_key), Depends(check_request_values)]
    for module in _router_modules():
        app.include_router(module.router, prefix="/v1", dependencies=secured)
    app.add_middleware(AuditTrail, factory=database.session_factory)
    app.add_middleware(RequestGuard, settings=settings)
    if settings.cors_origins:
        app.add_middleware(CORSMiddleware, allow_origins=settings.cors_origins,
                           allow_methods=["GET", "POST", "DELETE"],
                           allow_headers=["Authorization", "Content-Type", "Idempotency-Key"],
                           expose_headers=["Retry-After", "X-Request-ID"])
    mount_planner(app)
    app.add_middleware(ProblemGuard)
    app.openapi = lambda: problem_openapi(app)  # type: ignore[method-assign]
    return app


INT64 = (INT64_MIN, INT64_MAX)
#: A string without NUL bytes (ECMA-262 and Python regular expressions read it alike).
NO_NUL_PATTERN = "^[^\\x00]*$"


def _bound_integers(schema: Any) -> None:
    """Publish the 64-bit range on every integer without bounds (the server refuses others),
    and every integer's bounds as integers inside that range: pydantic writes ``le=2**63 - 1``
    as the float 9.223372036854776e18, which is 2**63, so a client reading the schema would
    take integers the server refuses for one."""
    if isinstance(schema, dict):
        if schema.get("type") == "integer":
            schema.setdefault("minimum", INT64[0])
            schema.setdefault("maximum", INT64[1])
            for key in ("minimum", "maximum"):
                bound = schema[key]
                if isinstance(bound, float) and bound.is_integer():
                    schema[key] = min(max(int(bound), INT64[0]), INT64[1])
        for value in schema.values():
            _bound_integers(value)
    elif isinstance(schema, list):
        for value in schema:
            _bound_integers(value)


def _bound_strings(schema: Any, max_length: int) -> None:
    """Publish the longest path or query value the request guard lets through, and that it
    holds no NUL byte (the guard refuses those too)."""
    if isinstance(schema, dict):
        if schema.get("type") == "string":
            schema["maxLength"] = min(schema.get("maxLength", max_length), max_length)
            if "format" not in schema and "enum" not in schema:
                schema.setdefault("pattern", NO_NUL_PATTERN)
        for key in ("anyOf", "oneOf", "allOf"):
            for value in schema.get(key, []):
                _bound_strings(value, max_length)


def problem_openapi(app: FastAPI) -> dict[str, Any]:
    """The OpenAPI document with every error answer of every operation published as
    ``application/problem+json`` (:class:`wearcast.service.errors.Problem`)."""
    if app.openapi_schema:
        return app.openapi_schema
    schema = get_openapi(title=app.title, version=app.version, description=app.description,
                         routes=app.routes)
    components = schema.setdefault("components", {}).setdefault("schemas", {})
    problem_schema = Problem.model_json_schema(ref_template="#/components/schemas/{model}")
    for name, definition in problem_schema.pop("$defs", {}).items():
        components[name] = definition
    components["Problem"] = problem_schema
    for name in ("HTTPValidationError", "ValidationError"):
        components.pop(name, None)
    ref = {"$ref": "#/components/schemas/Problem"}
    settings: Settings = app.state.settings
    for definition in components.values():
        _bound_integers(definition)
    for path, operations in schema.get("paths", {}).items():
        for operation in operations.values():
            if not isinstance(operation, dict) or "responses" not in operation:
                continue
            for parameter in operation.get("parameters", []):
                _bound_integers(parameter.get("schema", {}))
                _bound_strings(parameter.get("schema", {}), settings.max_id_length
                               if parameter.get("in") == "path" else MAX_QUERY_VALUE_CHARS)
            statuses = dict(COMMON_ERRORS)
            if operation.get("security"):
                statuses |= SECURED_ERRORS
            if path == "/v1/health":
                statuses = {503: COMMON_ERRORS[503], 405: COMMON_ERRORS[405],
                            400: COMMON_ERRORS[400], 422: COMMON_ERRORS[422],
                            500: COMMON_ERRORS[500]}
            responses = operation["responses"]
            for status, description in statuses.items():
                key = str(status)
                responses[key] = {"description": responses.get(key, {}).get("description")
                                  or description,
                                  "content": {PROBLEM_MEDIA_TYPE: {"schema": ref}}}
                if status in (429, 503):
                    responses[key]["headers"] = {"Retry-After": {
                        "description": "seconds to wait", "schema": {"type": "integer"}}}
    app.openapi_schema = schema
    return schema


def mount_planner(app: FastAPI) -> None:
    """The planner web page (plain HTML and JavaScript, no build step) at ``/planner/``."""
    from pathlib import Path

    from fastapi.staticfiles import StaticFiles

    static = Path(__file__).parent / "static" / "planner"
    app.mount("/planner", StaticFiles(directory=static, html=True), name="planner")
