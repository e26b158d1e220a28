"""What every ``shary`` command prints: coloured lines for people, one JSON document for programs.

The commands of every part (the engine's, the planner's, the simulator's) print
through these helpers so that they agree on two contracts:

* a problem in a user's file is a ``FILE:LINE:COL: error: …`` line on standard
  error, and any other error is one ``error: …`` line there;
* with ``--json``, standard output carries exactly one JSON document, whatever
  happens: the command's result, or ``{"problems": [...]}`` for refused files
  (each with ``file``, ``line``, ``col``, ``message``), or ``{"error": "..."}``.
  Errors still go to standard error as well, so a person watching sees them.
"""

from __future__ import annotations

import json
import re
import sys
from collections.abc import Sequence
from typing import Any

from rich.console import Console

from userfiles.errors import Problem
from userfiles.outputs import OutputError

EXIT_FAILED = 1
"""It ran, and the expectation failed (a scenario not met, no plan, a test failed)."""
EXIT_BAD_INPUT = 2
"""A file was refused or the command line asks for something that does not exist."""

out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)


def escape(text: str) -> str:
    """``text`` with rich markup made literal (file names and messages may hold ``[``)."""
    return text.replace("[", r"\[")


def print_problems(problems: Sequence[Problem]) -> None:
    """The ``FILE:LINE:COL: error: …`` lines, on standard error."""
    for problem in problems:
        location = f"{problem.file}:{problem.line}:{problem.col}:"
        err.print(f"[bold]{escape(location)}[/bold] [bold red]error:[/bold red] "
                  f"{escape(problem.message)}")


def problems_json(problems: Sequence[Problem]) -> list[dict[str, Any]]:
    """Problems as JSON objects (``file``, ``line``, ``col``, ``message``)."""
    return [{"file": p.file, "line": p.line, "col": p.col, "message": p.message}
            for p in problems]


def emit_json(document: Any) -> None:
    """Print one JSON document on standard output (plain: no rich markup, no wrapping)."""
    sys.stdout.write(json.dumps(document, sort_keys=True, default=str) + "\n")
    sys.stdout.flush()


def error(message: str, *, json_mode: bool = False, status: int = EXIT_BAD_INPUT) -> int:
    """Report an error that is not in a file: one ``error: …`` line; returns ``status``.

    In ``--json`` mode the same message is also the JSON document, so that a
    program reading standard output always gets one.
    """
    err.print(f"[bold red]error:[/bold red] {escape(message)}")
    if json_mode:
        emit_json({"error": message})
    return status


def refused(problems: Sequence[Problem], *, json_mode: bool = False) -> int:
    """Report refused files (standard error, and JSON in ``--json`` mode); returns 2."""
    print_problems(problems)
    if json_mode:
        emit_json({"problems": problems_json(problems)})
    return EXIT_BAD_INPUT


def output_refused(refusal: OutputError, *, json_mode: bool = False) -> int:
    """An output that cannot be written: ``PATH: error: … (hint)``; returns 2."""
    err.print(f"[bold]{escape(refusal.path)}:[/bold] [bold red]error:[/bold red] "
              f"{escape(refusal.message)} ({escape(refusal.hint)})")
    if json_mode:
        emit_json({"error": f"{refusal.path}: {refusal.message} ({refusal.hint})"})
    return EXIT_BAD_INPUT


def add_json_flag(parser: Any, what: str = "the result") -> None:
    """The ``--json`` flag, worded the same on every command."""
    parser.add_argument("--json", action="store_true",
                        help=f"print {what} as one JSON document on standard output "
                        "(docs/cli.md gives its shape)")


def listing(key: str, entries: Sequence[tuple[str, str, Any]], *, json_mode: bool) -> int:
    """A one-line-each list of named documents (``shary schemes``, ``shary scenarios``):
    ``entries`` are (name, doc, file); with ``--json``, one document under ``key``."""
    listed = [{"name": name, "summary": first_sentence(doc), "doc": " ".join(doc.split()),
               "file": str(file)} for name, doc, file in entries]
    if json_mode:
        emit_json({key: listed})
        return 0
    # the summaries in one column, after the longest name (up to a limit: past it, a
    # name too long for any column pushes its own summary only)
    width = max((min(len(item["name"]), MAX_NAME_COLUMN) for item in listed), default=0)
    for item in listed:
        out.print(f"[bold]{escape(item['name']):<{width}}[/bold] {escape(item['summary'])}")
    return 0


MAX_NAME_COLUMN = 40
"""The widest name column :func:`listing` makes."""


def first_sentence(doc: str) -> str:
    """A doc's first sentence, for one-line listings ("Fig. 2" does not end it)."""
    first = re.split(r"(?<!Fig)\.\s", " ".join(doc.split()), maxsplit=1)[0]
    return first.rstrip(".") + "."
