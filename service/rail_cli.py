"""``wearcast rail-import`` and ``wearcast rails``: measured rails from the command line (the
same store functions as ``/v1/rails``), and the ``--rail-id`` option the table and simulation
commands share.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any, get_args

import typer
from rich.table import Table

RailIdOption = Annotated[int | None, typer.Option("--rail-id", help=(
    "stored measured rail (wearcast rails) in place of the nominal rail, both sides"))]
HighRailIdOption = Annotated[int | None, typer.Option("--high-rail-id", help=(
    "stored measured rail as the high (outer) rail of every curve"))]
LowRailIdOption = Annotated[int | None, typer.Option("--low-rail-id", help=(
    "stored measured rail as the low (inner) rail of every curve"))]


def rail_import(
        file: Annotated[Path, typer.Argument(exists=True, dir_okay=False,
                                             help="MiniProf rail file (.ban, .mpt)")],
        name: Annotated[str | None, typer.Option(help="rail name")] = None,
        gauge_side: Annotated[str | None, typer.Option(help=(
            "negative_x or positive_x: instrument-X side of the gauge face"))] = None,
        inclination: Annotated[str | None, typer.Option(help="laying slope, e.g. 1/40")]
        = None,
        reference: Annotated[str, typer.Option(help="60E1, UIC60, 60E2 or rail:<id>")]
        = "60E1") -> None:
    """Import the rail profiles of a MiniProf file (a repeated file creates nothing)."""
    from wearcast.service import rail_store
    from wearcast.service.cli import _session, _show, raise_field
    from wearcast.service.readers.miniprof_rail import GaugeSide

    if gauge_side is not None and gauge_side not in get_args(GaugeSide):
        raise_field("gauge_side", f"must be {' or '.join(get_args(GaugeSide))}")
    with _session() as (database, session):
        result = rail_store.import_rail_file(
            session, file.read_bytes(), file.name, name=name,
            gauge_side=gauge_side,  # type: ignore[arg-type]
            inclination=rail_store.parse_inclination(inclination), reference=reference,
            raw_dir=database.settings.raw_dir)
        _show({"file_name": result.file_name,
               "created": [_rail_summary(r) for r in result.created],
               "duplicates": [_rail_summary(r) for r in result.duplicates],
               "skipped": [s.model_dump() for s in result.skipped],
               "warnings": result.warnings})


def rails(reference: Annotated[str | None, typer.Option(help=(
              "take the head wear against this head (60E1, UIC60, 60E2, rail:<id>)"))] = None
          ) -> None:
    """List the stored rails with their head wear (W1 vertical, W2 gauge face, W3 45 deg)."""
    from wearcast.service import rail_store
    from wearcast.service.cli import _num, _session, console

    with _session() as (_, session):
        items = rail_store.list_rails(session, limit=1000, reference=reference)
    table = Table(title="measured rails: head wear \\[mm] (+ = metal lost)")
    for column in ("id", "name", "kind", "reference", "datum", "W1 vertical", "W2 gauge face",
                   "W3 45°", "fits"):
        table.add_column(column, justify="right" if column.startswith("W") else "left")
    for r in items:
        w = r.wear
        table.add_row(str(r.id), r.name, r.kind, w.reference,
                      "fitted" if w.placement.fitted else "instrument", _num(w.vertical.value_mm),
                      _num(w.lateral.value_mm), _num(w.corner_45.value_mm),
                      "yes" if w.reference_fits else "NO")
    console.print(table)
    for r in items:
        for reason in r.wear.mismatch:
            console.print(f"rail {r.id}: {reason}")


def _r3(value: Any) -> Any:
    if isinstance(value, tuple | list):
        return [_r3(v) for v in value]
    return None if value is None else round(float(value), 3)


def _rail_summary(rail: Any) -> dict[str, Any]:
    w = rail.wear
    return {"id": rail.id, "name": rail.name, "kind": rail.kind, "part": rail.part,
            "top_mm": _r3(rail.frame.top_mm), "gauge_point_mm": _r3(rail.frame.gauge_point_mm),
            "head_width_mm": _r3(rail.frame.head_width_mm),
            "wear": {"reference": w.reference, "placement": w.placement.method,
                     "W1_vertical_mm": _r3(w.vertical.value_mm),
                     "W2_gauge_face_mm": _r3(w.lateral.value_mm),
                     "W3_45deg_mm": _r3(w.corner_45.value_mm),
                     "reference_fits": w.reference_fits, "mismatch": w.mismatch}}
