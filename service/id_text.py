"""Ids written as text: a path or body value naming a row by its integer id or by a name.

``str.isdigit`` is true for characters ``int`` cannot read (superscripts such as ``"²"``) and
for digit strings beyond the 64-bit range a database id column holds, so a value counts as an
id only when it is ASCII digits whose integer fits that range; anything else is a name.
"""

from __future__ import annotations

INT64_MAX = 2**63 - 1


def decimal_id(value: str) -> int | None:
    """The id a string of ASCII digits (no sign) names, or None when it is not one."""
    if not (value.isascii() and value.isdigit()):
        return None
    significant = value.lstrip("0")
    if len(significant) > 19:
        return None
    number = int(significant or "0")
    return number if number <= INT64_MAX else None
