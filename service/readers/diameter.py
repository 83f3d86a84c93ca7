"""The measured wheel diameter of an import (optional quantity ``diameter_mm`` [mm]).

Long and parameter CSVs and manifests carry it as the optional column ``diameter_mm`` (the
running diameter at the tape circle, 70 mm from the back face). A MiniProf file measured with
the instrument's diameter option carries ``DiameterTaperline=<mm>`` in its header; when the
manifest row leaves ``diameter_mm`` empty the import takes it from there (single-profile
files only). Nothing is guessed: a file without it gives no diameter.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

#: MiniProf header key of the diameter measured at the taperline (tape circle) [mm].
MINIPROF_DIAMETER_KEY = "DiameterTaperline"
#: Plausible railway wheel running diameters [mm] (light rail 500 to locomotives 1,250).
DIAMETER_RANGE_MM = (300.0, 1500.0)


def miniprof_diameter_mm(header: Mapping[str, str]) -> float | None:
    """``DiameterTaperline`` [mm] of a MiniProf header, None when absent or implausible."""
    raw = header.get(MINIPROF_DIAMETER_KEY)
    if raw is None:
        return None
    try:
        value = float(str(raw).strip())
    except ValueError:
        return None
    low, high = DIAMETER_RANGE_MM
    return value if math.isfinite(value) and low <= value <= high else None
