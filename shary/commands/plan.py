"""``shary plan``: the HATP-like planner from the command line.

The command lives in the engine, not in :mod:`planner`: the planner imports
nothing from ``shary`` (it is a library anyone can use), while the command
needs the engine's terminal conventions and its renderer (Graphviz with the
``graphviz-pure`` fallback, :mod:`shary.log.display`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from shary.commands.schemes import draw, drawing_output
from shary.log.terminal import add_json_flag, emit_json, error, escape
from shary.log.terminal import err as _err
from shary.log.terminal import out as _out
from userfiles.outputs import output_file


def add_plan(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plan", help="plan a problem with the HATP-like planner")
    p.add_argument("domain", help="a built-in domain name or a domain file")
    p.add_argument("problem", type=Path, help="a problem file")
    p.add_argument("--budget-ms", type=int, default=None, metavar="N",
                   help="time budget (default: the problem's); the best plan so far is kept")
    p.add_argument("--max-depth", type=int, default=None, metavar="N",
                   help="decomposition depth budget (default 10,000 nested tasks)")
    p.add_argument("--max-nodes", type=int, default=None, metavar="N",
                   help="node budget (default 500,000 nodes expanded and bindings tried)")
    p.add_argument("--rules", default=None, metavar="RULE,…",
                   help="the social rules to apply (default: the problem's selection; "
                   "'none' for none)")
    add_json_flag(p, "the plan, its score and its validation")
    p.add_argument("--render", choices=("tree", "streams", "policy"),
                   help="draw the decomposition tree or the per-agent streams; for a "
                   "conditional problem (with agendas), tree is the explored options, streams "
                   "each branch's, policy the branches and the human decisions")
    p.add_argument("--mode", choices=("expected", "worst"), default=None,
                   help="conditional problems: a human decision costs its options' expected "
                   "cost or the worst (default: the problem's policy, else expected)")
    p.add_argument("--yaml", action="store_true",
                   help="conditional problems: print the plan (abstract and primitive tasks, "
                   "decisions, branches) as YAML")
    p.add_argument("-o", "--output", type=Path, metavar="OUT",
                   help="where --render draws (.svg, .png, .dot, .gv)")
    p.add_argument("--hddl", action="store_true",
                   help="DOMAIN and PROBLEM are HDDL files (total order, as in the IPC 2020 "
                   "HTN track); the search stops at the first plan (see --improve)")
    p.add_argument("--improve", action="store_true",
                   help="HDDL: after the first plan, look for better ones until --budget-ms")
    p.add_argument("--ipc", action="store_true",
                   help="print the plan in the IPC plan format (for HDDL problems)")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args: argparse.Namespace) -> int:
    import planner

    if args.render and args.output is None:
        return error("--render needs -o OUT", json_mode=args.json)
    if args.output is not None:
        output_file(args.output)
        drawing_output(args.output)
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
            return error(str(err.args[0]), json_mode=args.json)
    if problem.agendas:
        from shary.commands.conditional import plan_conditional

        return plan_conditional(args, problem)
    if args.render == "policy" or args.yaml:
        return error(f"{'--render policy' if args.render == 'policy' else '--yaml'} is for "
                     "conditional problems (with agendas)", json_mode=args.json)
    result = planner.plan(problem, args.budget_ms, first=args.hddl and not args.improve,
                          max_depth=args.max_depth, max_nodes=args.max_nodes)
    best = result.plan
    errors = planner.validate(problem, best) if best is not None else []
    if args.ipc:
        from planner.io.ipc import write_ipc

        if best is None:
            _err.print("[bold red]no plan[/bold red]: " + escape(result.explain()))
        else:
            sys.stdout.write(write_ipc(best, problem.spelling))
    elif args.json:
        emit_json(_plan_json(problem, result, errors))
    else:
        _print_plan(problem, result, errors)
    if best is not None and args.render:
        from planner.display.plans import streams_dot, tree_dot
        from shary.log.display import render_dot

        title = f"{problem.name} ({domain.name})"
        source = tree_dot(best, title) if args.render == "tree" else streams_dot(best, title)
        if draw(lambda: render_dot(source, args.output), args.output, quiet=args.json):
            return 1
    return 0 if best is not None and not errors else 1


def _plan_json(problem, result, errors) -> dict:  # type: ignore[no-untyped-def]
    best = result.plan
    out = {"problem": problem.name, "domain": problem.domain.name, "found": best is not None,
           "plans_found": result.plans_found, "expansions": result.expansions,
           "complete": result.complete, "elapsed_ms": round(result.elapsed_ms, 3),
           "exhausted": result.exhausted}
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
             else "search budget exhausted" + (": best so far" if best else "")
             if result.exhausted
             else "time budget reached: best so far")
    _out.print(f"[bold]{problem.name}[/bold] ({problem.domain.name}): {result.plans_found} "
               f"plan(s) in {result.elapsed_ms:.1f} ms, {result.expansions} expansions, {state}")
    if best is None:
        if result.exhausted:
            _out.print(f"[bold red]search budget exhausted[/bold red]: "
                       f"{escape(result.exhausted)}")
        if result.failures:
            _out.print("[bold red]no plan[/bold red]; where each top task got stuck:")
        for failure in result.failures:
            _out.print(f"  {escape(str(failure))}")
        return
    names = {a.index: str(a) for a in best.actions}
    for agent, actions in best.streams.items():
        _out.print(f"[bold]{agent}[/bold] ({problem.kind(agent) or 'agent'})")
        for a in actions:
            _out.print(f"  {a.start:6.1f} - {a.end:6.1f}  {escape(str(a))}  [dim]cost "
                       f"{a.cost:g}[/dim]")
    by_index = {a.index: a for a in best.actions}
    crossing = [k for k in best.links if by_index[k.producer].agent != by_index[k.consumer].agent]
    if crossing:
        _out.print("[bold]links between streams[/bold]")
        for link in crossing:
            _out.print(f"  {escape(names[link.producer])} -> {escape(names[link.consumer])}"
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
        _out.print(f"  [yellow]{escape(violation)}[/yellow]")
    if errors:
        _out.print("[bold red]the validator refuses this plan:[/bold red]")
        for error in errors:
            _out.print(f"  {escape(error)}")
    else:
        _out.print("[green]validated[/green]: every precondition, decomposition and goal holds")
