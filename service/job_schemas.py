"""The status every background job answers with (simulations, coefficient fits, ``/v1/jobs``,
the 202 of a physics job).
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel

JobStatus = Literal["queued", "running", "done", "failed", "cancelled"]


class JobStatusOut(BaseModel):
    """What every job answer says of the job: id, name, status, progress (0-1), message and
    error (simulations, coefficient fits, ``/v1/jobs``, the 202 of a physics job)."""

    id: int
    name: str | None
    status: JobStatus
    progress: float
    message: str | None = None
    error: str | None = None
