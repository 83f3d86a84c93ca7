"""Ids written as text: a path or body value naming a row by its integer id or by a name.

``str.isdigit`` is true for characters ``int`` cannot read (superscripts such as ``"²"``) and
for digit strings beyond the 64-bit range a database id column holds, so a value counts as an
id only when it is ASCII digits whose integer fits that range; anything else is a name.
"""

from __future__ import annotations

#: The signed 64-bit range of the database's integer columns.
INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1


def int64_of_decimal(digits: str) -> int | None:
    """The integer a decimal string (optional sign, then digits) names when it lies in the
    signed 64-bit range, else None; leading zeros count for nothing however many there are,
    and a string beyond 19 significant digits is refused without ``int()``."""
    sign = -1 if digits.startswith("-") else 1
    significant = digits.lstrip("+-").lstrip("0")
    if len(significant) > 19:
        return None
    number = sign * int(significant or "0")
    return number if INT64_MIN <= number <= INT64_MAX else None


def decimal_id(value: str) -> int | None:
    """The id a string of ASCII digits (no sign) names, or None when it is not one."""
    if not (value.isascii() and value.isdigit()):
        return None
    return int64_of_decimal(value)
