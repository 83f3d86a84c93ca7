"""Import readers: parse and validate uploaded measurement files into records.

No database, no profile processing: each reader turns bytes or a binary stream plus a file
name into ``ProfileRecord`` / ``ParameterRecord`` objects, or raises ``ImportFileError``
naming the file, line, field and reason. ``iter_upload`` dispatches any upload.
"""

from wearcast.service.readers.bundle import (
    RawMember,
    ZipLimits,
    iter_upload,
    iter_upload_with_raw,
)
from wearcast.service.readers.errors import ImportFileError
from wearcast.service.readers.long_csv import iter_profile_records, sniff_kind
from wearcast.service.readers.manifest import read_manifest
from wearcast.service.readers.miniprof import MiniProfFile, parse_miniprof, to_wheel_frame
from wearcast.service.readers.parameter_csv import iter_parameter_records
from wearcast.service.readers.records import (
    MeasurementMeta,
    MeasurementMetaWithoutPoints,
    ParameterRecord,
    ProfileRecord,
)

__all__ = [
    "ImportFileError", "MeasurementMeta", "MeasurementMetaWithoutPoints", "MiniProfFile",
    "ParameterRecord", "ProfileRecord", "RawMember", "ZipLimits", "iter_parameter_records",
    "iter_profile_records", "iter_upload", "iter_upload_with_raw", "parse_miniprof",
    "read_manifest", "sniff_kind", "to_wheel_frame",
]
