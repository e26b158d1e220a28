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

import itertools
from typing import Any

from planner.model.domain import Problem
from planner.model.plan import Plan, fact_text


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


def validate_conditional(problem: Problem, policy: Any) -> list[str]:
    """Every way a conditional plan (a :class:`~planner.conditional.policy.Policy`) fails:
    each branch is replayed from the initial state, with each agent's agenda, for
    **every** assignment of its open values (each AgentX candidate, each query
    candidate) -- the turns in order, each decomposition against the agenda's head (its
    precondition, its bindings, its subtasks), each action's precondition, the end of the
    controlled agendas and the goals at each leaf."""
    from planner.conditional.policy import walk

    if policy.root is None:
        return ["there is no conditional plan to check"]
    errors: list[str] = []
    for number, branch in enumerate(walk(policy.root), start=1):
        tokens = list(dict.fromkeys(_open_values([step for step, _ in branch])))
        for combo in itertools.product(*(t.candidates for t in tokens)):
            assignment = dict(zip(tokens, combo, strict=True))
            where = f"branch {number}" + (", " + ", ".join(
                f"{t}={v}" for t, v in assignment.items()) if assignment else "")
            for error in _replay_branch(problem, policy, [s for s, _ in branch], assignment):
                errors.append(f"{where}: {error}")
                break
    return errors


def _open_values(steps: list) -> list:
    from planner.conditional.exploration import OpenValue

    found = []
    for step in steps:
        for value in step.args:
            if isinstance(value, OpenValue):
                found.append(value)
        for exp in step.expansions:
            found.extend(v for _, v in exp.bindings if isinstance(v, OpenValue))
    return found


def _replay_branch(problem: Problem, policy: Any, steps: list, assignment: dict) -> list[str]:
    from planner.conditional.exploration import DONE, IDLE, MARK, WAIT, OpenValue, marked_methods

    domain = problem.domain
    marked = marked_methods(problem)
    values: dict[tuple[str, str], Any] = dict(problem.initial)
    order = [agent for agent, _ in problem.agendas]
    controlled = policy.exploration.controlled
    agendas = {agent: list(tasks) for agent, tasks in problem.agendas}

    def get(entity: str, attribute: str) -> Any:
        return values.get((entity, attribute))

    def resolve(env: dict) -> dict:
        return {k: assignment.get(v, v) if isinstance(v, OpenValue) else v
                for k, v in env.items()}

    for turn, step in enumerate(steps):
        label = f"step {turn + 1} {step} by {step.agent}"
        if step.agent != order[turn % len(order)]:
            return [f"{label}: it is {order[turn % len(order)]}'s turn"]
        agenda = agendas[step.agent]
        for exp in step.expansions:
            if exp.method.startswith(MARK) and agenda and agenda[0] == (exp.method, ()):
                del agenda[0]
                continue
            if not agenda or agenda[0] != (exp.method, tuple(exp.args)):
                return [f"{label}: {exp.method}{tuple(exp.args)} is not at the head of "
                        f"{step.agent}'s agenda"]
            method = domain.methods.get(exp.method)
            dec = next((d for d in method.decompositions if d.name == exp.decomposition),
                       None) if method else None
            if dec is None:
                return [f"{label}: {exp.method} has no decomposition {exp.decomposition!r}"]
            env = dict(zip((p for p, _ in method.params), exp.args, strict=True))
            env.update(exp.bindings)
            for var, kind in dec.vars:
                value = env.get(var)
                value = assignment.get(value, value) if isinstance(value, OpenValue) else value
                if not problem.is_a(value, kind):
                    return [f"{label}: {exp.method}[{dec.name}] binds {var} to {value!r}, "
                            f"not a {kind}"]
            if dec.pre is not None and not dec.pre(resolve(env), get):
                return [f"{label}: {exp.method}[{dec.name}] used while its precondition is "
                        f"false: {dec.pre.text}"]
            if method.first:
                first = _first_choice(problem, method, env, resolve, get)
                if first != (dec.name, exp.bindings):
                    return [f"{label}: {exp.method} chooses its first applicable "
                            f"decomposition, {first}, not {dec.name}"]
            subtasks = [(s.task, tuple(a(env, get) for a in s.args)) for s in dec.subtasks]
            if method.name in marked:
                subtasks.append((MARK + method.name, ()))
            if len(subtasks) != exp.subtasks:
                return [f"{label}: {exp.method}[{dec.name}] has {len(subtasks)} subtasks, "
                        f"the plan says {exp.subtasks}"]
            rest = agenda[1:]
            if dec.abandon is not None:
                end = (MARK + dec.abandon, ())
                if end not in rest:
                    return [f"{label}: {exp.method}[{dec.name}] abandons {dec.abandon}, "
                            "which it is not part of"]
                rest = rest[rest.index(end) + 1:]
            if len(agenda) - 1 - len(rest) != exp.dropped:
                return [f"{label}: {exp.method}[{dec.name}] drops {len(agenda) - 1 - len(rest)}"
                        f" tasks, the plan says {exp.dropped}"]
            agenda[:] = subtasks + rest
        if step.name in (IDLE, DONE):
            if agenda:
                return [f"{label}: {step.agent}'s agenda is not empty"]
            if step.name == DONE and any(agendas[a] for a in order if a in controlled):
                return [f"{label}: a controlled agent's agenda is not empty"]
            continue
        if step.name == WAIT:
            if step.agent in controlled or not agenda:
                return [f"{label}: only a human with tasks left waits"]
            continue
        action = domain.actions.get(step.name)
        if action is None or not agenda or agenda[0] != (step.name, tuple(step.args)):
            return [f"{label}: not the head of {step.agent}'s agenda"]
        env = resolve(dict(zip(action.names, step.args, strict=True)))
        if action.pre is not None and not action.pre(env, get):
            return [f"{label}: precondition false when its turn comes: {action.pre.text}"]
        writes: list[tuple[tuple[str, str], Any]] = []
        action.apply(env, get, lambda e, a, v, _w=writes: _w.append(((e, a), v)))
        values.update(writes)
        del agenda[0]
        for param, subtasks in action.assigns:
            target = env[param]
            if target not in agendas:
                return [f"{label}: gives tasks to {target}, who has no agenda"]
            agendas[target][:0] = [(s.task, tuple(a(env, get) for a in s.args))
                                   for s in subtasks]
    if any(agendas[a] for a in order if a in controlled):
        return ["the branch ends before every controlled agenda is done"]
    for (entity, attribute), wanted in problem.goals.items():
        if values.get((entity, attribute)) != wanted:
            return [f"goal {fact_text(entity, attribute)} == {wanted!r} does not hold at the "
                    f"leaf ({values.get((entity, attribute))!r})"]
    return []


def _first_choice(problem: Problem, method: Any, env: dict, resolve: Any, get: Any
                  ) -> tuple[str, tuple] | None:
    """A ``choose: first`` method's choice: its first decomposition and binding (closed
    variables, in name order) whose precondition holds."""
    for dec in method.decompositions:
        opened = {o.var for o in dec.open}
        closed = [(v, k) for v, k in dec.vars if v not in opened]
        for values in itertools.product(*(problem.of_type(k) for _, k in closed)):
            trial = {**env, **dict(zip((v for v, _ in closed), values, strict=True))}
            if dec.pre is None or dec.pre(resolve(trial), get):
                return dec.name, tuple((v, trial[v]) for v, _ in dec.vars)
    return None
