"""``wearcast contact``: the loaded wheel-rail contact at given poses from the command line
(the same computation as ``POST /v1/contact``), with profiles by name or from SIMPACK
``.prw``/``.prr`` files."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from wearcast.service.errors import ApiError


def _floats(text: str, name: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise typer.BadParameter(f"{name}: comma-separated numbers, got {text!r}") from None


def contact(
        shift: Annotated[str, typer.Option(help="lateral shifts [mm], comma-separated")],
        wheel: Annotated[str, typer.Option(help="S1002 or a SIMPACK .prw file")] = "S1002",
        rail: Annotated[str, typer.Option(help="60E1, 60E2 or a SIMPACK .prr file")] = "60E1",
        inclination: Annotated[float, typer.Option(help=(
            "rail inclination slope (0 for a file already canted)"))] = 1.0 / 40.0,
        side: Annotated[str, typer.Option(help="left or right wheel")] = "left",
        yaw: Annotated[str, typer.Option(help="yaw [rad], one or one per shift")] = "0",
        roll: Annotated[str | None, typer.Option(help=(
            "roll [rad], one or one per shift (default: solved)"))] = None,
        load: Annotated[float, typer.Option(help="vertical wheel load [N]")] = 10_000.0,
        radius: Annotated[float, typer.Option(help="nominal wheel radius [mm]")] = 460.0,
        friction: Annotated[float, typer.Option(help="friction coefficient")] = 0.3,
        method: Annotated[str, typer.Option(help="auto, bem, bem-coarse, kp, hertz")] = "auto",
        as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False) -> None:
    """Contact patches, forces and pressures of one wheel at each shift (CONTACT's wheel-rail
    module: non-Hertzian normal contact, FASTSIM)."""
    from pydantic import ValidationError

    from wearcast.service import cli
    from wearcast.service.contact_schemas import ContactIn
    from wearcast.service.contact_store import compute_contact

    shifts = _floats(shift, "shift")
    yaws = _floats(yaw, "yaw")
    rolls = None if roll is None else _floats(roll, "roll")

    def per_shift(values: list[float] | None, name: str) -> list[float | None]:
        given: list[float | None] = list(values) if values is not None else []
        if values is None:
            return [None] * len(shifts)
        if len(given) == 1:
            return given * len(shifts)
        if len(given) != len(shifts):
            raise typer.BadParameter(f"{name}: give one value or one per shift")
        return given

    poses = [{"shift_mm": s, "yaw_rad": y, "roll_rad": r, "wheel_load_n": load}
             for s, y, r in zip(shifts, per_shift(yaws, "yaw"), per_shift(rolls, "roll"),
                                strict=True)]
    body: dict[str, object] = {"poses": poses, "inclination": inclination, "side": side,
                               "nominal_radius_mm": radius, "friction": friction,
                               "normal_method": method}
    if wheel.upper() != "S1002":
        body["wheel_file"] = {"text": Path(wheel).read_text(encoding="utf-8",
                                                            errors="replace")}
    if Path(rail).suffix.lower() == ".prr":
        body["rail_file"] = {"text": Path(rail).read_text(encoding="utf-8", errors="replace")}
    else:
        body["rail"] = rail.upper()
    try:
        out = compute_contact(None, ContactIn.model_validate(body))
    except ValidationError as exc:
        cli.err.print(f"invalid input: {exc.errors()[0]['loc']}: {exc.errors()[0]['msg']}")
        raise typer.Exit(2) from None
    except ApiError as exc:
        cli.err.print(f"{exc.status}: {exc.item()}")
        raise typer.Exit(2) from None
    data = out.model_dump()
    if as_json:
        typer.echo(json.dumps(data, indent=1))
        return
    typer.echo("shift_mm roll_mrad patch y_wheel_mm angle_deg Fn_N Fx_N Fs_N pmax_MPa "
                      "a_mm b_mm method")
    for pose in data["poses"]:
        for k, p in enumerate(pose["patches"]):
            typer.echo(
                f"{pose['shift_mm']:8.2f} {1e3 * pose['roll_rad']:9.3f} {k:5d} "
                f"{p['y_wheel_mm']:10.2f} {57.29578 * p['contact_angle_rad']:9.2f} "
                f"{p['normal_force_n']:8.0f} {p['fx_n']:7.0f} {p['fs_n']:7.0f} "
                f"{p['peak_pressure_mpa']:8.0f} {p['a_mm']:5.2f} {p['b_mm']:5.2f} "
                f"{p['normal_method']}")
