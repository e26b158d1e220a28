"""``shary plan`` on a conditional problem (one with ``agendas``): explore, choose, check.

The planner explores the humans' choices as branches (:mod:`planner.conditional.exploration`),
chooses the robot's best answer to each (:mod:`planner.conditional.policy`) and the
validator replays every branch with every AgentX and query candidate
(:func:`planner.evaluation.validate.validate_conditional`); this module prints or draws
the result.  ``--json`` and ``--yaml`` give the plan as the supervisor reads it
(:mod:`planner.conditional.sharedplan`, JSON Schema
``planner/schemas/conditional-plan.schema.json``).
"""

from __future__ import annotations

import argparse
import time

from planner.conditional.exploration import MAX_STEPS
from shary.commands.schemes import draw
from shary.log.terminal import emit_json, error, escape
from shary.log.terminal import out as _out
from userfiles import yamlsafe


def plan_conditional(args: argparse.Namespace, problem) -> int:  # type: ignore[no-untyped-def]
    from planner.conditional.exploration import explore
    from planner.conditional.policy import select
    from planner.conditional.sharedplan import to_dict
    from planner.evaluation.validate import validate_conditional

    if args.max_depth is not None and not 1 <= args.max_depth <= MAX_STEPS:
        return error(f"--max-depth is the turns per branch of a conditional plan: 1 to "
                     f"{MAX_STEPS:,}", json_mode=args.json)
    mode = args.mode or problem.policy.get("mode", "expected")
    started = time.process_time()
    exploration = explore(problem, max_steps=args.max_depth, max_nodes=args.max_nodes,
                          worst=mode == "worst")
    policy = select(problem, exploration, mode)
    elapsed = (time.process_time() - started) * 1000
    errors = validate_conditional(problem, policy) if policy.root is not None else []
    document = to_dict(policy)
    document.update({"valid": policy.root is not None and not errors,
                     "validation_errors": errors, "cpu_ms": round(elapsed, 3),
                     "turns": exploration.nodes, "exhausted": exploration.exhausted,
                     "explanation": exploration.dead_ends if policy.root is None else []})
    if args.json:
        emit_json(document)
    elif args.yaml:
        print(yamlsafe.dump(document), end="")
    else:
        _print(problem, policy, exploration, errors, elapsed)
    if policy.root is not None and args.render:
        from planner.display.policies import policy_dot, streams_dot, tree_dot
        from shary.log.display import render_dot

        title = f"{problem.name} ({problem.domain.name})"
        drawer = {"policy": policy_dot, "tree": tree_dot, "streams": streams_dot}[args.render]
        source = drawer(policy, title)
        if draw(lambda: render_dot(source, args.output), args.output,
                quiet=args.json or args.yaml):
            return 1
    return 0 if policy.root is not None and not errors else 1


def _print(problem, policy, exploration, errors, elapsed) -> None:  # type: ignore[no-untyped-def]
    from planner.display.policies import policy_lines

    _out.print(f"[bold]{problem.name}[/bold] ({problem.domain.name}): conditional plan, "
               f"{policy.leaves} branch(es) explored in {elapsed:.1f} ms of CPU "
               f"({exploration.nodes} turns and decompositions)")
    if policy.root is None:
        if exploration.exhausted:
            _out.print(f"[bold red]search budget exhausted[/bold red]: "
                       f"{escape(exploration.exhausted)}")
            return
        _out.print("[bold red]no conditional plan[/bold red]: no policy brings every "
                   "branch to its end; where branches ended:")
        reasons = list(exploration.dead_ends)
        if exploration.cut:
            reasons.append(f"{exploration.cut} branch(es) cut after {exploration.max_steps} "
                           "turns (the step budget: policy max_steps, or --max-depth)")
        if exploration.loops:
            reasons.append(f"{exploration.loops} branch(es) came back to a turn they had "
                           "been at, nothing changed (a loop)")
        for why in reasons:
            _out.print(f"  {escape(why)}")
        return
    if exploration.cut or exploration.loops:
        _out.print(f"[dim]{exploration.cut} branch(es) cut by the step budget, "
                   f"{exploration.loops} loop(s) that changed nothing[/dim]")
    for line in policy_lines(policy):
        _out.print(escape(line))
    _out.print(f"[bold]{policy.mode} cost {policy.cost:.4g}[/bold] over "
               f"{len(policy.branches)} branch(es) of the policy: "
               + ", ".join(f"{c:g}" for c in policy.branch_costs))
    if errors:
        _out.print("[bold red]the validator refuses this plan:[/bold red]")
        for message in errors:
            _out.print(f"  {escape(message)}")
    else:
        _out.print("[green]validated[/green]: every branch, with every AgentX and query "
                   "candidate")
