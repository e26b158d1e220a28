"""The ``shary`` command.

Problems in a user's file are printed as ``FILE:LINE:COL: error: …`` on
standard error and the command exits with status 2; nothing a file contains
can make it print a traceback.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rich.console import Console

from shary import builtin
from userfiles import yamlsafe
from userfiles.errors import FileError, Problem
from userfiles.outputs import OutputError, output_file, write_output
from userfiles.reader import allow_paths

EXIT_BAD_FILE = 2

_out = Console(highlight=False, soft_wrap=True)
_err = Console(stderr=True, highlight=False, soft_wrap=True)


def main(argv: Sequence[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    allow_paths(args.allow_path)
    try:
        return int(args.func(args) or 0)
    except FileError as err:
        _print_problems(err.problems)
        return EXIT_BAD_FILE
    except OutputError as err:  # PATH: error: … (no line: an output has none)
        _err.print(f"[bold]{_escape(err.path)}:[/bold] [bold red]error:[/bold red] "
                   f"{_escape(err.message)} ({_escape(err.hint)})")
        return EXIT_BAD_FILE
    except KeyboardInterrupt:
        return 130


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="shary", description="A SHARY-style supervision engine for robots that work "
        "with people.")
    parser.add_argument("--allow-path", action="append", default=[], type=Path,
                        metavar="FOLDER", help="a folder that user files may name files in, "
                        "besides their own folder (repeatable)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("validate", help="check schemes, acts, recipe libraries and Turtle files "
                       "(default: the built-in ones)")
    p.add_argument("paths", nargs="*", type=Path, metavar="PATH",
                   help="files to check; acts files among them extend the acts of the others, "
                   "recipe files are checked together with the built-in library")
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("schemes", help="list the built-in communication schemes")
    p.set_defaults(func=cmd_schemes)

    p = sub.add_parser("simulate", help="run a scheme against a script of events and waits")
    p.add_argument("scheme", help="a built-in scheme name or a scheme file")
    p.add_argument("script", nargs="*", metavar="EVENT|WAIT",
                   help="events to send (H-AGREE, done …) and waits on the clock (5s, 250ms)")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("render", help="draw a diagram")
    what = p.add_subparsers(dest="what", required=True, metavar="WHAT")
    r = what.add_parser("scheme", help="draw a scheme to .svg, .png, .dot or .mmd (Mermaid)")
    r.add_argument("scheme", help="a built-in scheme name or a scheme file")
    r.add_argument("-o", "--output", type=Path, required=True, metavar="OUT")
    r.add_argument("--active", default="", metavar="STATE,…",
                   help="highlight these states (an active configuration)")
    r.set_defaults(func=cmd_render_scheme)

    r = what.add_parser("tree", help="draw the task tree of a logged run, as it stood at a time")
    r.add_argument("log", type=Path, metavar="LOG", help="a context log (.sqlite)")
    r.add_argument("--at", type=float, default=None, metavar="T",
                   help="seconds of the run's clock (default: the end)")
    r.add_argument("-o", "--output", type=Path, required=True, metavar="OUT")
    r.set_defaults(func=cmd_render_tree)

    p = sub.add_parser("import-scxml", help="convert a data-model-free SCXML chart to a scheme")
    p.add_argument("source", type=Path, metavar="FILE.scxml")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="FILE.yaml")
    p.set_defaults(func=cmd_import_scxml)

    p = sub.add_parser("plan", help="plan a problem with the HATP-like planner")
    p.add_argument("domain", help="a built-in domain name or a domain file")
    p.add_argument("problem", type=Path, help="a problem file")
    p.add_argument("--budget-ms", type=int, default=None, metavar="N",
                   help="time budget (default: the problem's); the best plan so far is kept")
    p.add_argument("--rules", default=None, metavar="RULE,…",
                   help="the social rules to apply (default: the problem's selection; "
                   "'none' for none)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--render", choices=("tree", "streams"),
                   help="draw the decomposition tree or the per-agent streams")
    p.add_argument("-o", "--output", type=Path, metavar="OUT",
                   help="where --render draws (.svg, .png, .dot)")
    p.add_argument("--hddl", action="store_true",
                   help="DOMAIN and PROBLEM are HDDL files (total order, as in the IPC 2020 "
                   "HTN track); the search stops at the first plan (see --improve)")
    p.add_argument("--improve", action="store_true",
                   help="HDDL: after the first plan, look for better ones until --budget-ms")
    p.add_argument("--ipc", action="store_true",
                   help="print the plan in the IPC plan format (for HDDL problems)")
    p.set_defaults(func=cmd_plan)

    from shary.log import add_log_command

    add_log_command(sub)

    p = sub.add_parser("run", help="run a scenario on the simulated Jido (headless), judge it")
    p.add_argument("scenario", metavar="NAME|FILE",
                   help="a built-in scenario (see 'shary scenarios') or a scenario file")
    p.add_argument("--seed", type=int, default=0, help="seed of the people's random choices")
    p.add_argument("--gui", action="store_true", help="open PyBullet's window")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="where to write log.sqlite, tree.svg, timeline.svg, summary.json "
                   "(default: runs/NAME)")
    p.add_argument("--snapshots", action="store_true", help="also write PNG views at each act")
    p.add_argument("--quiet", action="store_true", help="print only the verdict")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("scenarios", help="list the built-in scenarios")
    p.set_defaults(func=cmd_scenarios)

    p = sub.add_parser("conformance", help="run SCION-style statechart tests found under DIR")
    p.add_argument("folder", type=Path, metavar="DIR")
    p.add_argument("--only", type=Path, metavar="LIST",
                   help="run only the charts named in this file (paths relative to DIR)")
    p.set_defaults(func=cmd_conformance)
    return parser


def _print_problems(problems: Sequence[Problem]) -> None:
    for problem in problems:
        location = f"{problem.file}:{problem.line}:{problem.col}:"
        _err.print(f"[bold]{_escape(location)}[/bold] [bold red]error:[/bold red] "
                   f"{_escape(problem.message)}")


def _escape(text: str) -> str:
    return text.replace("[", r"\[")


# -- validate -----------------------------------------------------------


def cmd_validate(args: argparse.Namespace) -> int:
    """Check files (by default the built-in ones): one report per file, each problem once,
    never ``ok`` for a file whose dependencies fail (see :mod:`shary.filekinds`)."""
    from shary.filekinds import builtin_files, validate

    reports = validate(list(args.paths) or builtin_files())
    for report in reports:
        _print_problems(report.problems)
    bad = [r for r in reports if not r.ok]
    for report in reports:
        if report.ok and report.kind is not None:
            _out.print(f"[green]ok[/green]    {_escape(report.file)}")
    if bad:
        count = sum(len(r.problems) for r in bad)
        _err.print(f"{count} problem(s) in {len(bad)} file(s) of {len(reports)} checked")
        return EXIT_BAD_FILE
    return 0


# -- schemes, simulate ---------------------------------------------------


def cmd_schemes(args: argparse.Namespace) -> int:
    from shary.io.schemes import load_scheme

    for path in builtin.files("schemes"):
        if path.stem == "acts":
            continue
        scheme = load_scheme(path)
        _out.print(f"[bold]{scheme.name:<24}[/bold] {_escape(_first_sentence(scheme.doc))}")
    return 0


def _first_sentence(doc: str) -> str:
    """A doc's first sentence, for one-line listings ("Fig. 2" does not end it)."""
    first = re.split(r"(?<!Fig)\.\s", " ".join(doc.split()), maxsplit=1)[0]
    return first.rstrip(".") + "."


def cmd_scenarios(args: argparse.Namespace) -> int:
    from sim.scenario import builtin_scenarios, load_scenario

    for name, path in builtin_scenarios().items():
        scenario = load_scenario(path)
        _out.print(f"[bold]{name:<26}[/bold] {_escape(_first_sentence(scenario.doc))}")
    return 0


def cmd_run(args: argparse.Namespace) -> int:
    from sim.run import run_scenario
    from sim.scenario import find_scenario

    try:
        path = find_scenario(args.scenario)
    except KeyError as err:
        _err.print(f"[bold red]error:[/bold red] {_escape(err.args[0])}")
        return EXIT_BAD_FILE
    from sim.narration import ConsoleReport

    out = args.out or Path("runs") / path.stem
    try:
        result = run_scenario(path, seed=args.seed, out=out, snapshots=args.snapshots,
                              gui=args.gui, report=None if args.quiet else ConsoleReport(_out))
    except RuntimeError as err:
        _err.print(f"[bold red]error:[/bold red] {_escape(str(err))}")
        return 1
    verdict = "[bold green]PASSED[/bold green]" if result.passed else "[bold red]FAILED[/bold red]"
    _out.print(f"{verdict} {result.scenario}: {result.simulated_seconds:.1f} s simulated in "
               f"{result.wall_seconds:.2f} s (x{result.real_time_factor:.0f} real time), "
               f"seed {result.seed}")
    for difference in result.differences:
        _out.print(f"  - {_escape(difference)}")
    _out.print(f"[dim]wrote {_escape(str(out))}/: "
               f"{', '.join(Path(v).name for k, v in result.outputs.items() if k != 'snapshots')}"
               + (f" and {len(result.outputs['snapshots'].split(', '))} snapshots"
                  if "snapshots" in result.outputs else "") + "[/dim]")
    return 0 if result.passed else 1


_WAIT = re.compile(r"^[0-9]+(\.[0-9]+)?(ms|s|min|h)$")


def cmd_simulate(args: argparse.Namespace) -> int:
    from shary.clock import SimulatedClock
    from shary.compiler import compile_scheme
    from shary.instance import LivelockError, SchemeListener
    from shary.io.schemes import load_scheme
    from shary.model import parse_duration
    from userfiles.schema import did_you_mean

    scheme = load_scheme(args.scheme)
    compiled = compile_scheme(scheme)
    unknown = [w for w in args.script if not _WAIT.match(w) and not compiled.can_take(w)]
    for word in unknown:
        _err.print(f"[bold red]error:[/bold red] no state of {scheme.name} takes the event "
                   f"{_escape(word)!r}{_escape(did_you_mean(word, compiled.descriptors()))}")
    if unknown:
        return EXIT_BAD_FILE
    clock = SimulatedClock()

    def who(instance) -> str:  # an invoked child's states read "helper/ask"
        return f"{instance.invoke_path}/" if instance.parent is not None else ""

    class Trace(SchemeListener):
        def invoking(self, instance, state, invoke):  # type: ignore[override]
            return self  # trace the invoked children too

        def entered(self, instance, state, event):  # type: ignore[override]
            act = f"  [cyan]{state.act} ({state.act_type.name})[/cyan]" if state.act_type else ""
            _out.print(f"{clock.now():8.2f}s  enter  {who(instance)}{state.name}{act}")

        def exited(self, instance, state, event):  # type: ignore[override]
            _out.print(f"{clock.now():8.2f}s  exit   {who(instance)}{state.name}")

        def logged(self, instance, text):  # type: ignore[override]
            _out.print(f"{clock.now():8.2f}s  log    {who(instance)}{_escape(text)}")

        def finished(self, instance, state):  # type: ignore[override]
            _out.print(f"{clock.now():8.2f}s  [bold]{who(instance)}finished in "
                       f"{state.name}[/bold]")

    _out.print(f"[bold]{scheme.name}[/bold]: {_escape(scheme.doc.strip())}")
    try:
        instance = compiled.start(clock=clock, listener=Trace())
        for word in args.script:
            if _WAIT.match(word):
                _out.print(f"{clock.now():8.2f}s  [dim]wait {word}[/dim]")
                clock.advance(parse_duration(word))
            else:
                _out.print(f"{clock.now():8.2f}s  [yellow]<- {_escape(word)}[/yellow]")
                instance.send(word)
            if instance.finished:
                break
    except LivelockError as err:
        raise FileError([err.problem]) from None
    _out.print(f"configuration: {', '.join(instance.configuration)}")
    return 0


# -- render ---------------------------------------------------------------


def cmd_render_scheme(args: argparse.Namespace) -> int:
    from shary.display import render_scheme
    from shary.io.schemes import load_scheme

    output_file(args.output)
    scheme = load_scheme(args.scheme)
    active = [s for s in args.active.split(",") if s]
    unknown = [s for s in active if s not in scheme.states]
    if unknown:
        _err.print(f"[bold red]error:[/bold red] --active names unknown states: "
                   f"{', '.join(unknown)}")
        return EXIT_BAD_FILE
    return _draw(lambda: render_scheme(scheme, args.output, active=active), args.output)


def _draw(draw: Any, out: Path, detail: str = "", quiet: bool = False) -> int:
    """Run a drawing function; a drawing that cannot be made is an error, not a traceback."""
    try:
        draw()
    except (ValueError, RuntimeError, OSError) as err:
        _err.print(f"[bold red]error:[/bold red] {_escape(str(err))}")
        return 1
    if not quiet:
        _out.print(f"wrote {_escape(str(out))}{detail}")
    return 0


def cmd_render_tree(args: argparse.Namespace) -> int:
    from shary.display import TEXT_SUFFIXES, render_tree
    from shary.log import end_time
    from shary.tasktree import MAX_DRAWN_NODES, replay_log

    output_file(args.output)
    tree = replay_log(args.log, args.at)
    when = f"t = {args.at:g} s" if args.at is not None else f"end (t = {end_time(args.log):g} s)"
    if len(tree) > MAX_DRAWN_NODES and args.output.suffix.lower() not in TEXT_SUFFIXES:
        raise FileError([Problem(str(args.log), 1, 1, (
            f"the task tree at {when} has {len(tree)} nodes; shary lays out at most "
            f"{MAX_DRAWN_NODES} (draw an earlier time with --at, or write DOT text with "
            "-o tree.dot)"))])
    return _draw(lambda: render_tree(tree, args.output, title=f"{args.log.name} at {when}"),
                 args.output, f" ({len(tree)} nodes)")


# -- planning ----------------------------------------------------------------


def cmd_plan(args: argparse.Namespace) -> int:
    import json

    import planner

    if args.render and args.output is None:
        _err.print("[bold red]error:[/bold red] --render needs -o OUT")
        return EXIT_BAD_FILE
    if args.output is not None:
        output_file(args.output)
    if args.hddl:
        problem = planner.load_hddl(args.domain, args.problem)
        domain = problem.domain
    else:
        domain = planner.load_domain(args.domain)
        problem = planner.load_problem(args.problem, domain)
    if args.rules is not None:
        try:
            problem.select_rules([] if args.rules == "none" else
                                 [r for r in args.rules.split(",") if r])
        except KeyError as err:
            _err.print(f"[bold red]error:[/bold red] {_escape(str(err.args[0]))}")
            return EXIT_BAD_FILE
    result = planner.plan(problem, args.budget_ms, first=args.hddl and not args.improve)
    best = result.plan
    errors = planner.validate(problem, best) if best is not None else []
    if args.ipc:
        from planner.ipc import write_ipc

        if best is None:
            _err.print("[bold red]no plan[/bold red]: " + _escape(result.explain()))
        else:
            sys.stdout.write(write_ipc(best))
    elif args.json:
        print(json.dumps(_plan_json(problem, result, errors), sort_keys=True))
    else:
        _print_plan(problem, result, errors)
    if best is not None and args.render:
        from planner.display import streams_dot, tree_dot
        from shary.display import render_dot

        title = f"{problem.name} ({domain.name})"
        source = tree_dot(best, title) if args.render == "tree" else streams_dot(best, title)
        if _draw(lambda: render_dot(source, args.output), args.output, quiet=args.json):
            return 1
    return 0 if best is not None and not errors else 1


def _plan_json(problem, result, errors) -> dict:  # type: ignore[no-untyped-def]
    best = result.plan
    out = {"problem": problem.name, "domain": problem.domain.name, "found": best is not None,
           "plans_found": result.plans_found, "expansions": result.expansions,
           "complete": result.complete, "elapsed_ms": round(result.elapsed_ms, 3)}
    if best is None:
        out["explanation"] = [str(f) for f in result.failures]
        return out
    out.update({
        "score": best.score, "criteria": best.criteria, "weights": best.weights,
        "breakdown": best.breakdown(), "violations": best.violations, "valid": not errors,
        "validation_errors": errors, "makespan": best.makespan,
        "actions": [{"index": a.index, "name": a.name, "args": list(a.args), "agent": a.agent,
                     "cost": a.cost, "start": a.start, "end": a.end} for a in best.actions],
        "streams": {agent: [a.index for a in acts] for agent, acts in best.streams.items()},
        "links": [{"from": k.producer, "to": k.consumer, "fact": k.fact}
                  for k in best.links]})
    return out


def _print_plan(problem, result, errors) -> None:  # type: ignore[no-untyped-def]
    best = result.plan
    state = ("first plan" if result.first else "search complete" if result.complete
             else "time budget reached: best so far")
    _out.print(f"[bold]{problem.name}[/bold] ({problem.domain.name}): {result.plans_found} "
               f"plan(s) in {result.elapsed_ms:.1f} ms, {result.expansions} expansions, {state}")
    if best is None:
        _out.print("[bold red]no plan[/bold red]; where each top task got stuck:")
        for failure in result.failures:
            _out.print(f"  {_escape(str(failure))}")
        return
    names = {a.index: str(a) for a in best.actions}
    for agent, actions in best.streams.items():
        _out.print(f"[bold]{agent}[/bold] ({problem.kind(agent) or 'agent'})")
        for a in actions:
            _out.print(f"  {a.start:6.1f} - {a.end:6.1f}  {_escape(str(a))}  [dim]cost "
                       f"{a.cost:g}[/dim]")
    by_index = {a.index: a for a in best.actions}
    crossing = [k for k in best.links if by_index[k.producer].agent != by_index[k.consumer].agent]
    if crossing:
        _out.print("[bold]links between streams[/bold]")
        for link in crossing:
            _out.print(f"  {_escape(names[link.producer])} -> {_escape(names[link.consumer])}"
                       f"  ({link.fact})")
    _out.print(f"[bold]score {best.score:g}[/bold] (makespan {best.makespan:g} s)")
    weighed = [n for n in best.criteria if best.weights.get(n, 0.0)]
    for name in weighed:
        value, weight = best.criteria[name], best.weights[name]
        _out.print(f"  {name:<24} {value:8.2f} x {weight:.3f} = {value * weight:8.2f}")
    others = [f"{n} {v:g}" for n, v in best.criteria.items() if n not in weighed]
    if others:
        _out.print(f"  [dim]not in the score: {', '.join(others)}[/dim]")
    for violation in best.violations:
        _out.print(f"  [yellow]{_escape(violation)}[/yellow]")
    if errors:
        _out.print("[bold red]the validator refuses this plan:[/bold red]")
        for error in errors:
            _out.print(f"  {_escape(error)}")
    else:
        _out.print("[green]validated[/green]: every precondition, decomposition and goal holds")


# -- SCXML ------------------------------------------------------------------


def cmd_import_scxml(args: argparse.Namespace) -> int:
    from shary.io.scxml import import_scxml

    output_file(args.output, inputs=[args.source])
    write_output(args.output, import_scxml(args.source))
    _out.print(f"wrote {_escape(str(args.output))}")
    return 0


def cmd_conformance(args: argparse.Namespace) -> int:
    from shary.conformance import find_tests, run_test

    folder: Path = args.folder
    if not folder.is_dir():
        _err.print(f"[bold red]error:[/bold red] {_escape(str(folder))} is not a folder")
        return EXIT_BAD_FILE
    charts = find_tests(folder)
    if args.only is not None:
        wanted = set(yamlsafe.read_text(args.only).split())
        charts = [c for c in charts if str(c.relative_to(folder)) in wanted]
    passed = failed = 0
    for chart in charts:
        outcome = run_test(chart, folder)
        if outcome.passed:
            passed += 1
        else:
            failed += 1
            _out.print(f"[red]FAIL[/red] {_escape(outcome.name)}: {_escape(outcome.reason)}")
    _out.print(f"{passed} passed, {failed} failed")
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
