"""The one reader pipeline every format goes through: safe load, schema, meaning, limits.

A format's loader is a *meaning* function over a :class:`Reader`; :func:`read`
does the rest, the same way for every format::

    def meaning(reader: Reader) -> Scenario:
        timeout = reader.duration(("timeout",), reader.data.get("timeout", 180))
        ...
    scenario = read(path, SCHEMA, meaning)

1. safe load (:mod:`userfiles.yamlsafe`: size, depth, alias bombs, tags, and
   every number finite and bounded);
2. the format's JSON Schema (:mod:`userfiles.schema`); meaning checks only run
   on a file whose shape is right, so they never meet a number where a list
   was promised;
3. meaning: the loader resolves names and reports with :meth:`Reader.problem`;
   the shared checks (:meth:`Reader.duration`, :meth:`Reader.confined_path`)
   put the stated limit in the message (numbers are finite and bounded by the
   safe load, sizes by the event pass and the schema);
4. every problem found is raised at once as one :class:`FileError`.

Why one pipeline: the rule of docs/architecture.md ("User files") then holds
by construction, not by care in each loader.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from jsonschema import Draft202012Validator

from userfiles import yamlsafe
from userfiles.errors import FileError, Problem
from userfiles.limits import MAX_DURATION, seconds, show_seconds
from userfiles.schema import check, size_limits

T = TypeVar("T")

_allowed: list[Path] = []


def allow_paths(paths: Iterable[str | os.PathLike[str]]) -> None:
    """Folders that user files may name besides their own folder (``--allow-path``)."""
    _allowed[:] = [Path(p).resolve() for p in paths]


@dataclass
class Reader:
    """One user file being read: its located data and the problems found so far."""

    located: yamlsafe.Located
    problems: list[Problem] = field(default_factory=list)

    @property
    def file(self) -> str:
        return self.located.file

    @property
    def data(self) -> Any:
        return self.located.data

    @property
    def folder(self) -> Path:
        return Path(self.located.file).resolve().parent

    @property
    def shape_ok(self) -> bool:
        """Whether the file has no problem beyond what loading let through (a duplicate
        key keeps its first value): its shape is the schema's, so meaning checks meet
        the types the schema promised and can go on to report everything else."""
        return len(self.problems) <= len(self.located.problems)

    def problem(self, where: tuple, message: str, *, key: bool = False) -> None:
        """Record a problem at the value (or, with ``key``, the key) at path ``where``."""
        self.problems.append(self.located.problem(where, message, key=key))

    def problem_inside(self, where: tuple, offset: int, message: str) -> None:
        """Record a problem ``offset`` characters into the string at ``where`` (the
        column of an error in an expression written as a YAML string)."""
        self.problems.append(self.located.problem_inside(where, offset, message))

    def duration(self, where: tuple, value: Any, *, maximum: float = MAX_DURATION,
                 what: str = "duration") -> float:
        """Seconds in a duration (see :func:`seconds`), at most ``maximum`` (a day)."""
        try:
            amount = seconds(value)
        except ValueError:
            self.problem(where, f"{value!r} is not a duration (write 5s, 2min, 500ms or a "
                                "number of seconds)")
            return 0.0
        if not math.isfinite(amount) or amount > maximum:
            self.problem(where, f"{what} {value} is too long (the limit is "
                                f"{show_seconds(maximum)})")
            return 0.0
        return amount

    def confined_path(self, where: tuple, name: str, *,
                      roots: Iterable[Path] = ()) -> Path | None:
        """The file ``name`` (relative to this file's folder), if it stays inside
        (see :func:`confine`); otherwise a problem at ``where`` and None."""
        full, refusal = confine(self.file, name, roots=roots)
        if refusal is not None:
            self.problem(where, refusal)
        return full

    def done(self) -> None:
        """Raise every problem found so far, at once."""
        if self.problems:
            raise FileError(self.problems)


def confine(file: str | os.PathLike[str], name: str, *,
            roots: Iterable[Path] = ()) -> tuple[Path | None, str | None]:
    """The file that ``file`` names as ``name``, or why it may not name it.

    A user file may only name files below its own folder, below ``roots``
    (the package's data) or below an ``--allow-path`` folder; anything else is
    refused before it is opened, so nothing of a file that is not the user's
    can ever be read or quoted back.
    """
    folder = Path(file).resolve().parent
    full = (folder / name).resolve()
    inside = [folder, *(Path(r).resolve() for r in roots), *_allowed]
    if not any(full.is_relative_to(root) for root in inside):
        return None, (f"{name!r} is outside the folder of {Path(file).name} (a file may only "
                      "name files below its own folder; --allow-path FOLDER allows another)")
    if not full.is_file():
        return None, f"no file {name!r} next to {Path(file).name}"
    return full, None


def spelled(path: str | os.PathLike[str], *, like: str | os.PathLike[str] = "") -> str:
    """How to name a file in a message: as the file that names it is named (absolute if
    ``like`` is), else relative to the working folder when it is below it."""
    full = Path(path).resolve()
    if Path(like).is_absolute():
        return str(full)
    try:
        return str(full.relative_to(Path.cwd()))
    except ValueError:
        return str(full)


def checked(path: str | os.PathLike[str], schema: Draft202012Validator,
            text: str | None = None) -> Reader:
    """Steps 1 and 2 of the pipeline, for a format that reads several files together
    (a recipe library): the file loaded safely with the schema's size limits, and its
    shape problems recorded on the reader rather than raised.  ``text``, when given, is
    read as if it were the file at ``path`` (the names it gives resolve from that
    file's folder): a document made in memory, e.g. a campaign's variation of a file."""
    sizes = size_limits(schema)
    located = (yamlsafe.load_file(path, sizes=sizes) if text is None
               else yamlsafe.load_text(text, os.fspath(path), sizes=sizes))
    return Reader(located, check(located, schema))


def open_checked(path: str | os.PathLike[str], schema: Draft202012Validator,
                 text: str | None = None) -> Reader:
    """Steps 1 and 2 of the pipeline: a :class:`Reader` over a file whose shape is right."""
    reader = checked(path, schema, text)
    reader.done()
    return reader


def read(path: str | os.PathLike[str], schema: Draft202012Validator,
         meaning: Callable[[Reader], T], *, text: str | None = None) -> T:
    """The whole pipeline: load safely, check the schema, then ``meaning`` (which records
    problems on the reader); raise one :class:`FileError` with every problem.  With
    ``text``, that text is read in place of the file's (see :func:`checked`)."""
    reader = open_checked(path, schema, text)
    result = meaning(reader)
    reader.done()
    return result
