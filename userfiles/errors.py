"""Problems found in files that users write, reported as ``FILE:LINE:COL: error: …``.

Every loader collects all the problems of a file before giving up, so a user
fixes a file in one round instead of one error at a time.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, order=True)
class Problem:
    """One problem at a position of a file (line and column count from 1)."""

    file: str
    line: int
    col: int
    message: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}: error: {self.message}"


class FileError(Exception):
    """A file was refused; ``problems`` lists every reason, in file order."""

    def __init__(self, problems: list[Problem]):
        self.problems = sorted(set(problems))
        super().__init__("\n".join(str(p) for p in self.problems))
