"""A conditional plan as the supervisor reads it: JAHRVIS's abstract and primitive tasks.

JAHRVIS (section VI-A.2) represents a shared plan as abstract tasks
λ = ⟨id, state, name, Δ⟩ and primitive tasks Π = ⟨id, state, name, agent,
params, preds, Δ⟩, where Δ is the id of the abstract task it was decomposed
from and preds the tasks that must be over before it starts.  The state is
the supervisor's to keep; the planner gives the rest, for the policy chosen by
:mod:`planner.conditional.policy`, unfolded into a tree:

* a primitive task's ``agent`` is an agent's name, or ``{"any-of": [...]}``
  (AgentX); a parameter is an entity's name, or ``{"query", "var",
  "candidates"}`` (a SPARQL query resolved when the step starts); ``kind``
  says whether it is an ``action`` or one of the turn markers ``wait`` (a
  human with nothing applicable), ``idle`` (an empty agenda) and ``done``;
* abstract and primitive tasks share one space of ids;
* each human choice with several options is a ``decision``: after which task,
  and for each option the task that starts its branch (a task says which
  decision and option it starts, so a supervisor that recognises the human's
  action knows the branch to follow), its probability and its cost;
* ``branches`` lists each leaf's tasks, root to leaf, and its cost.

The JSON Schema is ``planner/schemas/conditional-plan.schema.json``.
"""

from __future__ import annotations

from typing import Any

from planner.conditional.exploration import DONE, IDLE, LEAF_KIND, MARK, WAIT, OpenValue, Step
from planner.conditional.policy import Choice, Policy, performer

FORMAT = "shary-conditional-plan/1"
_KINDS = {WAIT: "wait", IDLE: "idle", DONE: "done"}


def _value(value: Any) -> Any:
    return value.as_json() if isinstance(value, OpenValue) else value


def to_dict(policy: Policy) -> dict[str, Any]:
    """The policy as abstract tasks, primitive tasks, decisions and branches (plain
    JSON/YAML data)."""
    problem = policy.problem
    out: dict[str, Any] = {
        "format": FORMAT, "problem": problem.name, "domain": problem.domain.name,
        "mode": policy.mode, "found": policy.root is not None,
        "cost": None if policy.cost is None else round(policy.cost, 6),
        "leaves_explored": policy.leaves, "agents": {
            agent: {"kind": problem.kind(agent),
                    "controlled": agent in policy.exploration.controlled}
            for agent in policy.exploration.order},
        "abstract": [], "primitive": [], "decisions": [], "branches": []}
    if policy.root is None:
        return out
    abstract: list[dict] = out["abstract"]
    primitive: list[dict] = out["primitive"]
    decisions: list[dict] = out["decisions"]
    ids = iter(range(1, 1 << 62))
    parents0 = {agent: [None] * len(tasks) for agent, tasks in problem.agendas}
    # (turn, each agent's agenda as the ids it was decomposed from, last task, path)
    stack: list[tuple[Choice, dict[str, list], int | None, list[int]]] = [
        (policy.root, parents0, None, [])]
    costs = iter(policy.branch_costs)
    while stack:
        node, parents, previous, path = stack.pop()
        if node.kind == LEAF_KIND:
            out["branches"].append({"tasks": path, "leaf": previous,
                                    "cost": round(next(costs), 6)})
            continue
        decision = None
        if node.kind == "and" and len(node.options) > 1:
            decision = {"id": f"d{len(decisions) + 1}", "agent": node.agent,
                        "after": previous, "options": []}
            decisions.append(decision)
        pending = []
        for index, (step, probability, child) in enumerate(node.options):
            mine = {agent: list(ids_) for agent, ids_ in parents.items()}
            task = _task(step, mine, ids, previous, abstract, policy)
            primitive.append(task)
            if decision is not None:
                task["decision"] = decision["id"]
                task["option"] = index
                decision["options"].append({
                    "task": task["id"], "label": str(step),
                    "via": [f"{e.method}[{e.decomposition}]" for e in step.expansions],
                    "probability": round(probability, 6),
                    "cost": round(step.cost + child.value, 6)})
            pending.append((child, mine, task["id"], path + [task["id"]]))
        stack.extend(reversed(pending))
    return out


def _task(step: Step, parents: dict[str, list], ids: Any, previous: int | None,
          abstract: list[dict], policy: Policy) -> dict[str, Any]:
    """The primitive task of a step, after the abstract tasks its decompositions open."""
    agenda = parents.setdefault(step.agent, [])
    for exp in step.expansions:
        parent = agenda.pop(0) if agenda else None
        if exp.method.startswith(MARK):  # the end of a task
            continue
        node = {"id": next(ids), "name": exp.method,
                "params": [_value(a) for a in exp.args], "agent": step.agent,
                "decomposition": parent, "method": exp.decomposition,
                "bindings": {k: _value(v) for k, v in exp.bindings}}
        abstract.append(node)
        del agenda[:exp.dropped]
        agenda[:0] = [node["id"]] * exp.subtasks
    parent = None
    if step.name not in _KINDS:
        parent = agenda.pop(0) if agenda else None
    for target, count in step.assigned:
        parents.setdefault(target, [])[:0] = [None] * count
    return {"id": next(ids), "name": step.name, "kind": _KINDS.get(step.name, "action"),
            "agent": _value(performer(policy.problem, step)),
            "params": [_value(a) for a in step.args],
            "predecessors": [] if previous is None else [previous],
            "decomposition": parent, "cost": step.cost, "duration": step.duration}
