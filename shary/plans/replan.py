"""What is left of a plan, as agendas a planner can start from (for a replan).

When a plan fails at its level, the robot asks for a new one from what is now
true.  The goals are what the old plan still had to do: for each agent, in
the order of the branch being followed (the first option at each decision
still ahead), the highest task of the decomposition that nothing has been
done of yet, or the primitive task itself when every task above it has begun.
A ``PlaceRed(robot, red_cube_1)`` whose place failed is asked again whole;
a ``RobotStack`` half done is not restarted from its first pick.
"""

from __future__ import annotations

from typing import Any

from shary.plans.tasks import ACTION, SharedPlan, is_open

__all__ = ["remaining_agendas"]


def _call(name: str, params: tuple[Any, ...]) -> str | None:
    if any(is_open(p) for p in params):
        return None
    return f"{name}({', '.join(map(str, params))})"


def remaining_agendas(plan: SharedPlan, current: list[int], executed: set[int],
                      agents: dict[int, Any]) -> dict[str, list[str]]:
    """Agent -> the tasks (``Name(args)``) still to do (see the module)."""
    begun: set[int] = set()
    for task in executed:
        if task in plan.primitive:
            begun.update(plan.ancestors(task))
    branch: list[int] = []
    start = current[0] if current else None
    while start is not None:
        path = list(plan.path(start))
        branch.extend(path)
        following = plan.next(path[-1])
        start = following[0].id if following else None
    out: dict[str, list[str]] = {}
    emitted: set[int] = set()
    empty = _empty_by_task(plan)
    for task in branch:
        spec = plan.primitive[task]
        if task in executed:
            continue
        for hollow in empty.get(task, ()):
            _emit_abstract(plan, hollow, [hollow, *plan.ancestors(hollow)], begun, emitted, out)
        if spec.kind != ACTION:
            continue
        agent = agents.get(task, spec.agent)
        fresh = [a for a in plan.ancestors(task) if a not in begun]
        if fresh:
            top = fresh[-1]
            if top in emitted:
                continue
            emitted.add(top)
            abstract = plan.abstract[top]
            call = _call(abstract.name, abstract.params)
            agent = abstract.agent or agent
        else:
            call = _call(spec.name, spec.params)
        if call is not None and isinstance(agent, str):
            out.setdefault(agent, []).append(call)
    return out


def _empty_by_task(plan: SharedPlan) -> dict[int, list[int]]:
    """Primitive task -> the abstract tasks decomposed into nothing on the way to it.

    A task the planner found already done (``HumanTopBlue`` when the blue cube is
    placed, ``CheckDone`` when the green cube is covered) has no primitive task, so
    no branch passes through it; but after a failure it may be needed again (the
    human left the first blue cube to the robot: theirs now goes on top).  The
    planner opens such tasks while looking for an agent's next step, and ids are
    given in that order (the step's abstract tasks, then the step), so each belongs
    to the first primitive task after it.
    """
    parents = {t.decomposition for t in plan.primitive.values()}
    parents |= {a.decomposition for a in plan.abstract.values()}
    steps = sorted(plan.primitive)
    out: dict[int, list[int]] = {}
    for node in sorted(plan.abstract):
        if node in parents:
            continue
        owner = next((t for t in steps if t > node), None)
        if owner is not None:
            out.setdefault(owner, []).append(node)
    return out


def _emit_abstract(plan: SharedPlan, node: int, chain: list[int], begun: set[int],
                   emitted: set[int], out: dict[str, list[str]]) -> None:
    """Add the highest task above ``node`` (itself included) nothing has been done of."""
    fresh = [a for a in chain if a not in begun]
    if not fresh or fresh[-1] in emitted:
        return
    top = plan.abstract[fresh[-1]]
    emitted.add(fresh[-1])
    call = _call(top.name, top.params)
    if call is not None and isinstance(top.agent, str):
        out.setdefault(top.agent, []).append(call)
