"""``/v1/contact``: the loaded wheel-rail contact of one wheel at given poses.

A plain ``def``: FastAPI runs it in its threadpool (0.1-0.5 s of one core per pose).
"""

from __future__ import annotations

from fastapi import APIRouter

from wearcast.service import contact_store
from wearcast.service.contact_schemas import ContactIn, ContactOut
from wearcast.service.deps import SessionDep

router = APIRouter(tags=["contact"])


@router.post("/contact", response_model=ContactOut)
def compute_contact(body: ContactIn, session: SessionDep) -> ContactOut:
    """Contact patches, forces, creepages and pressures of the wheel at each pose (CONTACT's
    wheel-rail module: non-Hertzian normal contact, FASTSIM)."""
    return contact_store.compute_contact(session, body)
