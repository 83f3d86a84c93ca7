"""The shared vocabulary: the rail rule, leading shares and the curve class's checks."""

from __future__ import annotations

import math

import pytest

from wearcast.physics.vocabulary import (
    RAILS,
    REGIONS,
    CurveClass,
    check_side,
    leading_share,
    rail_for,
    region_of,
)


def test_rail_rule_left_curve_puts_right_wheels_on_the_high_rail() -> None:
    assert rail_for("left", "right") == "high"
    assert rail_for("left", "left") == "low"
    assert rail_for("right", "left") == "high"
    assert rail_for("right", "right") == "low"
    assert rail_for(None, "left") == "tangent"


def test_rail_rule_is_mirror_symmetric() -> None:
    mirror = {"left": "right", "right": "left"}
    for direction in ("left", "right"):
        for side in ("left", "right"):
            assert rail_for(direction, side) == rail_for(mirror[direction], mirror[side])


def test_each_curve_puts_one_wheel_of_an_axle_on_each_rail() -> None:
    for direction in ("left", "right"):
        assert {rail_for(direction, "left"), rail_for(direction, "right")} == {"high", "low"}
    assert set(RAILS) == {"high", "low", "tangent"}


def test_regions_order_and_split() -> None:
    assert REGIONS == ("flange", "tread")
    assert region_of(-30.01) == "flange" and region_of(-30.0) == "tread"


def test_leading_share_sums_to_one_per_bogie() -> None:
    for mode in ("lead", "mixed"):
        assert leading_share(1, mode) + leading_share(2, mode) == pytest.approx(1.0)
    assert leading_share(1, "lead") == 1.0 and leading_share(2, "mixed") == 0.5


def test_curve_class_checks_name_the_field() -> None:
    with pytest.raises(ValueError, match="radius_m"):
        CurveClass(radius_m=-300.0)
    with pytest.raises(ValueError, match="direction"):
        CurveClass(radius_m=300.0, direction="up")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="share"):
        CurveClass(radius_m=300.0, share=math.nan)
    assert CurveClass(radius_m=None).is_tangent and CurveClass(radius_m=math.inf).is_tangent
    assert CurveClass(radius_m=300.0, direction="left").rail_for("right") == "high"
    assert CurveClass(radius_m=None).rail_for("right") == "tangent"


def test_side_check_is_one_rule_for_the_contact_functions() -> None:
    from wearcast.physics.contact.creepages import rigid_creepages

    assert [check_side(s) for s in ("left", "right")] == ["left", "right"]
    for bad in ("Left", "centre", None, 1):
        with pytest.raises(ValueError, match="side: must be 'left' or 'right', got"):
            check_side(bad)
    with pytest.raises(ValueError, match="side: must be 'left' or 'right', got 'middle'"):
        rigid_creepages("middle", 10.0, 20.0, 0.0, 0.0, 0.0, 0.0, 460.0,
                        [[0.0], [750.0], [0.0]], 0.0)
