"""One entry point for an uploaded file: CSV, MiniProf + manifest, or a zip of these.

Dispatch by extension (content is sniffed when the extension says nothing):

* ``.csv`` — long profile CSV or parameter-only CSV, told apart by the header
  (``long_csv.sniff_kind``); read streaming;
* ``.whl`` / ``.mpt`` — MiniProf wheel files; each needs a manifest row (``manifest=``),
  else ``ImportFileError "no manifest row for file X"``; ``.ban`` rail files are refused;
* ``.zip`` — any mix of the above (nested folders allowed, nested zips not) plus exactly one
  ``manifest.csv`` when MiniProf files are present. Limits against zip bombs: member count,
  per-member and total uncompressed size, and compression ratio (``ZipLimits``); the limits
  are checked on the central directory before anything is decompressed, and zipfile never
  inflates a member beyond its declared size.

A MiniProf record's metadata is its manifest row; ``measured_on`` and ``instrument_id`` left
empty there are taken from the file (``Date``, ``MPSerNo`` → ``"miniprof:<serial>"``,
``DiameterTaperline`` → ``diameter_mm``); a
manifest ``side`` that contradicts the file's ``Side=%L/%R`` is refused.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import posixpath
import zipfile
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import IO, Any, BinaryIO, TypeAlias

from wearcast.service.readers.diameter import miniprof_diameter_mm
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.long_csv import iter_profile_records, read_header, sniff_kind
from wearcast.service.readers.manifest import MANIFEST_NAME, manifest_key, read_manifest
from wearcast.service.readers.miniprof import (
    RAIL_EXTENSIONS,
    WHEEL_EXTENSIONS,
    parse_miniprof,
    to_wheel_frame,
)
from wearcast.service.readers.parameter_csv import iter_parameter_records
from wearcast.service.readers.records import MeasurementMeta, ParameterRecord, ProfileRecord

Record: TypeAlias = ProfileRecord | ParameterRecord
#: A reader of long profile CSVs: (stream at the header, file name) -> its records.
ProfileReader: TypeAlias = Callable[[IO[bytes], str], Iterator[ProfileRecord]]
ManifestArg = Mapping[str, MeasurementMeta] | bytes | BinaryIO | None


@dataclass(frozen=True)
class ZipLimits:
    """Refuse archives beyond these bounds (sizes in bytes)."""

    max_members: int = 200_000
    max_member_bytes: int = 4 * 1024**3
    max_total_bytes: int = 8 * 1024**3
    #: uncompressed / compressed; long CSVs repeat their metadata and compress ~20-60x.
    max_ratio: float = 300.0
    #: members smaller than this are exempt from the ratio test
    ratio_exempt_bytes: int = 1024**2
    #: CSV files: the longest line [bytes] and the most header columns (checked streaming)
    max_line_bytes: int = 1024**2
    max_columns: int = 512


DEFAULT_LIMITS = ZipLimits()
_JUNK_PREFIXES = ("__MACOSX/",)


@dataclass(frozen=True)
class RawMember:
    """A file of the upload as received: its path (``upload.zip:dir/a.whl`` inside a zip),
    bytes and SHA-256 (hex)."""

    path: str
    data: bytes
    sha256: str

    @classmethod
    def of(cls, path: str, data: bytes) -> RawMember:
        return cls(path, data, hashlib.sha256(data).hexdigest())


def _extension(name: str) -> str:
    return posixpath.splitext(name.lower())[1]


def _as_stream(data_or_stream: bytes | BinaryIO) -> BinaryIO:
    if isinstance(data_or_stream, bytes | bytearray | memoryview):
        return io.BytesIO(bytes(data_or_stream))
    return data_or_stream


def _read_all(data_or_stream: bytes | BinaryIO) -> bytes:
    if isinstance(data_or_stream, bytes | bytearray | memoryview):
        return bytes(data_or_stream)
    return data_or_stream.read()


def _csv_records(stream: IO[bytes], name: str, limits: ZipLimits = DEFAULT_LIMITS,
                 profile_reader: ProfileReader | None = None) -> Iterator[Record]:
    """Sniff the header, then stream the right CSV reader over the whole file
    (``profile_reader``, default :func:`iter_profile_records`, for a long profile CSV)."""
    from wearcast.service.upload_limits import guarded

    if not stream.seekable():
        stream = io.BytesIO(stream.read())
    stream = guarded(stream, name, limits.max_line_bytes, limits.max_columns)
    start = stream.tell()
    columns = read_header(stream, name)
    try:
        kind = sniff_kind(columns)
    except ValueError as exc:
        raise ImportFileError(name, str(exc), line=1) from None
    stream.seek(start)
    if kind == "profile":
        yield from (profile_reader or iter_profile_records)(stream, name)
    else:
        yield from iter_parameter_records(stream, name)


def _load_manifest(manifest: ManifestArg, name: str) -> dict[str, MeasurementMeta] | None:
    if manifest is None:
        return None
    if isinstance(manifest, Mapping):
        return {manifest_key(k): v for k, v in manifest.items()}
    return read_manifest(_as_stream(manifest), name)


class _Manifest:
    """Look-ups of MiniProf files in a manifest, tracking which rows were used."""

    def __init__(self, rows: dict[str, MeasurementMeta] | None, name: str,
                 base_dir: str = "") -> None:
        self.rows = rows or {}
        self.name = name
        self.base_dir = base_dir
        self.used: dict[str, str] = {}

    def find(self, member: str, part: int | None, display: str) -> MeasurementMeta | None:
        """The row naming ``member`` by its zip path, its path relative to the manifest's
        folder, or its base name (``#part`` appended for one part of an .mpt)."""
        suffix = "" if part is None else f"#{part}"
        candidates = [member]
        if self.base_dir and member.startswith(self.base_dir + "/"):
            candidates.append(member[len(self.base_dir) + 1:])
        candidates.append(posixpath.basename(member))
        for path in candidates:
            key = path + suffix
            if key in self.rows:
                label = member + suffix
                if key in self.used and self.used[key] != label:
                    raise ImportFileError(self.name, f"manifest row {key!r} matches both "
                                          f"{self.used[key]} and {label}; give the path",
                                          line=self.rows[key].source_line, field="file")
                self.used[key] = label
                return self.rows[key]
        return None

    def require(self, member: str, part: int | None, display: str) -> MeasurementMeta:
        meta = self.find(member, part, display)
        if meta is None:
            label = member if part is None else f"{member}#{part}"
            raise ImportFileError(display, f"no manifest row for file {label}"
                                  + ("" if self.rows else " (upload a manifest.csv with it)"),
                                  field="file")
        return meta

    def check_all_used(self) -> None:
        unused = sorted(set(self.rows) - set(self.used))
        if unused:
            key = unused[0]
            raise ImportFileError(self.name, f"manifest lists file {key!r}, which is not in "
                                  "the upload", line=self.rows[key].source_line, field="file")


def _miniprof_records(data: bytes, member: str, display: str, manifest: _Manifest
                      ) -> list[ProfileRecord]:
    """ProfileRecords of one MiniProf wheel file (one per manifest-listed part of an .mpt)."""
    if _extension(member) in RAIL_EXTENSIONS:
        raise ImportFileError(display, "rail profile (.ban): only wheel profiles (.whl, .mpt) "
                              "can be imported as wheel measurements; import rails through "
                              "POST /v1/rails/import")
    mp = parse_miniprof(data, display)
    if mp.is_rail:
        to_wheel_frame(mp)  # raises the rail refusal
    wanted: list[tuple[int | None, MeasurementMeta]]
    if mp.parts:
        whole = manifest.find(member, None, display)
        if whole is not None and len(mp.parts) == 1:
            wanted = [(mp.parts[0].number, whole)]
        elif whole is not None:
            raise ImportFileError(display, f"file has {len(mp.parts)} profile parts; the "
                                  "manifest must name each as "
                                  f"'{posixpath.basename(member)}#<part>'", field="file")
        else:
            wanted = [(p.number, manifest.require(member, p.number, display))
                      for p in mp.parts]
    else:
        wanted = [(None, manifest.require(member, None, display))]
    out = []
    for part, meta in wanted:
        y_mm, z_mm = to_wheel_frame(mp, part)
        if mp.side_hint is not None and mp.side_hint != meta.side:
            raise ImportFileError(
                display, f"manifest says side {meta.side!r} (line {meta.source_line}) but the "
                f"file says Side={mp.header.get('Side', '')} ({mp.side_hint})", field="side")
        updates: dict[str, Any] = {
            "source_file": display if part is None else f"{display}#{part}",
            "source_line": None}
        if meta.measured_on is None and mp.measured_on is not None:
            updates["measured_on"] = mp.measured_on
        if meta.instrument_id is None and mp.instrument_serial is not None:
            updates["instrument_id"] = f"miniprof:{mp.instrument_serial}"
        if meta.diameter_mm is None and part is None:
            updates["diameter_mm"] = miniprof_diameter_mm(mp.header)
        out.append(ProfileRecord(dataclasses.replace(meta, **updates), y_mm, z_mm,
                                 mp.instrument_parameters,
                                 header_parameters=None if mp.parts else mp.header_parameters,
                                 instrument_datum=True, manifest_line=meta.source_line,
                                 datum_header=_datum_header(mp.header)))
    return out


def _datum_header(header: Mapping[str, str]) -> dict[str, str] | None:
    """The header's datum entries: offsets and reference points, as printed."""
    out = {k: v for k, v in header.items()
           if k in ("Xoffset", "Yoffset", "WheelAdjustPoint") or k.startswith("RefPoint")}
    return out or None


def _check_zip_limits(infos: list[zipfile.ZipInfo], name: str, limits: ZipLimits) -> None:
    if len(infos) > limits.max_members:
        raise ImportFileError(name, f"zip has {len(infos)} members; at most "
                              f"{limits.max_members} are accepted")
    total = 0
    for info in infos:
        if info.file_size > limits.max_member_bytes:
            raise ImportFileError(f"{name}:{info.filename}", f"member expands to "
                                  f"{info.file_size} bytes; at most {limits.max_member_bytes} "
                                  "are accepted")
        if (info.file_size > limits.ratio_exempt_bytes
                and info.file_size > limits.max_ratio * max(info.compress_size, 1)):
            raise ImportFileError(f"{name}:{info.filename}", "compression ratio "
                                  f"{info.file_size / max(info.compress_size, 1):.0f}:1 exceeds "
                                  f"{limits.max_ratio:g}:1 (zip bomb?)")
        total += info.file_size
    if total > limits.max_total_bytes:
        raise ImportFileError(name, f"zip expands to {total} bytes; at most "
                              f"{limits.max_total_bytes} are accepted")


def _zip_records(data_or_stream: bytes | BinaryIO, name: str, manifest: ManifestArg,
                 keep_raw: bool, limits: ZipLimits, profile_reader: ProfileReader | None = None
                 ) -> Iterator[tuple[Record, RawMember | None]]:
    stream = _as_stream(data_or_stream)
    if not stream.seekable():
        stream = io.BytesIO(stream.read())
    try:
        archive = zipfile.ZipFile(stream)
    except zipfile.BadZipFile as exc:
        raise ImportFileError(name, f"not a readable zip archive ({exc})") from None
    with archive:
        infos = [i for i in archive.infolist() if not i.is_dir()
                 and not i.filename.startswith(_JUNK_PREFIXES)
                 and not posixpath.basename(i.filename).startswith(".")]
        _check_zip_limits(infos, name, limits)
        manifests = [i for i in infos if posixpath.basename(i.filename).lower() == MANIFEST_NAME]
        miniprofs = [i for i in infos if _extension(i.filename) in WHEEL_EXTENSIONS]
        if len(manifests) > 1:
            raise ImportFileError(name, "zip holds more than one manifest.csv: "
                                  + ", ".join(i.filename for i in manifests))
        for info in infos:
            ext = _extension(info.filename)
            if info not in manifests and ext not in (".csv", *WHEEL_EXTENSIONS,
                                                     *RAIL_EXTENSIONS):
                kind = "nested zip archives are" if ext == ".zip" else f"'{ext}' files are"
                raise ImportFileError(f"{name}:{info.filename}", f"{kind} not accepted in a "
                                      "zip (expected .csv, .whl, .mpt and manifest.csv)")
        rows: dict[str, MeasurementMeta] | None = _load_manifest(manifest, name)
        if manifests:
            if rows is not None:
                raise ImportFileError(name, "a manifest was given both inside the zip and "
                                      "separately")
            manifest_info = manifests[0]
            rows = read_manifest(io.BytesIO(archive.read(manifest_info)),
                                 f"{name}:{manifest_info.filename}")
        if miniprofs and rows is None:
            raise ImportFileError(name, "zip holds MiniProf files but no manifest.csv")
        lookup = _Manifest(rows, f"{name}:{manifests[0].filename}" if manifests else name,
                           posixpath.dirname(manifests[0].filename) if manifests else "")
        for info in infos:
            if info in manifests:
                continue
            display = f"{name}:{info.filename}"
            ext = _extension(info.filename)
            if ext == ".csv":
                if keep_raw:
                    csv_raw = RawMember.of(display, archive.read(info))
                    for record in _csv_records(io.BytesIO(csv_raw.data), display, limits,
                                               profile_reader):
                        yield record, csv_raw
                else:
                    with archive.open(info) as member:
                        for record in _csv_records(member, display, limits,
                                                   profile_reader):
                            yield record, None
            else:
                data = archive.read(info)
                raw = RawMember.of(display, data) if keep_raw else None
                for record in _miniprof_records(data, info.filename, display, lookup):
                    yield record, raw
        if miniprofs:
            lookup.check_all_used()


def _iter(data_or_stream: bytes | BinaryIO, file_name: str, manifest: ManifestArg,
          keep_raw: bool, limits: ZipLimits, profile_reader: ProfileReader | None = None
          ) -> Iterator[tuple[Record, RawMember | None]]:
    ext = _extension(file_name)
    if ext not in (".csv", ".zip", *WHEEL_EXTENSIONS, *RAIL_EXTENSIONS):
        stream = _as_stream(data_or_stream)
        if stream.seekable():
            head = stream.read(4)
            stream.seek(-len(head), io.SEEK_CUR)
            if head == b"PK\x03\x04":
                ext = ".zip"
            data_or_stream = stream
        if ext != ".zip":
            raise ImportFileError(file_name, f"unsupported file type {ext or '(none)'!r}: "
                                  "expected .csv, .whl, .mpt or .zip")
    if ext == ".zip":
        yield from _zip_records(data_or_stream, file_name, manifest, keep_raw, limits,
                                profile_reader)
    elif ext == ".csv":
        if keep_raw:
            csv_raw = RawMember.of(file_name, _read_all(data_or_stream))
            for record in _csv_records(io.BytesIO(csv_raw.data), file_name, limits,
                                       profile_reader):
                yield record, csv_raw
        else:
            for record in _csv_records(_as_stream(data_or_stream), file_name, limits,
                                       profile_reader):
                yield record, None
    else:
        data = _read_all(data_or_stream)
        lookup = _Manifest(_load_manifest(manifest, "manifest"), "manifest")
        raw = RawMember.of(file_name, data) if keep_raw else None
        for record in _miniprof_records(data, posixpath.basename(file_name), file_name,
                                        lookup):
            yield record, raw


def iter_upload(data_or_stream: bytes | BinaryIO, file_name: str, *,
                manifest: ManifestArg = None, limits: ZipLimits = DEFAULT_LIMITS,
                profile_reader: ProfileReader | None = None) -> Iterator[Record]:
    """Records of an uploaded file (CSV, MiniProf with ``manifest``, or zip), streaming.

    ``manifest`` (for a bare ``.whl``/``.mpt``): the result of ``read_manifest`` or the
    manifest CSV's bytes/stream. ``profile_reader`` reads long profile CSVs (default
    :func:`iter_profile_records`; the import parses them in its worker processes,
    :func:`wearcast.service.import_csv_blocks.read_profiles`). Raises ImportFileError on the
    first problem.
    """
    for record, _ in _iter(data_or_stream, file_name, manifest, False, limits,
                           profile_reader):
        yield record


def iter_upload_with_raw(data_or_stream: bytes | BinaryIO, file_name: str, *,
                         manifest: ManifestArg = None, limits: ZipLimits = DEFAULT_LIMITS
                         ) -> Iterator[tuple[Record, RawMember]]:
    """Like ``iter_upload`` but each record comes with the raw file it was read from (the
    same RawMember object for all records of one file), so the caller can keep raw files
    with their SHA-256. Each file is held in memory while its records are read (a zip
    member at most ``limits.max_member_bytes``); use ``iter_upload`` to stream a huge CSV.
    """
    for record, raw in _iter(data_or_stream, file_name, manifest, True, limits):
        assert raw is not None
        yield record, raw
