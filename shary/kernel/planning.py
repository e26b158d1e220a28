"""The planner port filled with the HATP-like planner of ``planner/``.

A planner-backed recipe hands its task to :class:`HatpPlanner`, which builds a
planning problem from the robot's facts (entities are the subjects of ``type``
facts naming a type of the domain; an attribute is read from the predicates
the recipe's ``plan.facts`` names for it — perception says ``isHolding``, the
domain says ``carries`` — or else from facts whose predicate is the
attribute's name), plans, and turns the plan into the act x task's steps:
each action becomes a step performed by the action's agent, refined by a task
or an atomic task of the recipe library (HATP stops at actions such as
MoveForManipulate; SHARY refines them), ordered by the plan's causal links,
its ordering constraints and each agent's stream, so that the human's and the
robot's steps run side by side when nothing orders them.

A refinement may also name a *method* of the domain (``AskHelp``): the whole
subtree the plan grew under it becomes one step, performed by the agent of
the method's first parameter.  That is how the human's part of a plan becomes
a joint task (the robot asks, the human acts, the robot monitors) rather than
orders sent to a person.

Besides the command line (``shary plan``, ``shary validate``), this is the
only part of ``shary`` that imports ``planner``.
"""

from __future__ import annotations

from typing import Any

import planner
from planner.model.domain import Assignment, Domain, Problem, SelectedRule
from shary.kernel.recipes import PlanSpec, Step, Term, parse_refinement


class PlanningFailed(RuntimeError):
    """No plan: the message explains where each top task got stuck."""


class HatpPlanner:
    """Plans a task from the facts with one domain (see the module's docstring)."""

    def __init__(self, domain: str | Domain, *, rules: dict[str, Any] | None = None,
                 budget_ms: float = 500.0, perspective: str = "robot"):
        self._domain = domain
        self.rules = dict(rules or {})
        self.budget_ms = budget_ms
        self.perspective = perspective
        self.last: planner.Result | None = None

    @property
    def domain(self) -> Domain:
        """The domain (given by name, it is read on first use)."""
        if isinstance(self._domain, str):
            self._domain = planner.load_domain(self._domain)
        return self._domain

    def problem(self, facts: Any, task: str, args: dict[str, Any],
                reading: dict[str, tuple[str, ...]] | None = None) -> Problem:
        """The planning problem the facts describe, with one top task.

        ``reading`` maps an attribute to the predicates it is read from (see
        :attr:`shary.kernel.recipes.PlanSpec.facts`).
        """
        reading = reading or {}
        entities: dict[str, str] = {}
        for type_name in self.domain.types:
            rows = facts.select("SELECT ?e WHERE { ?e w:type ?t }", self.perspective,
                                t=facts.term(type_name))
            for row in rows:
                entities[str(row["e"])] = type_name
        initial: dict[tuple[str, str], Any] = {}
        for entity, type_name in entities.items():
            for attribute in self.domain.types[type_name].attributes:
                value = self._read(facts, entity, reading.get(attribute, (attribute,)))
                if value is not None:
                    initial[(entity, attribute)] = value
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

    def _read(self, facts: Any, entity: str, predicates: tuple[str, ...]) -> Any:
        for predicate in predicates:
            if predicate.startswith("^"):
                rows = facts.select(f"SELECT ?s WHERE {{ ?s w:{predicate[1:]} ?e }}",
                                    self.perspective, e=facts.term(entity))
                values = sorted(str(row["s"]) for row in rows)
            else:
                values = facts.objects(entity, predicate, self.perspective)
            if values:
                return values[0]
        return None

    def plan_steps(self, spec: PlanSpec, args: dict[str, Any], facts: Any,
                   assigned: tuple[Any, ...] = ()) -> list[Step]:
        """The Planner port of :class:`shary.kernel.supervisor.Supervisor`; ``assigned`` are the
        steps people took on (plan negotiation: ``action``, ``things``, ``agent``, as
        :class:`shary.dialogue.negotiation.Taken`): the plan honours them."""
        problem = self.problem(facts, spec.task, args, spec.facts)
        problem.assigned = tuple(Assignment(a.action, tuple(a.things), a.agent)
                                 for a in assigned)
        result = planner.plan(problem, self.budget_ms)
        self.last = result
        if result.plan is None:
            raise PlanningFailed(f"no plan for {spec.task}: {result.explain()}")
        return self.steps(result.plan, spec.refine)

    def steps(self, plan: planner.Plan, refine: dict[str, str]) -> list[Step]:
        """A plan's actions as recipe steps, in a partial order.

        Each action is a unit, unless it lies under a method named in
        ``refine``: then the outermost such method's subtree is one unit.
        A unit comes after every unit that one of its actions has a causal
        link, an ordering or an earlier action of the same agent's stream
        from (for a collapsed subtree, the streams of the agents acting in it).
        """
        unit_of: dict[int, int] = {}   # action index -> its unit (first action index)
        units: dict[int, tuple[str, str, dict[str, Any], str]] = {}
        for root in plan.roots:
            self._units(plan, root, refine, unit_of, units)
        names = {u: f"{u + 1}-{units[u][0].lower()}" for u in units}
        before: dict[int, set[int]] = {u: set() for u in units}

        def order(first: int, second: int) -> None:
            a, b = unit_of[first], unit_of[second]
            if a != b:
                before[b].add(a)

        for link in plan.links:
            order(link.producer, link.consumer)
        for first, second in plan.orderings:
            order(first, second)
        last: dict[str, int] = {}
        for action in sorted(plan.actions, key=lambda a: a.index):
            if action.agent in last:
                order(last[action.agent], action.index)
            last[action.agent] = action.index
        steps = []
        for unit in sorted(units):
            _, text, values, agent = units[unit]
            target, mapping = parse_refinement(text)
            missing = [source for source in mapping.values() if source not in values]
            if missing:
                raise PlanningFailed(f"the refinement {text!r} names {', '.join(missing)}, "
                                     f"which the plan does not bind there")
            step_args = {param: Term("const", values[source])
                         for param, source in mapping.items()}
            steps.append(Step(names[unit], target, None, step_args, Term("const", agent),
                              tuple(names[u] for u in sorted(before[unit]))))
        return steps

    def _units(self, plan: planner.Plan, node_id: int, refine: dict[str, str],
               unit_of: dict[int, int], units: dict[int, tuple]) -> None:
        """Walk the decomposition tree, cutting it into units (see :meth:`steps`)."""
        stack = [node_id]
        while stack:
            node = plan.tree[stack.pop()]
            if node.action is not None:
                action = plan.actions[node.action]
                if action.name not in refine:
                    raise PlanningFailed(f"the plan's action {action.name} has no refinement; "
                                         f"add it under the recipe's plan.refine")
                definition = self.domain.actions[action.name]
                values = {p: a for (p, _), a in zip(definition.params, action.args,
                                                    strict=True)}
                unit_of[action.index] = action.index
                units[action.index] = (action.name, refine[action.name], values, action.agent)
            elif node.task in refine and (leaves := _leaves(plan, node.id)):
                method = self.domain.methods[node.task]
                values = {p: a for (p, _), a in zip(method.params, node.args, strict=True)}
                values.update(node.bindings)
                first = min(leaves)
                for index in leaves:
                    unit_of[index] = first
                units[first] = (node.task, refine[node.task], values, str(node.args[0]))
            else:
                stack.extend(reversed(node.children))


def _leaves(plan: planner.Plan, node_id: int) -> list[int]:
    """Indices of the actions under a node of the decomposition tree."""
    out, stack = [], [node_id]
    while stack:
        node = plan.tree[stack.pop()]
        if node.action is not None:
            out.append(node.action)
        stack.extend(node.children)
    return out


def planners_for(library: Any, *, budget_ms: float = 500.0) -> dict[str, HatpPlanner]:
    """A planner for each domain the library's planner-backed recipes name, each domain
    read now: a supervisor that is not a simulated run (``shary ros`` on a robot) finds
    a bad or missing domain when it starts (``FileError``, at its line), not when a
    person has already said yes to a task that needs it."""
    domains = sorted({recipe.plan.domain for recipe in library.recipes
                      if recipe.plan is not None})
    return {name: HatpPlanner(planner.load_domain(name), budget_ms=budget_ms)
            for name in domains}
