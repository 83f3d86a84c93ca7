"""Which physical causes the physics diagnosis names when the whole-vehicle loop hides them.

Run: .venv/bin/python benchmarks/physics_diagnosis_detection.py [--flange-height]
(``--flange-height``: FH measured too, beside FT and qR)

Truth: ``simulate_vehicle_wear`` (metro_b, a 250 m curve in both directions on 30 % of the
route, USFD, D_step 1 mm, 3,000 km) with one cause injected, a wear scale of 1.2, 5 vehicles
with 4 irregular mileages each (200-1,500 km) and 0.02 mm noise on FT and qR. The diagnosis
(``statistics.physics_diagnosis``) runs the same loop at its catalogue values (flange wear
factor 0.25 / 0.5 / 1, friction 0.3 / 0.4 / 0.5, Hertz / Kik-Piotrowski patch, direction share
0.5 / 1, traction torque on the motor axles 0 / 2,400 / 4,800 N m) and prints, per hidden
cause, the verdict and every finding (relative held-out gain, interval low end, Holm p, fitted
value and scale), the runner-up, the margin over it and the margin test's p (a cause is named
only when that margin is significant; else ``ambiguous``).
"""

from __future__ import annotations

from wearcast.physics.vocabulary import CurveClass
from wearcast.statistics.generators.scenarios import (
    cached_vehicle_simulator,
    measured_vehicle_series,
)
from wearcast.statistics.physics_diagnosis import PhysicsCause, diagnose_physics

ROUTE = [CurveClass(250.0, 100.0, None, "left", 0.15),
         CurveClass(250.0, 100.0, None, "right", 0.15), CurveClass(None, share=0.7)]
CATALOGUE = (
    PhysicsCause("flange_lubrication", "flange", "flange_wear_factor", (0.25, 0.5, 1.0), 1.0),
    PhysicsCause("friction_level", "friction", "friction", (0.3, 0.4, 0.5), 0.4),
    PhysicsCause("patch_model", "patch", "patch_width", ("hertz", "kik_piotrowski"), "hertz"),
    PhysicsCause("running_direction_share", "direction", "forward_share", (0.5, 1.0), 0.5),
    # 0, 0.15 and 0.3 of the metro_b motor axle's adhesion torque 2 mu Q r (16.0 kN m)
    PhysicsCause("traction_on_motor_axles", "traction", "traction_torque_nm",
                 (0.0, 2400.0, 4800.0), 0.0))
HIDDEN = ({}, {"flange_wear_factor": 0.5}, {"friction": 0.5}, {"patch_width": "kik_piotrowski"},
          {"forward_share": 1.0}, {"traction_torque_nm": 4000.0})


def main() -> None:
    import sys

    flange_height = "--flange-height" in sys.argv[1:]
    print("measured: FT, qR" + (" and FH" if flange_height else ""))

    def report(params, seconds):
        print(f"  loop run {dict(params) or 'null'}: {seconds:.0f} s", flush=True)

    simulate = cached_vehicle_simulator(ROUTE, "metro_b", law="usfd", mileage_km=3000.0,
                                        depth_per_step_mm=1.0, on_run=report)
    for hidden in HIDDEN:
        measured = measured_vehicle_series(simulate(hidden), wear_scale=1.2, noise_mm=0.02,
                                          flange_height=flange_height)
        d = diagnose_physics(simulate, measured, catalogue=CATALOGUE, n_bootstrap=500)
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
