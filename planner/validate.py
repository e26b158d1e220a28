"""An independent plan validator: replay the plan and check everything again.

It does not trust the search: starting from the problem's initial state it
walks the decomposition tree depth first, checks that each top task is the
problem's, that each compound task uses one of its method's decompositions
with a binding of the right types whose precondition holds at that point and
whose subtasks are exactly the node's children, that each action's
precondition holds when its turn comes, that actions come in the plan's
order, and that the goals hold at the end.  Every plan in the tests goes
through it.
"""

from __future__ import annotations

from typing import Any

from planner.domain import Problem
from planner.plan import Plan, fact_text


def validate(problem: Problem, plan: Plan) -> list[str]:
    """Every way ``plan`` fails to be a valid solution of ``problem`` (empty: valid)."""
    domain = problem.domain
    errors: list[str] = []
    values: dict[tuple[str, str], Any] = dict(problem.initial)

    def get(entity: str, attribute: str) -> Any:
        return values.get((entity, attribute))

    if len(plan.roots) != len(problem.tasks):
        errors.append(f"the plan has {len(plan.roots)} top tasks, the problem "
                      f"{len(problem.tasks)}")
    for root, (name, args) in zip(plan.roots, problem.tasks, strict=False):
        node = plan.tree[root]
        if (node.task, tuple(node.args)) != (name, tuple(args)):
            errors.append(f"top task {node.task}{node.args} is not {name}{tuple(args)}")
    next_action = 0
    stack = list(reversed(plan.roots))
    while stack:
        node = plan.tree[stack.pop()]
        label = f"{node.task}({', '.join(str(a) for a in node.args)})"
        if node.action is not None:
            act = plan.actions[node.action]
            if node.action != next_action:
                errors.append(f"{label}: action {node.action} comes where action "
                              f"{next_action} was expected")
            next_action = node.action + 1
            action = domain.actions.get(act.name)
            if action is None or act.name != node.task or tuple(act.args) != tuple(node.args):
                errors.append(f"{label}: the tree and the action list disagree ({act})")
                continue
            env = {p: a for (p, _), a in zip(action.params, act.args, strict=True)}
            if action.performer(env) != act.agent:
                errors.append(f"{label}: performed by {act.agent}, not {action.performer(env)}")
            if action.pre is not None and not action.pre(env, get):
                errors.append(f"{label}: precondition false when its turn comes: "
                              f"{action.pre.text}")
            writes: list[tuple[tuple[str, str], Any]] = []

            def put(entity: str, attribute: str, value: Any, _w: list = writes) -> None:
                _w.append(((entity, attribute), value))

            action.apply(env, get, put)
            values.update(writes)
            continue
        method = domain.methods.get(node.task)
        if method is None:
            errors.append(f"{label}: no method {node.task!r} in the domain")
            continue
        dec = next((d for d in method.decompositions if d.name == node.decomposition), None)
        if dec is None:
            errors.append(f"{label}: {node.task} has no decomposition {node.decomposition!r}")
            continue
        env = {p: a for (p, _), a in zip(method.params, node.args, strict=True)}
        for var, kind in dec.vars:
            value = node.bindings.get(var)
            if not problem.is_a(value, kind):
                errors.append(f"{label}: variable {var} is bound to {value!r}, not a {kind}")
            env[var] = value
        if dec.pre is not None and not dec.pre(env, get):
            errors.append(f"{label}: decomposition {dec.name} used while its precondition is "
                          f"false: {dec.pre.text}")
        expected = [(s.task, tuple(a(env, get) for a in s.args)) for s in dec.subtasks]
        children = [(plan.tree[c].task, tuple(plan.tree[c].args)) for c in node.children]
        if expected != children:
            errors.append(f"{label}: subtasks {children} are not those of {dec.name}: "
                          f"{expected}")
        stack.extend(reversed(node.children))
    if next_action != len(plan.actions):
        errors.append(f"the tree covers {next_action} of the plan's {len(plan.actions)} "
                      "actions")
    for (entity, attribute), wanted in problem.goals.items():
        if values.get((entity, attribute)) != wanted:
            errors.append(f"goal {fact_text(entity, attribute)} == {wanted!r} does not hold at "
                          f"the end ({values.get((entity, attribute))!r})")
    return errors
