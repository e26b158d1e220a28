"""The scheme commands: ``schemes``, ``simulate``, ``render``, ``import-scxml``, ``conformance``."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path
from typing import Any

from shary import builtin
from shary.log.terminal import EXIT_BAD_INPUT, add_json_flag, emit_json, error, escape, listing
from shary.log.terminal import out as _out
from userfiles import yamlsafe
from userfiles.errors import FileError, Problem
from userfiles.outputs import OutputError, output_file, write_output

# -- schemes, simulate ---------------------------------------------------


def add_schemes(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("schemes", help="list the built-in communication schemes")
    add_json_flag(p, "the list")
    p.set_defaults(func=cmd_schemes)


def cmd_schemes(args: argparse.Namespace) -> int:
    from shary.io.schemes import load_scheme

    schemes = [(load_scheme(path), path) for path in builtin.files("schemes")
               if path.stem != "acts"]
    return listing("schemes", [(s.name, s.doc, path) for s, path in schemes],
                   json_mode=args.json)


def add_simulate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("simulate", help="run a scheme against a script of events and waits")
    p.add_argument("scheme", help="a built-in scheme name or a scheme file")
    p.add_argument("script", nargs="*", metavar="EVENT|WAIT",
                   help="events to send (H-AGREE, done …), with data as JSON after '=' "
                   "(H-AGREE='{\"object\": \"cup\"}'), and waits on the clock (5s, 250ms)")
    add_json_flag(p, "the trace")
    p.set_defaults(func=cmd_simulate)


_WAIT = re.compile(r"^[0-9]+(\.[0-9]+)?(ms|s|min|h)$")


def cmd_simulate(args: argparse.Namespace) -> int:
    from shary.io.schemes import load_scheme
    from shary.statechart.clock import SimulatedClock
    from shary.statechart.compiler import compile_scheme
    from shary.statechart.instance import LivelockError, SchemeListener
    from userfiles.limits import seconds
    from userfiles.schema import did_you_mean

    scheme = load_scheme(args.scheme)
    compiled = compile_scheme(scheme)
    script: list[tuple[str, Any]] = []
    for word in args.script:
        name, given, data = word.partition("=")
        try:
            script.append((name, json.loads(data) if given else None))
        except ValueError as err:
            return error(f"the data of {name!r} is not JSON: {err}", json_mode=args.json)
    unknown = [w for w, _ in script if not _WAIT.match(w) and not compiled.can_take(w)]
    if unknown:
        messages = [f"no state of {scheme.name} takes the event {word!r}"
                    f"{did_you_mean(word, compiled.descriptors())}" for word in unknown]
        for message in messages:
            error(message)
        if args.json:
            emit_json({"error": "; ".join(messages)})
        return EXIT_BAD_INPUT
    clock = SimulatedClock()
    trace: list[dict[str, Any]] = []

    def note(kind: str, line: str, **details: Any) -> None:
        """One step of the trace: printed as it happens, or kept for the JSON document."""
        if args.json:
            trace.append({"time": round(clock.now(), 6), "kind": kind, **details})
        else:
            _out.print(f"{clock.now():8.2f}s  {line}")

    def who(instance) -> str:  # type: ignore[no-untyped-def]  # a child's states: "helper/ask"
        return f"{instance.invoke_path}/" if instance.parent is not None else ""

    class Trace(SchemeListener):
        def invoking(self, instance, state, invoke):  # type: ignore[override]
            return self  # trace the invoked children too

        def entered(self, instance, state, event):  # type: ignore[override]
            act = f"  [cyan]{state.act} ({state.act_type.name})[/cyan]" if state.act_type else ""
            name = f"{who(instance)}{state.name}"
            note("enter", f"enter  {escape(name)}{act}", state=name, act=state.act,
                 act_type=state.act_type.name if state.act_type else None)

        def exited(self, instance, state, event):  # type: ignore[override]
            name = f"{who(instance)}{state.name}"
            note("exit", f"exit   {escape(name)}", state=name)

        def logged(self, instance, text):  # type: ignore[override]
            note("log", f"log    {escape(who(instance) + text)}", text=who(instance) + text)

        def finished(self, instance, state):  # type: ignore[override]
            name = f"{who(instance)}{state.name}"
            note("finished", f"[bold]{escape(who(instance))}finished in {state.name}[/bold]",
                 state=name)

    if not args.json:
        _out.print(f"[bold]{scheme.name}[/bold]: {escape(scheme.doc.strip())}")
    try:
        instance = compiled.start(clock=clock, listener=Trace())
        for word, data in script:
            if _WAIT.match(word):
                note("wait", f"[dim]wait {word}[/dim]", wait=word)
                clock.advance(seconds(word))
            else:
                shown = word if data is None else f"{word} {json.dumps(data)}"
                note("event", f"[yellow]<- {escape(shown)}[/yellow]", event=word,
                     **({} if data is None else {"data": data}))
                instance.send(word, data)
            if instance.finished:
                break
    except LivelockError as err:
        raise FileError([err.problem]) from None
    if args.json:
        emit_json({"scheme": scheme.name, "trace": trace, "finished": instance.finished,
                   "configuration": list(instance.configuration)})
    else:
        _out.print(f"configuration: {', '.join(instance.configuration)}")
    return 0


# -- render ---------------------------------------------------------------


def add_render(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("render", help="draw a diagram")
    what = p.add_subparsers(dest="what", required=True, metavar="WHAT")
    r = what.add_parser("scheme", help="draw a scheme to .svg, .png, .dot or .mmd (Mermaid)")
    r.add_argument("scheme", help="a built-in scheme name or a scheme file")
    r.add_argument("-o", "--output", type=Path, required=True,
                   metavar="OUT", help="the file to draw; its suffix says how: .svg or .png "
                   "(laid out by Graphviz), .dot or .gv (DOT text), .mmd or .mermaid "
                   "(Mermaid), .md (a Markdown page holding a Mermaid block)")
    r.add_argument("--active", default="", metavar="STATE,…",
                   help="highlight these states (an active configuration)")
    r.set_defaults(func=cmd_render_scheme)

    r = what.add_parser("tree", help="draw the task tree of a logged run, as it stood at a time")
    r.add_argument("log", type=Path, metavar="LOG", help="a context log (.sqlite)")
    r.add_argument("--at", type=float, default=None, metavar="T",
                   help="seconds of the run's clock (default: the end)")
    r.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="the file to draw: .svg or .png (laid out by Graphviz), .dot or .gv "
                   "(DOT text, for a tree too big to lay out)")
    r.set_defaults(func=cmd_render_tree)


def drawing_output(out: Path, *, mermaid: bool = False) -> None:
    """Refuse, before any work, a drawing command's ``-o`` whose suffix names no drawing
    it makes (a DOT graph's, or also Mermaid's for a scheme): ``-o out.gif`` is an output
    that cannot be written (exit 2), not a drawing that failed once a log was replayed or
    a plan searched."""
    from shary.log.display import DOT_SUFFIXES, SUFFIXES

    allowed = SUFFIXES if mermaid else DOT_SUFFIXES
    if out.suffix.lower() not in allowed:
        what = f"a {out.suffix} file" if out.suffix else "a file without a suffix"
        raise OutputError(out, f"cannot draw to {what}", f"use one of {', '.join(allowed)}")


def cmd_render_scheme(args: argparse.Namespace) -> int:
    from shary.io.schemes import load_scheme
    from shary.log.display import render_scheme

    output_file(args.output)
    drawing_output(args.output, mermaid=True)
    scheme = load_scheme(args.scheme)
    active = [s for s in args.active.split(",") if s]
    unknown = [s for s in active if s not in scheme.states]
    if unknown:
        return error(f"--active names unknown states: {', '.join(unknown)}")
    return draw(lambda: render_scheme(scheme, args.output, active=active), args.output)


def draw(drawing: Any, out: Path, detail: str = "", quiet: bool = False) -> int:
    """Run a drawing function; a drawing that cannot be made is an error, not a traceback."""
    try:
        drawing()
    except (ValueError, RuntimeError, OSError) as err:
        return error(str(err), status=1)
    if not quiet:
        _out.print(f"wrote {escape(str(out))}{detail}")
    return 0


def cmd_render_tree(args: argparse.Namespace) -> int:
    from shary.kernel.tasktree import MAX_DRAWN_NODES, replay_log
    from shary.log.contextlog import end_time
    from shary.log.display import TEXT_SUFFIXES, render_tree

    output_file(args.output)
    drawing_output(args.output)
    tree = replay_log(args.log, args.at)
    when = f"t = {args.at:g} s" if args.at is not None else f"end (t = {end_time(args.log):g} s)"
    if len(tree) > MAX_DRAWN_NODES and args.output.suffix.lower() not in TEXT_SUFFIXES:
        raise FileError([Problem(str(args.log), 1, 1, (
            f"the task tree at {when} has {len(tree)} nodes; shary lays out at most "
            f"{MAX_DRAWN_NODES} (draw an earlier time with --at, or write DOT text with "
            "-o tree.dot)"))])
    return draw(lambda: render_tree(tree, args.output, title=f"{args.log.name} at {when}"),
                args.output, f" ({len(tree)} nodes)")


# -- SCXML ------------------------------------------------------------------


def add_import_scxml(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("import-scxml", help="convert a data-model-free SCXML chart to a scheme")
    p.add_argument("source", type=Path, metavar="FILE.scxml")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="FILE.yaml")
    p.set_defaults(func=cmd_import_scxml)


def cmd_import_scxml(args: argparse.Namespace) -> int:
    from shary.io.scxml import import_scxml

    output_file(args.output, inputs=[args.source])
    write_output(args.output, import_scxml(args.source))
    _out.print(f"wrote {escape(str(args.output))}")
    return 0


def add_conformance(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("conformance", help="run the statechart tests found under DIR: SCION "
                       "pairs and plain charts, or the W3C IRP's tests (a DIR with its "
                       "manifest.xml) translated to shary's data model: the mandatory ones "
                       "decide, the optional ones are reported")
    p.add_argument("folder", type=Path, metavar="DIR")
    p.add_argument("--only", type=Path, metavar="LIST",
                   help="run only the charts named in this file (paths relative to DIR), e.g. "
                   "the suite's NO-DATAMODEL.txt (the charts with no ECMAScript)")
    add_json_flag(p, "every test's outcome")
    p.set_defaults(func=cmd_conformance)


def cmd_conformance(args: argparse.Namespace) -> int:
    from shary.statechart import w3c
    from shary.statechart.conformance import find_tests, run_test

    folder: Path = args.folder
    if not folder.is_dir():
        return error(f"{folder} is not a folder" if folder.exists() else
                     f"{folder}: no such folder (SCION's statechart suite is not part of the "
                     "repository: the README's section 'External suites' says how to clone "
                     "it)", json_mode=args.json)
    irp = w3c.is_irp(folder)
    charts = w3c.irp_tests(folder) if irp else find_tests(folder)
    if args.only is not None:
        wanted = set(yamlsafe.read_text(args.only).split())
        charts = [c for c in charts if str(c.relative_to(folder)) in wanted]
    outcomes = []
    for outcome in (w3c.run_irp(folder, charts) if irp
                    else (run_test(chart, folder) for chart in charts)):
        outcomes.append(outcome)
        if not outcome.passed and not args.json:
            _out.print(f"[red]FAIL[/red] {escape(outcome.name)}: {escape(outcome.reason)}")
    optional = list(w3c.run_irp(folder, w3c.irp_tests(folder, "optional"))) \
        if irp and args.only is None else []
    passed = sum(o.passed for o in outcomes)
    failed = len(outcomes) - passed
    if args.json:
        figures = {"folder": str(folder), "passed": passed, "failed": failed,
                   "tests": _outcomes(outcomes)}
        if optional:
            figures["optional"] = {"passed": sum(o.passed for o in optional),
                                   "failed": sum(not o.passed for o in optional),
                                   "tests": _outcomes(optional)}
        emit_json(figures)
    else:
        for outcome in optional:
            if not outcome.passed:
                _out.print(f"[yellow]optional FAIL[/yellow] {escape(outcome.name)}: "
                           f"{escape(outcome.reason)}")
        _out.print(f"{passed} passed, {failed} failed")
        if optional:
            ok = sum(o.passed for o in optional)
            _out.print(f"optional tests: {ok} passed, {len(optional) - ok} failed")
        if failed and args.only is None and (folder / "NO-DATAMODEL.txt").is_file():
            _out.print(f"[dim]shary reads no ECMAScript; the charts without it: "
                       f"--only {escape(str(folder / 'NO-DATAMODEL.txt'))}[/dim]")
    return 0 if failed == 0 else 1


def _outcomes(outcomes: list) -> list[dict]:
    return [{"name": o.name, "passed": o.passed, "reason": o.reason} for o in outcomes]
