"""``shary context LOG``: what an agent (or a team task) did over a period of a run.

The Context Manager's summaries (:mod:`shary.team.context`) from the command
line: ``shary context run.sqlite --agent K-10 --last 10min`` answers "what did
K-10 do in the last 10 minutes?" (of the run's clock, counted back from the
log's last event).  Durations are written as in every file (``10min``,
``90s``, ``1.5h``; :func:`userfiles.limits.seconds`).
"""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path
from typing import Any

from shary.log.terminal import add_json_flag, emit_json, error, escape
from shary.log.terminal import out as _out
from userfiles.limits import MAX_DURATION, seconds


def add_context(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("context", help="summarize what an agent or a team task did over a "
                       "period of a run (the Context Manager)",
                       description="Summarize a context log: the team tasks, questions and "
                       "answers, associations, control changes and atomic tasks of one agent "
                       "(or one team task, or everyone) over a period.")
    p.add_argument("file", type=Path, metavar="LOG", help="a context log (.sqlite) of a run")
    p.add_argument("--agent", metavar="A", help="only what this agent did or was asked")
    p.add_argument("--task", metavar="T", help="only what concerns this team task")
    p.add_argument("--last", type=_duration, metavar="DURATION",
                   help="the last DURATION of the run (10min, 90s, 1.5h)")
    p.add_argument("--since", type=_duration, metavar="TIME",
                   help="from this time of the run's clock (seconds, or 2min …)")
    p.add_argument("--until", type=_duration, metavar="TIME",
                   help="up to this time of the run's clock")
    add_json_flag(p, "the summary")
    p.set_defaults(func=cmd_context)


def _duration(text: str) -> float:
    try:
        amount = seconds(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a duration (write 10min, 90s, "
                                         "500ms or a number of seconds)") from None
    if amount > MAX_DURATION * 365:
        raise argparse.ArgumentTypeError(f"{text!r} is longer than a year")
    return amount


def cmd_context(args: argparse.Namespace) -> int:
    from shary.team.context import ContextManager

    if args.last is not None and args.since is not None:
        return error("give --last or --since, not both", json_mode=args.json)
    summary = ContextManager(args.file).summary(agent=args.agent, task=args.task,
                                                last=args.last, since=args.since,
                                                until=args.until)
    if args.json:
        emit_json(summary.as_json())
        return 0
    who = args.agent or (f"task {args.task}" if args.task else "the team")
    print_ = _out.print
    print_(f"[bold]{escape(who)}[/bold], {summary.since:.1f}s – {summary.until:.1f}s "
           f"of the run")
    if not summary.counts:
        print_("  nothing happened")
        return 0
    for task in summary.tasks:
        print_(f"  task {escape(str(task['task']))}: {task['outcome'] or 'still running'} "
               f"({_span(task)}) by {escape(str(task['agent']))}")
    for question in summary.questions:
        answer = _answered(question)
        image = (question.get("data") or {}).get("image")
        print_(f"  question {escape(repr(question.get('text')))} from "
               f"{escape(str(question.get('asker')))} -> {escape(answer)}"
               + (f" (image {escape(str(image))})" if image else ""))
    if summary.actions:
        atomic = Counter(a["atomic"] for a in summary.actions)
        busy = sum((a["end"] or summary.until) - a["start"] for a in summary.actions)
        print_(f"  {len(summary.actions)} atomic task(s), {busy:.1f}s busy: "
               + ", ".join(f"{escape(str(name))} x{count}" for name, count in atomic.items()))
    if summary.moments:
        print_("  what happened:")
        for time, text in summary.moments:
            print_(f"    {time:9.3f}  {escape(text)}")
    return 0


def _span(task: dict[str, Any]) -> str:
    start = "?" if task["start"] is None else f"{task['start']:.1f}s"
    end = "…" if task["end"] is None else f"{task['end']:.1f}s"
    return f"{start}–{end}"


def _answered(question: dict[str, Any]) -> str:
    if question.get("answer") is None:
        return "expired, no answer" if question.get("expired") else "no answer yet"
    if question.get("expired"):
        return f"expired, fell back to {question['answer']!r}"
    return f"{question['by']}: {question['answer']!r}"
