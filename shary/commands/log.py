"""``shary log FILE…``: a context log's events listed for a person, a pipe or a file.

The log itself (:mod:`shary.log.contextlog`) is the run's archive: how rows are written,
committed, checked and streamed back.  This is the command that shows them,
and it changes for other reasons: how a table reads on a terminal, how long a
page is, what a pipe gets, how filters are spelled on the command line.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
from collections.abc import Iterator
from itertools import islice
from pathlib import Path
from typing import Any

from rich.markup import escape
from rich.text import Span, Text

from shary.log.contextlog import LogEvent, merged_events, printable, write_jsonl
from shary.log.terminal import err as _err
from shary.log.terminal import out as _out
from userfiles.outputs import open_output, output_file

TERMINAL_PAGE = 1000
"""Events ``shary log`` lists on a terminal without ``--limit`` before it says how to see
more: a terminal draws a few thousand lines a second, and a long run logs millions (into
a pipe or a file every event is written, at about a hundred thousand a second)."""
_LINES_PER_PRINT = 1000  # one print per line through rich is ten times slower
_BARE = re.compile(r"[^\s\"'=,\[\]{}\x00-\x1f]+")


def add_log(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``shary log FILE [filters] [--json | --jsonl OUT]`` to the ``shary`` command."""
    p = subparsers.add_parser(
        "log", help="list the events of a context log, filtered by task, agent, kind, time",
        description="List the events of a context log. Filters combine: an event is shown "
        "when it matches all of them.")
    p.add_argument("file", type=Path, nargs="+", metavar="FILE",
                   help="a context log (.sqlite) of a run; several (one per agent of a "
                   "distributed team) are merged into one view ordered by time")
    p.add_argument("--task", metavar="T", help="only the events of this task")
    p.add_argument("--agent", metavar="A", help="only the events of this agent")
    p.add_argument("--kind", metavar="K",
                   help="only this kind of event; a trailing * matches a prefix ('fact-*')")
    p.add_argument("--since", type=float, metavar="SECONDS",
                   help="only the events at or after this engine time")
    p.add_argument("--until", type=float, metavar="SECONDS",
                   help="only the events at or before this engine time")
    p.add_argument("--limit", type=_count, metavar="N", help="show at most N events")
    p.add_argument("--offset", type=_count, default=0, metavar="N",
                   help="skip the first N matching events (with --limit: pages)")
    output = p.add_mutually_exclusive_group()
    output.add_argument("--jsonl", type=Path, metavar="OUT",
                        help="write the events to OUT, one JSON object a line")
    output.add_argument("--json", action="store_true",
                        help="print the events as JSON lines instead of a table")
    p.set_defaults(func=cmd_log)


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, not {text!r}")
    return value


def cmd_log(args: argparse.Namespace) -> int:
    """Run ``shary log``; a bad log raises :class:`FileError`, a place that cannot be
    written :class:`OutputError`, for the CLI to print.

    Events are streamed: the first lines appear at once however long the log,
    and ``shary log run.sqlite | head`` stops reading when ``head`` is done.
    """
    filters: dict[str, Any] = {"task": args.task, "agent": args.agent, "kind": args.kind,
                               "since": args.since, "until": args.until,
                               "limit": args.limit, "offset": args.offset}
    if args.jsonl is not None:
        output_file(args.jsonl, inputs=args.file)
        with merged_events(args.file, **filters) as events, open_output(args.jsonl) as stream:
            count = write_jsonl(events, stream)
        _out.print(f"wrote {count} event(s) to {escape(str(args.jsonl))}")
        return 0
    page = TERMINAL_PAGE if args.limit is None and not args.json and _out.is_terminal \
        else None
    if page is not None:
        filters["limit"] = page + 1  # one more tells whether there are more
    with merged_events(args.file, **filters) as events:
        try:
            if args.json:
                write_jsonl(events, sys.stdout)
            else:
                stream = iter(events)
                _print_table(islice(stream, page) if page is not None else stream)
                if page is not None and next(stream, None) is not None:
                    _err.print(_more_hint(args, page), highlight=False)
            sys.stdout.flush()
        except BrokenPipeError:
            # The reader went away (| head): not an error. Python would complain
            # again when it flushes stdout at exit, so point stdout at nothing.
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


def _more_hint(args: argparse.Namespace, page: int) -> Text:
    """How to see the events after the first page, or fewer of them."""
    hint = (f"… more events after these {page}: the next ones with --offset "
            f"{args.offset + page} --limit {page}; fewer with --kind K ('fact-*'), --task T, "
            "--agent A, --since S, --until S; all of them with --limit N or through a pipe "
            f"(shary log {' '.join(str(f) for f in args.file)} | less)")
    return Text(hint, style="dim")


def _print_table(events: Iterator[LogEvent]) -> None:
    """One aligned line per event: greppable, and fast enough for a long log.

    Lines are printed in blocks as they are read; a column widens when a block
    needs it (a log of millions of events is never held whole).  On a terminal
    each block is one rich Text whose styled spans are computed from the
    column widths (a rich Table measures every cell, a millisecond a row); into
    a pipe or a file, where there is no colour to show, the lines are written
    as they are, about twenty times faster.
    """
    widths = [len(title) for title in ("time", "kind", "task", "agent")]
    styled = _out.is_terminal
    shown = 0
    while block := list(islice(events, _LINES_PER_PRINT)):
        rows = [(f"{e.time:.3f}", printable(e.kind), e.task and printable(e.task),
                 e.agent and printable(e.agent), _compact(e.data)) for e in block]
        widths = [max(w, *(len(row[i] or "-") for row in rows)) for i, w in enumerate(widths)]
        w_time, w_kind, w_task, w_agent = widths
        lines = [f"{time:>{w_time}}  {kind:<{w_kind}}  {task or '-':<{w_task}}  "
                 f"{agent or '-':<{w_agent}}  {data}" for time, kind, task, agent, data in rows]
        header = (f"{'time':>{w_time}}  {'kind':<{w_kind}}  {'task':<{w_task}}  "
                  f"{'agent':<{w_agent}}  data")
        if not styled:
            sys.stdout.write("".join(f"{line}\n" for line in ([header] if not shown else [])
                                     + lines))
        else:
            if not shown:
                _out.print(Text(header, style="bold"))
            _out.print(_styled(lines, rows, w_time + 2, w_time + w_kind + 4,
                               w_time + w_kind + w_task + 6))
        shown += len(rows)
    if not shown:
        _err.print("no matching events")


def _styled(lines: list[str], rows: list[tuple[str, str, str | None, str | None, str]],
            at_kind: int, at_task: int, at_agent: int) -> Text:
    """A block of table lines as one Text: kinds in cyan, missing names dim."""
    spans: list[Span] = []
    start = 0
    for line, (_, kind, task, agent, _) in zip(lines, rows, strict=True):
        spans.append(Span(start + at_kind, start + at_kind + len(kind), "cyan"))
        spans.extend(Span(start + at, start + at + 1, "dim")
                     for at, name in ((at_task, task), (at_agent, agent)) if name is None)
        start += len(line) + 1
    return Text("\n".join(lines), spans=spans)


def _compact(data: dict[str, Any]) -> str:
    """``key=value …`` with simple strings bare and everything else as compact JSON."""
    return " ".join(
        f"{key}={value}" if isinstance(value, str) and _BARE.fullmatch(value)
        else f"{key}={json.dumps(value, ensure_ascii=False, separators=(',', ':'))}"
        for key, value in data.items())
