"""The Robot Plan Manager: when the robot acts, and where its head looks meanwhile.

JAHRVIS's RPM (Section VI-C.1) keeps the robot's beliefs about the plan,
decides which robot action to perform and when, and drives the head to
monitor the human's next expected action (which also gives joint attention).
Robot actions run through their action models (:class:`shary.recognition.
execution.RobotActions`: look, act, retry up to ``max_attempts``, then fail to
the plan); a task's open values are resolved when it starts
(:meth:`RobotPlanManager.resolve`): an AgentX actor is the first of its
candidates who is free and can reach the objects, a query parameter the first
answer of its SPARQL query over the fact base (the robot's perspective).
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Callable
from typing import Any

from shary.kernel.arbiter import WATCH
from shary.kernel.executors import Outcome, Reporter, Request, record_outcome
from shary.plans.tasks import PrimitiveTask, is_open

__all__ = ["RobotPlanManager"]


class RobotPlanManager:
    """Runs the robot's tasks of a plan and points its head (see the module)."""

    def __init__(self, sup: Any, models: Any):
        self.sup = sup
        self.models = models
        self.ontology = models.ontology
        self.busy: int | None = None
        """The robot's task under way, if any."""
        self._reporter = Reporter(self._outcome, sup.loop.call_soon)
        self._ids = itertools.count(1)
        self._waiting: dict[str, Callable[[Outcome], Any]] = {}

    # -- open values --------------------------------------------------------------------

    def resolve(self, task: PrimitiveTask, bound: dict[tuple, Any], busy: set[str]
                ) -> tuple[str, tuple[Any, ...]]:
        """The task's agent and parameters with its open values chosen now; ``bound``
        keeps each open variable's value for the other tasks of its decomposition."""
        agent = task.agent
        if is_open(agent):
            key = (task.decomposition, "agent", tuple(agent.get("any-of", ())))
            if key not in bound:
                bound[key] = self._choose_agent(task, agent.get("any-of", ()), busy, bound)
            agent = bound[key]
        params = []
        for value in task.params:
            if is_open(value) and "any-of" in value:
                value = agent
            elif is_open(value):
                key = (task.decomposition, value.get("var"))
                if key not in bound:
                    bound[key] = self._answer(value, agent)
                value = bound[key]
            params.append(value)
        return agent, tuple(params)

    def _choose_agent(self, task: PrimitiveTask, candidates: tuple[str, ...], busy: set[str],
                      bound: dict[tuple, Any]) -> str:
        """Who is free and can reach the task's (known) objects; else the first free one."""
        objects = [v for v in task.objects() if not is_open(v)]
        free = [c for c in candidates if c not in busy] or list(candidates)
        for agent in free:
            if all(self.sup.facts.holds(o, "isReachableBy", agent) for o in objects):
                return agent
        return free[0]

    def _answer(self, value: dict[str, Any], agent: str) -> Any:
        """The first answer of a query parameter (its candidates if it has none).

        The planner writes queries as Ontologenius is asked: ``:`` names the world's
        entities, ``a`` is its class relation (the fact base's ``type``); the query's
        other variable is the AgentX actor, chosen before it and bound here."""
        var = value.get("var", "x")
        query = re.sub(r"(?<=\s)a(?=\s)", ":type", str(value.get("query", "")))
        others = sorted(set(re.findall(r"\?(\w+)", query)) - {var})
        namespace = str(self.sup.facts.term("type"))[:-len("type")]
        try:
            rows = self.sup.facts.select(f"PREFIX : <{namespace}> SELECT ?{var} WHERE "
                                         f"{{ {query} }}", **dict.fromkeys(others, agent))
        except ValueError as err:  # a query the fact base refuses is said, not raised
            self.sup.record("plan-query", agent=self.sup.robot, query=query, error=str(err))
            rows = []
        answers = sorted(str(row[var]) for row in rows if row.get(var) is not None)
        self.sup.record("plan-query", agent=self.sup.robot, query=query, bound=agent,
                        answers=answers)
        candidates = answers or [str(c) for c in value.get("candidates", ())]
        return candidates[0] if candidates else None

    # -- acting -------------------------------------------------------------------------

    def model_for(self, name: str, side: dict[str, Any]) -> Any:
        """The action model of ``side`` (robot or human models) for a planner action."""
        cls = self.ontology.action_class(name)
        if cls is None:
            return None
        exact = [m for m in side.values() if self.ontology.action_class(m.name) == cls]
        if exact:
            return exact[0]
        wider = [m for m in side.values()
                 if (generic := self.ontology.action_class(m.name)) is not None
                 and self.ontology.is_a(cls, generic)]
        return wider[0] if wider else None

    def roles(self, name: str, objects: tuple[Any, ...]) -> dict[str, Any]:
        """role -> entity for a planner action's parameters after its agent."""
        cls = self.ontology.action_class(name)
        params = self.ontology.parameters(cls) if cls is not None else ()
        return {p.role: o for p, o in zip(params, objects, strict=False)}

    def perform(self, task: PrimitiveTask, node: str, objects: tuple[Any, ...],
                done: Callable[[str, str], Any]) -> None:
        """Run the robot's task; ``done(status, reason)`` once it ended."""
        model = self.model_for(task.name, self.models.robot)
        if model is None:
            self.sup.loop.call_soon(done, "failed", f"no robot action model for {task.name}")
            return
        roles = self.roles(task.name, objects)
        params = {role: roles.get(role) for role, _ in model.params}
        self.busy = task.id

        def over(result: Any) -> None:
            self.busy = None
            done(result.status, result.reason)

        self.sup.robot_actions.perform(model.name, params, node, over)

    def cancel(self, node: str) -> None:
        self.sup.robot_actions.cancel(node)

    def watch(self, target: Any, node: str, priority: int = WATCH) -> None:
        """Turn the head to what the human's next expected action is about (held, at
        the plan's priority, as long as ``node`` is not over: :mod:`shary.kernel.arbiter`)."""
        if target is not None:
            self.request("look-at", {"target": str(target)}, node, priority=priority)

    def request(self, atomic: str, args: dict[str, Any], node: str,
                done: Callable[[Outcome], Any] | None = None, priority: int = WATCH) -> None:
        """An atomic task of the robot's own (look, speak), logged like every other."""
        request = Request(f"p{next(self._ids)}", atomic, args, self.sup.robot, node, priority)
        if done is not None:
            self._waiting[request.id] = done
        self.sup.executors.dispatch(request, self._reporter, self.sup.record)

    def _outcome(self, outcome: Outcome) -> None:
        record_outcome(self.sup.record, outcome)
        done = self._waiting.pop(outcome.request.id, None)
        if done is not None:
            done(outcome)
