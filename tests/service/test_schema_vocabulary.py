"""The HTTP layer speaks the core's words: no enumeration of the service is a copy of one the
core defines (it imports the core's ``Literal``), and the bodies that carry a core record
(a route's curve class, a simulation's curve class, a curve-radius table row) carry its
fields.
"""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

from wearcast.physics import wear_tables as physics_wear_tables
from wearcast.physics.vocabulary import CurveClass, Direction
from wearcast.service.route_schemas import RouteClassIn, RouteClassOut, SegmentIn
from wearcast.service.simulation_schemas import SimulationClassIn
from wearcast.service.wear_table_schemas import RadiusIn, WearTableRowOut
from wearcast.statistics import wear_tables as statistics_wear_tables
from wearcast.statistics.routes import RouteClass

ROOT = Path(__file__).resolve().parents[2]


def _literal_values(node: ast.expr) -> frozenset[object] | None:
    """The values of ``Literal[...]`` (a Subscript of the name Literal), else None."""
    if not (isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name)
            and node.value.id == "Literal"):
        return None
    items = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
    if not all(isinstance(i, ast.Constant) for i in items):
        return None
    return frozenset(i.value for i in items if isinstance(i, ast.Constant))


def _core_literals() -> dict[frozenset[object], str]:
    """Every ``Name = Literal[...]`` of physics/ and statistics/, by its set of values."""
    out: dict[frozenset[object], str] = {}
    for package in ("physics", "statistics"):
        for path in sorted((ROOT / package).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Assign) and len(node.targets) == 1 \
                        and isinstance(node.targets[0], ast.Name):
                    values = _literal_values(node.value)
                    if values is not None and len(values) > 1:
                        out.setdefault(values, f"{path.relative_to(ROOT)}: {node.targets[0].id}")
    return out


def test_the_core_literals_are_found() -> None:
    core = _core_literals()
    assert core[frozenset({"flange", "tread"})] == "physics/vocabulary.py: Region"
    assert frozenset({"hertz", "kik_piotrowski"}) in core


def test_no_service_module_writes_a_core_enumeration_again() -> None:
    core = _core_literals()
    copies = []
    for path in sorted((ROOT / "service").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            values = _literal_values(node) if isinstance(node, ast.Subscript) else None
            if isinstance(node, ast.Tuple) and len(node.elts) > 1 and all(
                    isinstance(e, ast.Constant) and isinstance(e.value, str)
                    for e in node.elts):
                values = frozenset(e.value for e in node.elts if isinstance(e, ast.Constant))
            if values is not None and values in core:
                copies.append(f"{path.relative_to(ROOT)}:{node.lineno} copies "
                              f"{sorted(map(str, values))}: import {core[values]}")
    assert copies == []


def test_route_class_bodies_carry_the_route_class_fields() -> None:
    names = [f.name for f in dataclasses.fields(RouteClass)]
    assert list(RouteClassIn.model_fields) == names
    assert list(RouteClassOut.model_fields) == names
    assert set(SegmentIn.model_fields) == set(names) - {"share"} | {"length_m"}
    assert RouteClassIn.model_fields["direction"].annotation == Direction | None


def test_the_simulation_class_body_is_the_curve_class() -> None:
    names = {f.name for f in dataclasses.fields(CurveClass)}
    assert set(SimulationClassIn.model_fields) == names
    assert set(RadiusIn.model_fields) == names - {"direction"}
    for f in dataclasses.fields(CurveClass):
        if f.default is not dataclasses.MISSING:
            assert SimulationClassIn.model_fields[f.name].default == f.default, f.name
    body = SimulationClassIn(radius_m=500.0, cant_mm=90.0, direction="right", share=0.4)
    assert CurveClass(**body.model_dump()).rail_for("right") == "low"


def test_a_table_row_answer_has_the_table_columns() -> None:
    assert list(WearTableRowOut.model_fields) == physics_wear_tables.TABLE_COLUMNS
    assert list(WearTableRowOut.model_fields) == list(statistics_wear_tables.TABLE_COLUMNS)
