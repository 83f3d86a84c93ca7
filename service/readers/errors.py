"""The one error every reader raises: what is wrong, in which file, on which line and field."""

from __future__ import annotations


class ImportFileError(ValueError):
    """An uploaded measurement file that cannot be imported as it stands.

    Attributes
    ----------
    file : the file's name as uploaded (for a zip member: ``"upload.zip:dir/member.csv"``)
    line : 1-based line in that file (the CSV header is line 1), or ``None`` for the whole file
    field : the column or header key at fault, or ``None``
    reason : what is wrong, phrased for the person who has to fix the file

    ``str(error)`` reads e.g. ``fleet.csv line 17, field 'side': 'up' is not one of left, right``.
    """

    def __init__(self, file: str, reason: str, *, line: int | None = None,
                 field: str | None = None) -> None:
        self.file = file
        self.line = None if line is None else int(line)
        self.field = field
        self.reason = reason
        super().__init__(self._message())

    def _message(self) -> str:
        where = self.file
        if self.line is not None:
            where += f" line {self.line}"
        if self.field is not None:
            where += f", field '{self.field}'"
        return f"{where}: {self.reason}"

    def as_dict(self) -> dict[str, str | int | None]:
        """JSON-ready form for a 4xx body: ``{file, line, field, reason, message}``."""
        return {"file": self.file, "line": self.line, "field": self.field,
                "reason": self.reason, "message": str(self)}
