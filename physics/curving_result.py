"""Result of the quasi-static curving of one bogie (``curving.solve_curving``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from wearcast.physics.bogie_equations import BogieContacts
from wearcast.physics.vocabulary import REGION_SPLIT_Y_MM, SIDES, rail_for

#: Wheel-frame lateral position separating flange (y < split) from tread [mm]: the vocabulary's.
FLANGE_SPLIT_Y_MM = REGION_SPLIT_Y_MM


@dataclass(frozen=True)
class CurvingResult(BogieContacts):
    """Quasi-static curving solution of one bogie: the bogie equations' per-contact
    quantities (:class:`~wearcast.physics.bogie_equations.BogieContacts`) at the equilibrium,
    plus the state, the operating point and the wear measures.

    State: ``wheelset_shift_mm`` (2,) of the wheelset centres (+ = left), ``contact_shift_mm``
    (2,) the same at rail level (the contact frame; differs by r0 times the roll),
    ``wheelset_roll_rad`` (2,) (+ = left wheel up), ``wheelset_yaw_rad`` (2,) (relative to the
    local track tangent, + = nose left), ``rolling_ratio`` (2,) Omega r0/V, ``bogie_shift_mm``,
    ``bogie_yaw_rad``. Per contact, arrays of shape (2 axles, 2 sides (left, right), 3 patch
    slots, field side first; the region follows from ``wheel_y_mm``): normal force [N],
    contact angle [rad], position on the wheel (wheel frame)
    and rail (rail frame) [mm], lateral distance from the track centre [mm], rolling radius
    [m], creepages xi, eta [-], phi [1/mm] and creep forces Fx, Fy [N], spin moment Mz [N mm]
    (each wheel in its own frame, lateral towards its field side), Hertz semi-axes a, b [mm] and
    p0 [MPa], and from FASTSIM on this state tau_max [MPa] and T_gamma [N]; ``in_contact`` marks
    loaded patches. Also: the operating point, ``high_rail_side`` (None on tangent track) and the
    residual norm of the scaled equilibrium and the solver ``state`` (scaled unknowns, used to
    continue from this solution); ``saturation_state`` the equilibrium of the smooth saturation
    law the solve went through (the start of the Newton solution with FASTSIM's forces; equal
    to ``state`` without them), the warm start of a later solve (``initial_states``), which
    runs the saturation law first; ``creep_grid`` the FASTSIM grid of the equilibrium's creep
    forces (None: the saturation law, ``contact.creep``).

    ``pipeline`` (with ``contact_pipeline=True``, else None): the contacts of the one contact
    pipeline (``curving_contacts``) at this equilibrium's pose of every wheel, same shape and
    signs as above, keyed by the per-contact field names of this class (those of
    ``bogie_equations.BogieContacts``: ``normal_force_n``, ``contact_angle_rad``, ``xi``,
    ``eta``, ``phi_per_mm``, ``fx_n``, ``fy_n``, ``mz_nmm``, ``a_mm``, ``b_mm``,
    ``rolling_radius_m``, ``wheel_y_mm``, ``rail_y_mm``, ``lateral_position_mm``) plus
    ``peak_pressure_mpa``, ``tau_max_mpa``, ``t_gamma_n``,
    ``in_contact``, and the pose it was evaluated at: ``state`` (as ``state``),
    ``wheelset_shift_mm``, ``wheelset_roll_rad``, ``wheelset_yaw_rad`` (2,) (the table's, or
    with ``pipeline_equilibrium`` the equilibrium of the pipeline's forces);
    ``pipeline_residual_norm`` the scaled bogie equilibrium residual there with the pipeline's
    forces in place of the table's (the vertical rows the table's).
    """

    radius_m: float
    direction: str
    cant_mm: float
    speed_m_s: float
    unbalanced_acceleration_m_s2: float
    wheelset_shift_mm: NDArray
    contact_shift_mm: NDArray
    wheelset_roll_rad: NDArray
    wheelset_yaw_rad: NDArray
    rolling_ratio: NDArray
    bogie_shift_mm: float
    bogie_yaw_rad: float
    p0_mpa: NDArray
    tau_max_mpa: NDArray
    t_gamma_n: NDArray
    in_contact: NDArray
    residual_norm: float
    state: NDArray
    saturation_state: NDArray | None = None
    creep_grid: int | None = None
    pipeline: dict[str, NDArray] | None = None
    pipeline_residual_norm: float = float("nan")

    @property
    def high_rail_side(self) -> str | None:
        """Side of the wheels on the high rail: right in a left curve (docs/conventions.md)."""
        if not np.isfinite(self.radius_m):
            return None
        return "right" if self.direction == "left" else "left"

    def rail_of(self, side: str) -> str:
        """``high``, ``low`` or ``tangent`` for the wheels on ``side`` (vocabulary.rail_for)."""
        return rail_for(None if not np.isfinite(self.radius_m) else self.direction,  # type: ignore[arg-type]
                        side)  # type: ignore[arg-type]

    @property
    def flange_contact(self) -> NDArray:
        """(2 axles, 2 sides): the wheel has a loaded patch on its flange (y < -30 mm)."""
        return np.any(self.in_contact & (self.wheel_y_mm < FLANGE_SPLIT_Y_MM), axis=-1)


    def leading_high_rail_patch(self, source: str = "table") -> dict[str, float]:
        """The most loaded patch of the leading wheelset's high-rail wheel (a curve only):
        every per-contact field at that patch, from the curving's own contacts (``table``) or
        from the one contact pipeline's at its pose (``pipeline``; needs ``contact_pipeline``
        in ``solve_curving``). Units as the fields' (N, rad, mm, MPa)."""
        side = self.high_rail_side
        if side is None:
            raise ValueError("radius_m: tangent track has no high rail")
        if source == "table":
            values = {f: getattr(self, f) for f in self.__dataclass_fields__}
        elif source == "pipeline":
            if self.pipeline is None:
                raise ValueError("source: solved without contact_pipeline")
            values = dict(self.pipeline)
        else:
            raise ValueError(f"source must be 'table' or 'pipeline', got {source!r}")
        # the per-contact fields: (2 axles, 2 sides, slots)
        contacts = {f: a for f, a in ((f, np.asarray(v)) for f, v in values.items())
                    if a.ndim == 3 and a.shape[:2] == (2, 2)}
        high = SIDES.index(side)
        k = int(np.argmax(contacts["normal_force_n"][0, high]))
        return {f: float(a[0, high, k]) for f, a in contacts.items()}
