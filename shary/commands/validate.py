"""``shary validate``: check the files users write, each against its schema and for meaning.

What is checked, and how a file's kind is known, is :mod:`shary.io.filekinds`;
the simulator adds its scenarios and profiles there by entry point.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from shary.log.terminal import EXIT_BAD_INPUT, add_json_flag, emit_json, escape, print_problems
from shary.log.terminal import err as _err
from shary.log.terminal import out as _out

EXIT_BAD_FILE = EXIT_BAD_INPUT


def add_validate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("validate", help="check schemes, acts, recipe libraries and Turtle files "
                       "(default: the built-in ones)")
    p.add_argument("paths", nargs="*", type=Path, metavar="PATH",
                   help="files to check, or folders (the .yaml, .yml and .ttl files directly "
                   "in each); acts files among them extend the acts of the others, "
                   "recipe files are checked together with the built-in library")
    add_json_flag(p, "each file's report")
    p.set_defaults(func=cmd_validate)


def cmd_validate(args: argparse.Namespace) -> int:
    """Check files (by default the built-in ones): one report per file, each problem once,
    never ``ok`` for a file whose dependencies fail (see :mod:`shary.io.filekinds`)."""
    from shary.io.filekinds import shipped_files, validate

    paths = list(args.paths) or shipped_files()
    reports = validate(paths)
    for report in reports:
        print_problems(report.problems)
        for note in report.notes:
            _err.print(escape(f"{note.file}:{note.line}:{note.col}: note: {note.message}"))
    bad = [r for r in reports if not r.ok]
    if args.json:
        emit_json({"files": [r.as_json() for r in reports]})
    else:
        for report in reports:
            if report.ok and report.kind is not None:
                _out.print(f"[green]ok[/green]    {escape(report.file)}")
    if bad:
        count = sum(len(r.problems) for r in bad)
        _err.print(f"{count} problem(s) in {len(bad)} file(s) of {len(reports)} checked")
        return EXIT_BAD_FILE
    return 0
