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
    for task in branch:
        spec = plan.primitive[task]
        if task in executed or spec.kind != ACTION:
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
