"""A rail worn to stated tonnages by the rail-step model (physics.rail_tonnage)."""

import pytest

from wearcast.physics.rail_feedback import simulate_rail_steps
from wearcast.physics.rail_head_wear import WornRail
from wearcast.physics.rail_tonnage import DEFAULT_WHEEL_STEPS, rails_worn_to_tonnages
from wearcast.physics.vocabulary import CurveClass

CURVES = [CurveClass(300.0, 100.0, None, "left", 0.15),
          CurveClass(300.0, 100.0, None, "right", 0.15), CurveClass(None, share=0.7)]


@pytest.fixture(scope="module")
def first_step():
    # rails_worn_to_tonnages wears seed 003's one mean rail
    return simulate_rail_steps("metro_b", CURVES, n_rail_steps=1, law="usfd",
                               steps=DEFAULT_WHEEL_STEPS, feedback="mean")


def test_tonnages_inside_and_at_the_end_of_a_rail_step(first_step):
    step_mt = float(first_step.tonnage_mt[0])
    assert 1.0 < step_mt < 10.0  # metro_b on 300 m curves: about 3-4 Mt per 0.8 mm
    out = rails_worn_to_tonnages("metro_b", CURVES, [0.0, 0.5 * step_mt, step_mt,
                                                     1.5 * step_mt], law="usfd")
    assert out.rail_steps == 2 and out.tonnage_per_step_mt[0] == pytest.approx(step_mt)
    # the second step wears the once-worn rail at a like rate: its curving equilibria stay on
    # the contact table (a spurious one at -43.8 m of shift, where the table repeats its last
    # row, left its curves without rail wear and the step took 8 times the first's tonnage)
    assert out.tonnage_per_step_mt[1] < 2.0 * step_mt
    assert out.rails[0.0] == "60E1"
    # a tonnage at the end of a step is that step's rail (seed 003 eq. 4), by content
    assert isinstance(out.rails[step_mt], WornRail)
    assert out.rails[step_mt] == first_step.rails[1]
    # inside a step the head loses area in proportion to the passages (one depth per vehicle)
    half = out.rails[0.5 * step_mt].area_loss_mm2()
    full = out.rails[step_mt].area_loss_mm2()
    assert half == pytest.approx(0.5 * full, rel=0.03)
    # beyond it the next step's rail goes on wearing
    assert out.rails[1.5 * step_mt].area_loss_mm2() > 1.2 * full
    assert out.rails[1.5 * step_mt].head_wear().corner_45.value_mm > \
        out.rails[step_mt].head_wear().corner_45.value_mm


def test_bad_tonnages_are_refused():
    with pytest.raises(ValueError, match="tonnages_mt"):
        rails_worn_to_tonnages("metro_b", CURVES, [-1.0])
    with pytest.raises(ValueError, match="rail steps"):
        rails_worn_to_tonnages("metro_b", CURVES, [1000.0], max_rail_steps=1)
