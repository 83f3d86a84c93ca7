"""Which physical causes the physics diagnosis names when the whole-vehicle loop hides them.

Run: .venv/bin/python benchmarks/physics_diagnosis_detection.py [--flange-height]
         [--segments] [--vehicles N] [--segment-seed S]
(``--flange-height``: FH measured too, beside FT and qR; ``--segments``: the curve-classes
cause, on a route given by its segments; ``--vehicles``: measured vehicles, default 5)

Truth: ``simulate_vehicle_wear`` (metro_b, a 250 m curve in both directions on 30 % of the
route, USFD, D_step 1 mm, 3,000 km) with one cause injected, a wear scale of 1.2, 5 vehicles
with 4 irregular mileages each (200-1,500 km) and 0.02 mm noise on FT and qR. The diagnosis
(``statistics.physics_diagnosis``) runs the same loop at its catalogue values (flange wear
factor 0.25 / 0.5 / 1, friction 0.3 / 0.4 / 0.5, Hertz / Kik-Piotrowski patch, direction share
0.5 / 1, traction torque on the motor axles 0 / 2,400 / 4,800 N m, the rail new / worn by the
vehicle's own passages to 5 / 10 Mt by ``physics.rail_tonnage``) and prints, per hidden
cause, the verdict and every finding (relative held-out gain, interval low end, Holm p, fitted
value and scale), the runner-up, the margin over it and the margin test's p (a cause is named
only when that margin is significant; else ``ambiguous``).

``--segments``: the route is ``scenarios.curvy_segments(seed)`` (40 curves of 150-800 m and
tangent track) binned into 4 classes as the model's; the catalogue adds the curve classes
(the segments re-binned into 2 and 6, ``curve_classes_cause(4)``) and drops the rail state;
hidden: the loop on the segments binned into 2 and into 6 classes, and nothing.
"""

from __future__ import annotations

from wearcast.physics.vocabulary import CurveClass
from wearcast.statistics.generators.scenarios import (
    cached_vehicle_simulator,
    curvy_segments,
    measured_vehicle_series,
)
from wearcast.statistics.physics_causes import (
    RAIL_TONNAGES_MT,
    PhysicsCause,
    curve_classes_cause,
)
from wearcast.statistics.physics_diagnosis import diagnose_physics
from wearcast.statistics.routes import route_from_segments

ROUTE = [CurveClass(250.0, 100.0, None, "left", 0.15),
         CurveClass(250.0, 100.0, None, "right", 0.15), CurveClass(None, share=0.7)]
CATALOGUE = (
    PhysicsCause("flange_lubrication", "flange", "flange_wear_factor", (0.25, 0.5, 1.0), 1.0),
    PhysicsCause("friction_level", "friction", "friction", (0.3, 0.4, 0.5), 0.4),
    PhysicsCause("patch_model", "patch", "patch_width", ("hertz", "kik_piotrowski"), "hertz"),
    PhysicsCause("running_direction_share", "direction", "forward_share", (0.5, 1.0), 0.5),
    # 0, 0.15 and 0.3 of the metro_b motor axle's adhesion torque 2 mu Q r (16.0 kN m)
    PhysicsCause("traction_on_motor_axles", "traction", "traction_torque_nm",
                 (0.0, 2400.0, 4800.0), 0.0),
    PhysicsCause("rail_state", "rail", "rail_tonnage_mt", (0.0, *RAIL_TONNAGES_MT), 0.0))
HIDDEN = ({}, {"flange_wear_factor": 0.5}, {"friction": 0.5}, {"patch_width": "kik_piotrowski"},
          {"forward_share": 1.0}, {"traction_torque_nm": 4000.0}, {"rail_tonnage_mt": 10.0},
          {"rail_tonnage_mt": 5.0})
#: The model's own number of classes of the segments route (``--segments``).
OWN_N_CLASS = 4
HIDDEN_SEGMENTS = ({}, {"curve_classes": 2}, {"curve_classes": 6})


def main() -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--flange-height", action="store_true")
    parser.add_argument("--segments", action="store_true")
    parser.add_argument("--vehicles", type=int, default=5)
    parser.add_argument("--segment-seed", type=int, default=0)
    args = parser.parse_args()
    flange_height = args.flange_height
    print("measured: FT, qR" + (" and FH" if flange_height else "")
          + f" on {args.vehicles} vehicles")

    def report(params, seconds):
        print(f"  loop run {dict(params) or 'null'}: {seconds:.0f} s", flush=True)

    if args.segments:
        segments = curvy_segments(args.segment_seed)
        route = [c.curve_class() for c in
                 route_from_segments(segments, n_class=OWN_N_CLASS).classes]
        simulate = cached_vehicle_simulator(route, "metro_b", law="usfd", mileage_km=3000.0,
                                            depth_per_step_mm=1.0, on_run=report,
                                            segments=segments)
        catalogue = (*CATALOGUE[:-1], curve_classes_cause(OWN_N_CLASS))
        hiddens = HIDDEN_SEGMENTS
        print(f"route: curvy_segments({args.segment_seed}) binned into {OWN_N_CLASS} classes "
              f"({len(route)} classes)")
    else:
        simulate = cached_vehicle_simulator(ROUTE, "metro_b", law="usfd", mileage_km=3000.0,
                                            depth_per_step_mm=1.0, on_run=report,
                                            rail_tonnages_mt=RAIL_TONNAGES_MT)
        catalogue, hiddens = CATALOGUE, HIDDEN
    for hidden in hiddens:
        measured = measured_vehicle_series(simulate(hidden), wear_scale=1.2, noise_mm=0.02,
                                          flange_height=flange_height,
                                          n_vehicles=args.vehicles)
        d = diagnose_physics(simulate, measured, catalogue=catalogue, n_bootstrap=500)
        margin = "" if d.margin is None else (
            f"; runner-up {d.runner_up}, margin {d.margin:+.3f}"
            + ("" if d.margin_p_value is None else f" (p {d.margin_p_value:.3f})"))
        candidates = f" {list(d.candidates)}" if d.candidates else ""
        print(f"hidden {hidden or 'nothing'} (scale 1.2) -> verdict {d.verdict}{candidates}; "
              f"null scale {d.null_fit['wear_scale']:.3f}{margin}")
        for f in d.findings:
            print(f"   {f.cause:24s} gain {f.gain.relative:+.3f} (low {f.gain.ci95_low:+.3f}) "
                  f"p_holm {f.evidence['p_holm']:.4f} value {f.extension['value']} scale "
                  f"{f.extension['wear_scale']:.3f}", flush=True)


if __name__ == "__main__":
    main()
