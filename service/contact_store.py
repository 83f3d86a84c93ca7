"""``POST /v1/contact``: resolve the request's wheel and rail into a track and run the contact
pipeline (``physics.contact.pose_contact``) at its poses. Nothing is stored."""

from __future__ import annotations

from typing import Any

from sqlalchemy.orm import Session

from wearcast.physics.contact.geometry import WheelsetTrack
from wearcast.physics.contact.locus import NoContactError
from wearcast.physics.contact.pose_contact import Pose, contact_at_poses
from wearcast.physics.contact.track_profiles import wheel_curve_from_height, wheelset_track
from wearcast.physics.profiles.measured import ProfileCurve, s1002_curve
from wearcast.physics.profiles.simpack import (
    ProfileFileError,
    parse_simpack_profile,
    rail_curve,
    wheel_curve,
)
from wearcast.service.contact_schemas import ContactIn, ContactOut
from wearcast.service.errors import Unprocessable
from wearcast.service.measured_wheel_source import requested_wheel
from wearcast.service.rail_store import measured_rail


def _wheel(session: Session | None, body: ContactIn) -> tuple[ProfileCurve, dict[str, Any]]:
    if body.wheel_file is not None:
        try:
            curve = wheel_curve(parse_simpack_profile(body.wheel_file.text))
        except ProfileFileError as exc:
            raise Unprocessable("wheel_file.text", str(exc)) from None
        return curve, {"source": "wheel_file (SIMPACK)"}
    if session is None:  # the command line: files and named profiles only
        if body.wheel_id is not None or body.measurement_id is not None:
            raise Unprocessable("wheel_id", "stored wheels need the service's database")
    found = None if session is None else requested_wheel(session, body)
    if found is None:
        return s1002_curve(), {"source": "S1002 (EN 13715)"}
    wheel, info = found
    return wheel_curve_from_height(wheel.height_mm, wheel.search_range_mm), info


def _track(session: Session | None, body: ContactIn, wheel: ProfileCurve
           ) -> tuple[WheelsetTrack, dict[str, Any]]:
    r0 = body.nominal_radius_mm
    if body.rail_file is not None:
        try:
            rail = rail_curve(parse_simpack_profile(body.rail_file.text))
        except ProfileFileError as exc:
            raise Unprocessable("rail_file.text", str(exc)) from None
        return (WheelsetTrack(wheel=wheel, rail=rail, nominal_radius_mm=r0,
                              rail_inclination=body.inclination),
                {"source": "rail_file (SIMPACK)", "inclination": body.inclination})
    if body.rail_id is not None:
        if session is None:
            raise Unprocessable("rail_id", "stored rails need the service's database")
        shape = measured_rail(session, body.rail_id)
        return (wheelset_track(wheel, shape, body.inclination, r0),
                {"source": f"stored rail {body.rail_id}", "name": shape.name,
                 "inclination": body.inclination})
    return (wheelset_track(wheel, body.rail, body.inclination, r0),
            {"source": body.rail, "inclination": body.inclination})


def compute_contact(session: Session | None, body: ContactIn) -> ContactOut:
    """The loaded contact of the requested wheel at every pose (422 naming the field when a
    profile is unusable or the wheel cannot touch its rail). Without a session (the command
    line) only named profiles and files are used."""
    wheel, wheel_info = _wheel(session, body)
    try:
        track, rail_info = _track(session, body, wheel)
    except ValueError as exc:
        raise Unprocessable("rail", str(exc)) from None
    poses = [Pose(p.shift_mm, p.yaw_rad, p.roll_rad, p.wheel_load_n) for p in body.poses]
    try:
        found = contact_at_poses(track, body.side, poses, speed_m_s=body.speed_m_s,
                                 mu=body.friction, shear_modulus_mpa=body.shear_modulus_mpa,
                                 poisson=body.poisson, method=body.normal_method,
                                 n_grid=body.fastsim_grid, bound=body.traction_bound)
    except NoContactError as exc:
        field = {"shift": "poses.shift_mm", "wheel": "wheel", "rail": "rail"}.get(
            exc.field, exc.field)
        raise Unprocessable(field, exc.reason) from None
    except (ValueError, RuntimeError) as exc:
        raise Unprocessable("poses", f"the contact could not be solved: {exc}") from None
    return ContactOut(wheel=wheel_info, rail=rail_info, side=body.side,
                      inclination=body.inclination, nominal_radius_mm=body.nominal_radius_mm,
                      method=body.normal_method, poses=[c.to_dict() for c in found])
