"""Reading the keys of conditional problems: open variables, agendas, AgentX names.

The loader (:mod:`planner.io.domainfiles`) calls these with its builder, so that every
problem is reported at its line like the rest of the file: a domain's
``open`` variables (AgentX and query parameters, :class:`~planner.model.domain.OpenVar`)
and a problem's ``agendas`` (each agent's own tasks, in turn order).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from planner.model.domain import Action, Method, OpenVar
from userfiles.schema import did_you_mean


def _items(value: Any) -> list[tuple[str, Any]]:
    return list(value.items()) if isinstance(value, dict) else []


def open_vars(builder: Any, path: tuple, raw: Any, vars_: dict[str, str]
              ) -> tuple[OpenVar, ...]:
    """A decomposition's open variables: each must be one of its ``vars``; an AgentX's
    of an agent type."""
    out = []
    for var, spec in _items(raw):
        if var not in vars_:
            builder.problem(path + ("open", var), f"{var!r} is not a variable of this "
                            f"decomposition (declare it in vars){did_you_mean(var, vars_)}",
                            key=True)
            continue
        if isinstance(spec, dict) and "query" in spec:
            out.append(OpenVar(var, "query", query=str(spec["query"])))
            continue
        etype = builder.types.get(vars_[var])
        if etype is not None and not etype.agent:
            builder.problem(path + ("open", var), f"an AgentX variable must be of an agent "
                            f"type; {var!r} is a {vars_[var]}")
        names = spec.get("any-of") if isinstance(spec, dict) else None
        out.append(OpenVar(var, "agentx", any_of=tuple(str(n) for n in names or ())))
    return tuple(out)


def read_assigns(builder: Any, actions: dict[str, Action], methods: dict[str, Method]
                 ) -> dict[str, Action]:
    """The actions' ``assigns`` (once every task's parameters are known): each key a
    parameter of an agent type, each task written as a subtask over the parameters; and
    each decomposition's ``abandon`` a method of the domain."""
    out = dict(actions)
    for name, spec in _items(builder.data.get("actions")):
        if name not in actions or not isinstance(spec, dict):
            continue
        action = actions[name]
        variables = dict(action.params)
        assigns = []
        for param, texts in _items(spec.get("assigns")):
            path = ("actions", name, "assigns", param)
            kind = variables.get(param)
            if kind is None or kind not in builder.types or not builder.types[kind].agent:
                builder.problem(path, f"{param!r} is not a parameter of {name} naming an "
                                f"agent{did_you_mean(param, variables)}", key=True)
                continue
            subtasks = [builder._subtask(path + (i,), str(t), variables)
                        for i, t in enumerate(texts or [])]
            assigns.append((param, tuple(s for s in subtasks if s is not None)))
        if assigns:
            out[name] = dataclasses.replace(action, assigns=tuple(assigns))
    for name, spec in _items(builder.data.get("methods")):
        for index, dec in enumerate((spec or {}).get("decompositions") or []):
            target = dec.get("abandon") if isinstance(dec, dict) else None
            if target is not None and target not in methods:
                builder.problem(("methods", name, "decompositions", index, "abandon"),
                                f"unknown method {target!r}{did_you_mean(target, methods)}")
    return out


def read_agendas(builder: Any, entities: dict[str, str]
                 ) -> tuple[tuple[str, tuple[tuple[str, tuple[Any, ...]], ...]], ...]:
    """The problem's agendas: each key an agent of the problem, each task checked like the
    problem's ``tasks``; then the AgentX names of the methods they may reach."""
    domain = builder.domain
    agendas = []
    for agent, texts in _items(builder.data.get("agendas")):
        if entities.get(agent) is None or not domain.types[entities[agent]].agent:
            agents = [e for e, t in entities.items() if domain.types[t].agent]
            builder.problem(("agendas", agent), f"{agent!r} is not an agent of this problem"
                            f"{did_you_mean(agent, agents)}", key=True)
            continue
        agenda = [builder._task(("agendas", agent, i), str(t), entities)
                  for i, t in enumerate(texts or [])]
        agendas.append((agent, tuple(t for t in agenda if t is not None)))
    if agendas:
        if "tasks" in builder.data:
            builder.problem(("agendas",), "a problem has tasks (one plan) or agendas (a "
                            "conditional plan), not both", key=True)
        specs = builder.data.get("entities") or {}
        kinds = {agent: (specs.get(agent) or {}).get("kind") for agent, _ in agendas}
        if all(kind in domain.uncontrolled for kind in kinds.values()):
            builder.problem(("agendas",), "no agent of the agendas is controlled (the "
                            f"domain leaves the choices of {', '.join(domain.uncontrolled)} "
                            "to them): give the robot an agenda", key=True)
        _check_any_of(builder, entities, [name for _, tasks in agendas for name, _ in tasks])
    return tuple(agendas)


def _check_any_of(builder: Any, entities: dict[str, str], tops: list[str]) -> None:
    """The agents an AgentX names must be this problem's, of the variable's type (in the
    methods the agendas may reach)."""
    methods = builder.domain.methods
    reached: set[str] = set()
    todo = [t for t in tops if t in methods]
    while todo:
        name = todo.pop()
        if name not in reached:
            reached.add(name)
            todo.extend(s.task for d in methods[name].decompositions for s in d.subtasks
                        if s.task in methods)
    for method in (methods[name] for name in sorted(reached)):
        for dec in method.decompositions:
            kinds = dict(dec.vars)
            for open_var in dec.open:
                for name in open_var.any_of:
                    if entities.get(name) != kinds.get(open_var.var):
                        builder.problem(("agendas",), f"{method.name}[{dec.name}] leaves "
                                        f"{open_var.var} to any-of {list(open_var.any_of)}, "
                                        f"but {name!r} is not an entity of type "
                                        f"{kinds.get(open_var.var)} in this problem", key=True)
