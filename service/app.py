"""The FastAPI application: ``create_app()`` wires the database, error handlers and routers."""

from __future__ import annotations

from fastapi import FastAPI

from wearcast.service.db import Database
from wearcast.service.errors import install_handlers
from wearcast.service.settings import Settings


def create_app(settings: Settings | None = None, *, migrate: bool = True) -> FastAPI:
    """An app serving the ``/v1`` contract on the database named by ``settings``.

    ``migrate`` brings the schema to the newest revision first (the only way it is created)
    and then recovers the simulation jobs of a previous process (running ones are marked
    failed with a reason, queued ones are queued again).
    """
    from wearcast.service.routes import (
        coefficient_fits,
        health,
        measurements,
        models,
        references,
        routes,
        simulations,
        wear_tables,
    )
    from wearcast.service.simulation_store import SimulationRunner

    database = Database(settings or Settings())
    if migrate:
        database.migrate()
    app = FastAPI(title="wearcast", version="0.1.0",
                  description="Wheel-profile wear and reprofiling-mileage prediction")
    app.state.database = database
    runner = SimulationRunner(database.session_factory)
    if migrate:
        runner.recover()  # jobs a previous process left running fail with a reason
    app.state.simulations = runner
    app.router.add_event_handler("shutdown", runner.shutdown)
    install_handlers(app)
    for module in (health, measurements, routes, wear_tables, models, simulations,
                   coefficient_fits, references):
        app.include_router(module.router, prefix="/v1")
    return app
