"""The planner port filled with the HATP-like planner of ``planner/``.

A planner-backed recipe hands its task to :class:`HatpPlanner`, which builds a
planning problem from the robot's facts (entities are the subjects of ``type``
facts naming a type of the domain; their attributes are the facts whose
predicate is the attribute's name), plans, and turns the plan into the act x
task's steps: each action becomes a step performed by the action's agent,
refined by a task or an atomic task of the recipe library (HATP stops at
actions such as MoveForManipulate; SHARY refines them), ordered by the plan's
causal links, its ordering constraints and each agent's stream, so that the
human's and the robot's steps run side by side when nothing orders them.

Besides the command line (``shary plan``, ``shary validate``), this is the
only part of ``shary`` that imports ``planner``.
"""

from __future__ import annotations

from typing import Any

import planner
from planner.domain import Domain, Problem, SelectedRule
from shary.recipes import Step, Term, parse_refinement


class PlanningFailed(RuntimeError):
    """No plan: the message explains where each top task got stuck."""


class HatpPlanner:
    """Plans a task from the facts with one domain (see the module's docstring)."""

    def __init__(self, domain: str | Domain, *, rules: dict[str, Any] | None = None,
                 budget_ms: float = 500.0, perspective: str = "robot"):
        self.domain = planner.load_domain(domain) if isinstance(domain, str) else domain
        self.rules = dict(rules or {})
        self.budget_ms = budget_ms
        self.perspective = perspective
        self.last: planner.Result | None = None

    def problem(self, facts: Any, task: str, args: dict[str, Any]) -> Problem:
        """The planning problem the facts describe, with one top task."""
        entities: dict[str, str] = {}
        for type_name in self.domain.types:
            rows = facts.select("SELECT ?e WHERE { ?e w:type ?t }", self.perspective,
                                t=facts.term(type_name))
            for row in rows:
                entities[str(row["e"])] = type_name
        initial: dict[tuple[str, str], Any] = {}
        for entity, type_name in entities.items():
            for attribute in self.domain.types[type_name].attributes:
                values = facts.objects(entity, attribute, self.perspective)
                if values:
                    initial[(entity, attribute)] = values[0]
        method = self.domain.task(task)
        if method is None:
            raise PlanningFailed(f"domain {self.domain.name!r} has no task {task!r}")
        try:
            top = tuple(args[name] for name, _ in method.params)
        except KeyError as err:
            raise PlanningFailed(f"{task} needs {err.args[0]!r}") from None
        rules = {name: SelectedRule(self.domain.rules[name],
                                    dict(p) if isinstance(p, dict) else {"default": float(p)})
                 for name, p in self.rules.items()}
        return Problem(f"{task}-from-facts", self.domain, entities, initial, ((task, top),),
                       rules=rules, budget_ms=int(self.budget_ms))

    def plan_steps(self, domain: str, task: str, args: dict[str, Any], facts: Any,
                   refine: dict[str, str]) -> list[Step]:
        """The Planner port of :class:`shary.supervisor.Supervisor`."""
        problem = self.problem(facts, task, args)
        result = planner.plan(problem, self.budget_ms)
        self.last = result
        if result.plan is None:
            raise PlanningFailed(f"no plan for {task}: {result.explain()}")
        return self.steps(result.plan, refine)

    def steps(self, plan: planner.Plan, refine: dict[str, str]) -> list[Step]:
        """A plan's actions as recipe steps, in a partial order."""
        names = {a.index: f"{a.index + 1}-{a.name.lower()}" for a in plan.actions}
        before: dict[int, set[int]] = {a.index: set() for a in plan.actions}
        for link in plan.links:
            before[link.consumer].add(link.producer)
        for first, second in plan.orderings:
            before[second].add(first)
        last: dict[str, int] = {}
        for action in sorted(plan.actions, key=lambda a: a.index):
            if action.agent in last:
                before[action.index].add(last[action.agent])
            last[action.agent] = action.index
        steps = []
        for action in sorted(plan.actions, key=lambda a: a.index):
            definition = self.domain.actions[action.name]
            values = {p: a for (p, _), a in zip(definition.params, action.args, strict=True)}
            if action.name not in refine:
                raise PlanningFailed(f"the plan's action {action.name} has no refinement; "
                                     f"add it under the recipe's plan.refine")
            target, mapping = parse_refinement(refine[action.name])
            step_args = {param: Term("const", values[source])
                         for param, source in mapping.items()}
            steps.append(Step(names[action.index], target, None, step_args,
                              Term("const", action.agent),
                              tuple(names[i] for i in sorted(before[action.index]))))
        return steps
