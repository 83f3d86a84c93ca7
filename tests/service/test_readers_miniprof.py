"""MiniProf reader: the real files of reference/miniprof and files written here."""

from __future__ import annotations

from datetime import date

import numpy as np
import pytest

from wearcast.physics.profiles.s1002 import s1002_height_mm
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.miniprof import parse_miniprof, to_wheel_frame

WHEEL_FILES = ["Car7216_0001r.whl", "Car7358_0001r.whl", "Car7422_0001r.whl",
               "Car7813_0001r.whl", "avg_wheel.whl", "left-wheel-v1-pre-dry.whl",
               "right-wheel-v1-pre-dry.whl", "whl_left_iter288.whl", "whl_left_iter795.whl"]


def _tip(y: np.ndarray, z: np.ndarray) -> tuple[float, float]:
    window = (y > -62) & (y < -45)
    i = int(np.argmax(np.where(window, z, -np.inf)))
    return float(y[i]), float(z[i])


@pytest.mark.parametrize("name", WHEEL_FILES)
def test_every_real_wheel_file_converts_to_a_plausible_wheel(reference_dir, name):
    mp = parse_miniprof((reference_dir / "miniprof" / name).read_bytes(), name)
    y, z = to_wheel_frame(mp)
    assert y.size > 500
    tip_y, tip_z = _tip(y, z)
    # Flange tip: new S1002 28 mm at y = -55 (EN 13715), worn wheels up to the
    # Sh limit of 36 mm; Car7358 measures 26.97 mm (a worn tip), hence 26.5; worn flanges
    # move the tip towards the tread (iter288: -49.3), so -57..-48.
    assert 26.5 <= tip_z <= 36.0
    assert -57.0 <= tip_y <= -48.0
    at_tape = np.abs(y) <= 1.0
    assert at_tape.any() and np.abs(z[at_tape]).max() < 0.5
    assert y[0] < -65 and y[-1] > 55  # ordered from the back face to the field side


def test_regular_files_keep_the_instrument_parameters(reference_dir):
    # Header values printed in the files themselves (MiniProf for Windows 2.43.73).
    mp = parse_miniprof((reference_dir / "miniprof/left-wheel-v1-pre-dry.whl").read_bytes(),
                        "left-wheel-v1-pre-dry.whl")
    assert mp.layout == "regular"
    assert mp.instrument_parameters == {"sd_mm": 36.1416, "sh_mm": 27.8749, "qr_mm": 9.0991}
    assert (mp.measured_on, mp.side_hint, mp.instrument_serial) == (
        date(2015, 7, 8), "left", "1197")
    right = parse_miniprof((reference_dir / "miniprof/right-wheel-v1-pre-dry.whl").read_bytes(),
                           "right-wheel-v1-pre-dry.whl")
    assert right.side_hint == "right"
    assert right.instrument_parameters == {"sd_mm": 36.3244, "sh_mm": 27.9698, "qr_mm": 9.1947}
    worn = parse_miniprof((reference_dir / "miniprof/whl_left_iter795.whl").read_bytes(),
                          "whl_left_iter795.whl")
    assert worn.instrument_parameters == {"sd_mm": 34.3347, "sh_mm": 34.9985, "qr_mm": 10.0658}
    # The measured points agree with the header's Sh to the instrument's smoothing.
    assert _tip(*to_wheel_frame(worn))[1] == pytest.approx(34.9985, abs=0.2)


def test_old_style_placeholders_are_never_trusted(reference_dir):
    for name in ("Car7422_0001r.whl", "avg_wheel.whl"):
        mp = parse_miniprof((reference_dir / "miniprof" / name).read_bytes(), name)
        assert mp.layout == "old"
        assert mp.instrument_parameters is None
        assert mp.header["Sd/Sh/qR"] == "32.58 37.11 14.71"
        assert mp.y_mm.max() < 37.0  # the placeholder line is not read as a point
    avg = parse_miniprof((reference_dir / "miniprof/avg_wheel.whl").read_bytes(), "avg_wheel.whl")
    assert (avg.instrument_serial, avg.measured_on) == ("148", date(1994, 3, 24))


def test_mpt_yields_its_parts_and_rails_are_refused(reference_dir):
    mp = parse_miniprof((reference_dir / "miniprof/SNX00500.mpt").read_bytes(), "SNX00500.mpt")
    assert mp.layout == "mpt"
    assert [(p.number, p.x_mm.size) for p in mp.parts] == [(1, 4285), (2, 4598)]
    assert mp.measured_on == date(2022, 9, 18)
    assert "MPD1" not in mp.parts[0].header and mp.parts[0].header["MPDN"] == "SNX00500"
    # Both parts of this file are rail heads drawn in AutoCAD: no flange, not a wheel.
    for part in (1, 2):
        with pytest.raises(ImportFileError, match="not a (plausible )?wheel profile"):
            to_wheel_frame(mp, part)
    for name in ("avg_low2.ban", "left-roller-v1-pre-dry.ban"):
        rail = parse_miniprof((reference_dir / "miniprof" / name).read_bytes(), name)
        assert rail.is_rail
        with pytest.raises(ImportFileError, match="rail profile"):
            to_wheel_frame(rail)


# ------------------------------------------------------------------ files written here

S_POINTS = np.linspace(-69.0, 60.0, 260)


def _s1002_points() -> tuple[np.ndarray, np.ndarray]:
    """Instrument X, Y [mm] of a new S1002 wheel (X = y + 70, Y = z)."""
    return S_POINTS + 70.0, np.asarray(s1002_height_mm(S_POINTS), dtype=float)


def _regular(x, y, *, sep=" ", extra_header="") -> bytes:
    head = ("ProgramName=MiniProf for Windows\nDate=02/05/2023\nSide=%R\nMPSerNo=777\n"
            f"ColumnDef=X,Y\nXYPoints={len(x)}\nSd=32.4\nSh=28.1\nqR=10.7\n{extra_header}\n")
    body = "\n".join(f"{a:.4f}{sep}{b:.4f}" for a, b in zip(x, y, strict=True))
    return (head + body + "\n").encode()


def _old(x, y) -> bytes:
    head = ("#MINIWHEELPROF\nTest.whl\nMINIPROF 101 55 2021 11 3\nStock.......: ICE\n"
            "Wheel ID....: 4711\n\" 32.58 37.11 14.71\n(Sd/Sh/qR)\n\n")
    return (head + "\n".join(f"{a:.4f} {b:.4f} 0.000" for a, b in zip(x, y, strict=True))
            + "\n").encode()


def _mpt(parts) -> bytes:
    text = "[FileInfo]\nProgramName=MiniProf for Windows\nDate=18/09/2022\n\n"
    for k, (x, y) in enumerate(parts, start=1):
        text += (f"[Profile{k}Info]\nMPD1=L 0 0 1 1\nMPSerNo=9\nColumnDef=X,Y,A,C\n"
                 f"XYPoints={len(x)}\n\n[Profile{k}Points]\n")
        text += "".join(f"{a:.4f} {b:.4f} 0.1 0 \n" for a, b in zip(x, y, strict=True)) + "\n"
    return text.encode()


def _assert_is_s1002(y, z):
    np.testing.assert_allclose(y, S_POINTS, atol=1e-4)
    np.testing.assert_allclose(z, s1002_height_mm(S_POINTS), atol=1e-4)


@pytest.mark.parametrize("sep", [" ", ", ", ",", "\t"])
@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("flip", [False, True])
def test_written_regular_file_any_order_sign_and_separator(sep, reverse, flip):
    x, y = _s1002_points()
    if reverse:
        x, y = x[::-1], y[::-1]
    if flip:
        y = -y
    mp = parse_miniprof(_regular(x, y, sep=sep), "w.whl")
    assert mp.layout == "regular"
    np.testing.assert_allclose(mp.x_mm, x, atol=1e-4)  # raw points keep file order and sign
    assert mp.instrument_parameters == {"sd_mm": 32.4, "sh_mm": 28.1, "qr_mm": 10.7}
    assert (mp.side_hint, mp.instrument_serial, mp.measured_on) == ("right", "777",
                                                                    date(2023, 5, 2))
    _assert_is_s1002(*to_wheel_frame(mp))


def test_written_old_style_and_mpt_files():
    x, y = _s1002_points()
    old = parse_miniprof(_old(x[::-1], -y[::-1]), "o.whl")
    assert old.layout == "old" and old.instrument_parameters is None
    assert (old.instrument_serial, old.measured_on) == ("55", date(2021, 11, 3))
    assert old.header["Wheel ID"] == "4711"
    _assert_is_s1002(*to_wheel_frame(old))
    mpt = parse_miniprof(_mpt([(x, y), (x[::-1], -y[::-1])]), "m.mpt")
    assert [p.number for p in mpt.parts] == [1, 2]
    for part in (1, 2):
        _assert_is_s1002(*to_wheel_frame(mpt, part))
    with pytest.raises(ImportFileError, match="2 profile parts"):
        to_wheel_frame(mpt)
    with pytest.raises(ImportFileError, match="no profile part 3"):
        to_wheel_frame(mpt, 3)


def test_malformed_files_name_file_and_line():
    x, y = _s1002_points()
    data = _regular(x, y).decode().splitlines()
    head = data.index("") + 1  # first point on file line head + 1
    broken = data.copy()
    broken[head + 4] = "95.0 abc"
    with pytest.raises(ImportFileError) as err:
        parse_miniprof(("\n".join(broken) + "\n").encode(), "bad.whl")
    assert (err.value.file, err.value.line) == ("bad.whl", head + 5)
    assert str(err.value).startswith(f"bad.whl line {head + 5}: ")
    short = "\n".join(data[:-10]) + "\n"
    with pytest.raises(ImportFileError, match="XYPoints=260 but 250"):
        parse_miniprof(short.encode(), "short.whl")
    with pytest.raises(ImportFileError, match="not a MiniProf file"):
        parse_miniprof(b"hello world\n1 2\n", "x.whl")
    with pytest.raises(ImportFileError, match="metres|not a wheel"):
        to_wheel_frame(parse_miniprof(_regular(x / 1000, y / 1000), "m.whl"))
