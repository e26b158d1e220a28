"""Each task's state in each agent's view, run by the ``shared-plan-task`` scheme.

Table III of JAHRVIS gives nine states (PLANNED, TODO, ONGOING, EXECUTED,
SUSPENDED, UNPLANNED, NOT_STARTING, NOT_FINISHED, NOT_SEEN).  Their
transitions are a statechart of this project (``schemes/shared-plan-task.yaml``:
validated, drawable with ``shary render scheme shared-plan-task``), compiled once
and started once per task and per view; the timeouts that make a task
NOT_STARTING or NOT_FINISHED are that scheme's timers on the engine's clock.
The robot's view is the robot's own belief; a human's view is the robot's
estimate of what that human believes (:mod:`shary.plans.beliefs` reads it).

Every state entered is logged (``plan-task`` rows: the task, the view, the
state) and kept as a fact ``taskState`` of the task in that view's perspective
of the fact base, so that what a human is believed to know can be queried like
any other fact.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from shary.io.schemes import load_scheme
from shary.statechart.compiler import CompiledScheme, compile_scheme
from shary.statechart.instance import SchemeInstance, SchemeListener

__all__ = ["SCHEME", "STATES", "TaskStates", "table_name"]

SCHEME = "shared-plan-task"
STATES = ("PLANNED", "TODO", "ONGOING", "EXECUTED", "SUSPENDED", "UNPLANNED",
          "NOT_STARTING", "NOT_FINISHED", "NOT_SEEN")
OVER = frozenset({"EXECUTED", "UNPLANNED"})
"""States a task does not leave."""

_compiled: dict[str, CompiledScheme] = {}


def table_name(state: str) -> str:
    """The scheme's state name as Table III writes it (``not-seen`` -> ``NOT_SEEN``)."""
    return state.replace("-", "_").upper()


def compiled_scheme(name: str = SCHEME) -> CompiledScheme:
    """The task-state scheme, loaded, checked and compiled once per process."""
    found = _compiled.get(name)
    if found is None:
        found = _compiled[name] = compile_scheme(load_scheme(name))
    return found


class TaskStates(SchemeListener):
    """The state of every task of a plan in every view (see the module's documentation).

    ``changed(task, view, state)`` is called after each change, on the loop
    that delivers the events.
    """

    def __init__(self, sup: Any, views: list[str], names: dict[int, str], *,
                 prefix: str = "task", changed: Callable[[int, str, str], Any] | None = None,
                 scheme: str = SCHEME):
        self.sup = sup
        self.views = list(views)
        self.names = names
        self.prefix = prefix
        self.changed = changed
        self._scheme = compiled_scheme(scheme)
        self._instances: dict[tuple[int, str], SchemeInstance] = {}
        self._of: dict[int, tuple[int, str]] = {}
        self._state: dict[tuple[int, str], str] = {}
        for task in names:
            for view in self.views:
                self._start(task, view)

    def _start(self, task: int, view: str) -> None:
        key = (task, view)
        self._state[key] = "PLANNED"
        instance = self._scheme.start(clock=self.sup.loop.clock, listener=self)
        self._of[id(instance)] = key
        self._instances[key] = instance
        self.sup.facts.set(self.fact_name(task), "taskState", "PLANNED", perspective=view)

    def fact_name(self, task: int) -> str:
        return f"{self.prefix}-{task}"

    def state(self, task: int, view: str) -> str:
        return self._state[(task, view)]

    def send(self, task: int, event: str, views: list[str] | None = None,
             reason: str | None = None) -> None:
        """Deliver ``event`` to the task in ``views`` (all by default); an event a state
        does not expect changes nothing."""
        for view in self.views if views is None else views:
            key = (task, view)
            if key in self._instances and self._state[key] not in OVER:
                self._instances[key].send(event, reason)

    def entered(self, instance: SchemeInstance, state: Any, event: Any) -> None:
        key = self._of.get(id(instance))
        if key is None or not state.is_atomic:
            return
        name = table_name(state.name)
        if name == self._state[key] and event is not None:
            return
        self._state[key] = name
        self._entered(key, name, event)

    def _entered(self, key: tuple[int, str], name: str, event: Any) -> None:
        task, view = key
        reason = getattr(event, "data", None)
        self.sup.record("plan-task", task=self.fact_name(task), agent=view, state=name,
                        name=self.names[task], event=getattr(event, "name", None),
                        reason=reason if isinstance(reason, str) else None,
                        estimate=True if view != self.sup.robot else None)
        self.sup.facts.set(self.fact_name(task), "taskState", name, perspective=view)
        if self.changed is not None and event is not None:
            self.changed(task, view, name)

    def stop(self) -> None:
        """Stop every timer (a plan replaced or over); a task NOT_SEEN in a human's view
        stays so, to become EXECUTED there when they are told (what they missed does not
        go away with the plan: :mod:`shary.plans.beliefs`).  The follower hears of no
        change any more: its task numbers are the next plan's."""
        self.changed = None
        for key, instance in self._instances.items():
            if self._state[key] != "NOT_SEEN":
                instance.cancel()
