"""The shared plan in the run's timeline: each task's states as bars (``plan-task`` rows).

:mod:`shary.log.lanes` calls :func:`plan_task` for each ``plan-task`` row that
:mod:`shary.plans.states` logs: a bar per state, in the lane of the agent who
does the task, as the robot believes it; a human's estimated view adds only
what differs from the robot's (NOT_SEEN), in that human's lane.
"""

from __future__ import annotations

from typing import Any

__all__ = ["PLAN_STATE_COLOURS", "plan_task"]

PLAN_STATE_COLOURS = {
    "TODO": "#9db9d8", "ONGOING": "#4e79a7", "NOT_STARTING": "#f28e2b",
    "NOT_FINISHED": "#e15759", "NOT_SEEN": "#b07aa1", "SUSPENDED": "#8c8c8c",
}
"""The task states drawn (PLANNED, EXECUTED and UNPLANNED are where bars end)."""


def plan_task(e: Any, open_items: dict[tuple[str, str | None], Any], items: list[Any],
              item_type: Any, shown_time: Any) -> None:
    """Turn one ``plan-task`` row into the timeline's items (see the module)."""
    d = e.data
    name, state = str(d["name"]), str(d.get("state"))
    doer = name.split("(", 1)[1].split(",")[0].rstrip(")").strip() if "(" in name else ""
    key = (str(e.task), e.agent)
    item = open_items.pop(key, None)
    if item is not None:
        item.end = e.time
    if not doer or state not in PLAN_STATE_COLOURS:
        return
    if d.get("estimate") and state != "NOT_SEEN":
        return  # a human's view says the same as the robot's
    item = item_type(e.agent if state == "NOT_SEEN" else doer, "plan-task", e.time, None,
                     f"{name} {state}",
                     f"{name}: {state} in {e.agent}'s view from {shown_time(e.time)} s"
                     + (f" ({d['reason']})" if d.get("reason") else ""), f"plan-{state}",
                     colour=PLAN_STATE_COLOURS[state],
                     attrs={"data-task": str(e.task), "data-state": state,
                            "data-start": repr(e.time)})
    items.append(item)
    open_items[key] = item
