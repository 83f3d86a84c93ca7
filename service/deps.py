"""Typed FastAPI dependencies: the request's database session and the settings."""

from __future__ import annotations

from collections.abc import AsyncIterator
from typing import Annotated

from fastapi import Depends, Request
from sqlalchemy.orm import Session
from starlette.concurrency import run_in_threadpool

from wearcast.service.db import Database
from wearcast.service.settings import Settings


def get_database(request: Request) -> Database:
    return request.app.state.database


async def get_session(request: Request) -> AsyncIterator[Session]:
    """A session per request; committed by the route's service call, rolled back otherwise.

    An ``async`` dependency, so that opening and closing the session costs no threadpool
    hop each (a plain generator's entry and exit would each run in the threadpool): making
    a session does no I/O (it connects on first use, in the route's thread), and closing one
    that holds no transaction does none either. A session still in a transaction (a route
    that only read) is closed on the event loop on SQLite — its connection's rollback is a
    call into the local library that waits for nothing — and in the threadpool on other
    databases (a round trip to the server); after an error it is rolled back in the
    threadpool.
    """
    database = request.app.state.database
    session = database.session_factory()
    try:
        yield session
    except BaseException:
        await run_in_threadpool(_close, session, True)
        raise
    if session.in_transaction() and not database.is_sqlite:
        await run_in_threadpool(_close, session, False)
    else:
        session.close()


def _close(session: Session, rollback: bool) -> None:
    try:
        if rollback:
            session.rollback()
    finally:
        session.close()


def get_settings(request: Request) -> Settings:
    return request.app.state.database.settings


SessionDep = Annotated[Session, Depends(get_session)]
DatabaseDep = Annotated[Database, Depends(get_database)]
SettingsDep = Annotated[Settings, Depends(get_settings)]
