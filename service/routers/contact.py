"""``/v1/contact``: the loaded wheel-rail contact of one wheel at given poses.

A plain ``def``: FastAPI runs it in its threadpool (2-9 ms of one core per pose on
S1002/60E1, ~0.15 s with the fine boundary-element grid: ``benchmarks/contact_method_cost.py``).
"""

from __future__ import annotations

from fastapi import APIRouter

from wearcast.service import contact_store
from wearcast.service.contact_schemas import ContactIn, ContactOut
from wearcast.service.deps import SessionDep, SettingsDep
from wearcast.service.errors import LimitExceeded

router = APIRouter(tags=["contact"])


@router.post("/contact", response_model=ContactOut)
def compute_contact(body: ContactIn, session: SessionDep, settings: SettingsDep) -> ContactOut:
    """Contact patches, forces, creepages and pressures of the wheel at each pose (CONTACT's
    wheel-rail module: non-Hertzian normal contact, FASTSIM). The fine boundary-element
    method (``normal_method: bem``) takes at most ``max_fine_bem_poses`` poses (422 naming
    ``poses`` and the limit), so that no request holds a core for more than seconds."""
    limit = settings.max_fine_bem_poses
    if body.normal_method == "bem" and len(body.poses) > limit:
        raise LimitExceeded("poses", "max_fine_bem_poses", limit,
                            f"{len(body.poses)} poses with normal_method bem (the fine "
                            "boundary-element grid); split them over requests or use auto",
                            status=422)
    return contact_store.compute_contact(session, body)
