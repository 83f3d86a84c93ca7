"""The physical causes a physics wear model is diagnosed with (issue 12's catalogue).

Each cause is an extension of the whole-vehicle wear loop with ONE physical parameter besides
the fitted wear-coefficient scale, run at a few values (:class:`PhysicsCause`): flange wear
against the tread, friction level, running-direction share, patch model, wear law, traction on
the motor axles, rail state and, for a route stored with its segments, the number of curve
classes. :data:`CATALOGUE` is the default; :func:`catalogue_for` adapts it to a model (its own
friction, traction scale, options and classes). Scored by
:func:`wearcast.statistics.physics_diagnosis.diagnose_physics`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any


@dataclass(frozen=True)
class PhysicsCause:
    """One cause: ``parameter`` of the loop varied over ``values`` (``null`` = the model as
    is; categorical when the values are strings)."""

    name: str
    summary: str
    parameter: str
    values: tuple[Any, ...]
    null: Any
    discrete: bool = False
    scaled_runs: bool = False
    """the values are factors on part of the wear (flange patches): a value above 1 is run at
    the wear scale 1 / value (:meth:`run_scale`), so that its run, made to the null's mileage,
    takes about the null's steps instead of up to ``value`` times as many; its series is read
    at its mileage x the run scale (a run at scale c reaches at m what the scale-1 run
    reaches at c m: ``physics_diagnosis``'s module docstring)"""

    @property
    def categorical(self) -> bool:
        """Each value run on its own, no blends between them: string values, or numbers
        flagged ``discrete`` (a number of curve classes has nothing between two counts)."""
        return self.discrete or any(isinstance(v, str) for v in self.values)

    def run_scale(self, value: Any) -> float:
        """The wear scale ``value``'s loop run is made at [-]: 1 / value for a value above 1
        of a cause with ``scaled_runs``, else 1.

        The wear being mostly the flange's, the fitted scale goes about as 1 / value, so the
        run reaches about as far beyond that value's own fit as the null's run beyond the
        null's, in about the null's steps. A blend between two values reads both runs at one
        scale, between their two fits: the upper value's run is then read up to its lower
        neighbour's scale, which it reaches only where the null's run reaches twice the
        null's fit (values doubling); blends beyond are out of range and the fit takes the
        reachable ones (tried at stop 34: runs at 1 / the lower neighbour gave the Aosta
        answer to 0.1 % of its gain in 3x the steps)."""
        if self.scaled_runs and not isinstance(value, str) and value is not None and value > 1:
            return 1.0 / float(value)
        return 1.0

    def run_params(self, value: Any) -> dict[str, Any]:
        """The parameter set of ``value``'s loop run: {parameter: value}, with
        ``wear_scale`` (a ``VehicleWearOptions`` field) when :meth:`run_scale` is not 1."""
        scale = self.run_scale(value)
        return ({self.parameter: value} if scale == 1.0
                else {self.parameter: value, "wear_scale": scale})


#: Factors of the flange-wear cause on the wear of flange patches: lubricated flanges (0.25,
#: 0.5) and flanges wearing more against the tread than the law's coefficient map gives (2, 4,
#: 8: dry flanges, or a tread whose wear natural contaminants lower, where the USFD map was
#: measured on dry twin discs, seed 003 §4.2). The scale c is refitted with each value, so the
#: factor sets the ratio of flange to tread wear, f x the law's.
FLANGE_WEAR_FACTORS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
#: The catalogue (issue 12): each cause one physical parameter of the loop besides the scale.
CATALOGUE: tuple[PhysicsCause, ...] = (
    PhysicsCause("flange_wear", "the flanges wear otherwise against the tread than the law "
                 "gives: factor on the wear of flange patches, the scale refitted with it "
                 "(below 1: lubricated flanges; above 1: dry flanges, or tread wear lowered by "
                 "natural contaminants the dry twin-disc map leaves out)",
                 "flange_wear_factor", FLANGE_WEAR_FACTORS, 1.0, scaled_runs=True),
    PhysicsCause("friction_level", "the friction coefficient differs from the model's "
                 "(dry/wet, season)", "friction", (0.2, 0.28, 0.4), 0.28),
    PhysicsCause("running_direction_share", "the vehicle does not run half its mileage in "
                 "each direction", "forward_share", (0.5, 0.75, 1.0), 0.5),
    PhysicsCause("patch_model", "the contact patch model (Hertz vs non-Hertzian width)",
                 "patch_width", ("hertz", "kik_piotrowski"), "hertz"),
    PhysicsCause("wear_law", "the wear law and its coefficient map", "law",
                 ("usfd", "archard_kth"), "usfd"),
    PhysicsCause("traction_on_motor_axles", "the motor axles carry a traction torque the model "
                 "leaves out (the line's mean tractive effort): torque per motor axle [N m]",
                 "traction_torque_nm", (0.0, 2000.0, 4000.0), 0.0),
    PhysicsCause("rail_state", "the rail is not new: the rail under the wheels worn by the "
                 "line's own traffic to a tonnage [Mt] (the rail-step model of seed 003 §6.1, "
                 "physics.rail_tonnage)", "rail_tonnage_mt", (0.0, 5.0, 10.0), 0.0),
)
#: Tonnages of the rail-state cause besides the new rail [Mt] (the defaults above; about 1.5
#: and 3 rail steps of 0.8 mm on seed 003's line, 1.4 and 2.8 on the metro test route).
RAIL_TONNAGES_MT = (5.0, 10.0)
#: Parameter of the curve-classes cause: the number of radius (and cant) classes the route's
#: segments are binned into (``statistics.routes.route_from_segments``'s ``n_class``).
CURVE_CLASSES_PARAMETER = "curve_classes"
#: Why the curve-classes cause is skipped when the route has no segments.
NO_SEGMENTS = ("the route is stored as curve classes, not segments: a class table cannot be "
               "re-binned (store the route with its segments to try this cause)")
#: Traction torques of the catalogue as shares of a motor axle's adhesion torque
#: 2 mu Q r (:func:`catalogue_for`); the default values above are about these shares of the
#: Minuetto motor axle's (mu 0.28, Q 57.1 kN, r 0.43 m: 13.7 kN m).
TRACTION_ADHESION_SHARES = (0.0, 0.15, 0.3)


def curve_classes_cause(n_class: int) -> PhysicsCause:
    """The track-description cause of a route binned from its segments into ``n_class``
    classes (seed 003 §5.3): the same segments binned coarser and finer, n_class -/+
    max(1, n_class // 2) (7 -> 4 and 10; at least 1), each level run on its own (discrete);
    the null (None) is the model's own classes."""
    if n_class < 1:
        raise ValueError(f"n_class: must be >= 1, got {n_class}")
    step = max(1, n_class // 2)
    values = tuple(dict.fromkeys(v for v in (n_class - step, n_class + step)
                                 if v >= 1 and v != n_class))
    return PhysicsCause("curve_classes", f"the track description: the route's segments binned "
                        f"into another number of curve classes than the model's {n_class} "
                        "(seed 003 §5.3: radius and cant classes)", CURVE_CLASSES_PARAMETER,
                        (None, *values), None, discrete=True)


def catalogue_for(friction: float, nulls: Mapping[str, Any] | None = None,
                  adhesion_torque_nm: float | None = None,
                  n_class: int | None = None) -> tuple[PhysicsCause, ...]:
    """:data:`CATALOGUE` with the friction level around a vehicle's own coefficient mu (its
    null): 0.7 mu, mu, 1.4 mu (the default catalogue is the Minuetto's, mu = 0.28), and, given
    the motor axle's adhesion torque 2 mu Q r [N m], the traction torques at
    :data:`TRACTION_ADHESION_SHARES` of it.

    ``nulls`` : {parameter: the model's own value} for a model that is not the catalogue's
    default (e.g. ``{"law": "archard_kth", "forward_share": 1.0}``): that value becomes the
    cause's null and is added to the values it is run at.

    ``n_class`` : the model's route was binned from its segments into this many classes: the
    catalogue gains :func:`curve_classes_cause` (without it the cause is skipped,
    :data:`NO_SEGMENTS`)."""
    out = []
    for c in CATALOGUE:
        if c.parameter == "friction":
            c = replace(c, values=(round(0.7 * friction, 4), friction,
                                   round(1.4 * friction, 4)), null=friction)
        if c.parameter == "traction_torque_nm" and adhesion_torque_nm is not None:
            c = replace(c, values=tuple(round(f * adhesion_torque_nm, 1)
                                        for f in TRACTION_ADHESION_SHARES), null=0.0)
        if nulls and c.parameter in nulls and nulls[c.parameter] is not None:
            null = nulls[c.parameter]
            if c.categorical:
                values = (null, *[v for v in c.values if v != null])
            else:
                values = tuple(sorted({float(v) for v in c.values} | {float(null)}))
            c = replace(c, values=values, null=null)
        out.append(c)
    if n_class is not None:
        out.append(curve_classes_cause(n_class))
    return tuple(out)
