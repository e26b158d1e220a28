"""The StackBuildingTask's plans: the first from the planner's problem, the next ones
from what the robot now believes.

:func:`first_plan` plans ``planner/problems/stack.yaml`` (or another problem of
the ``stack`` domain) into a :class:`~shary.plans.tasks.SharedPlan`.
:class:`Replanner` is the follower's ``replan`` port: it writes the problem
again with each block's ``on``, ``top`` and ``loose`` and each agent's
``holding`` taken from the robot's perspective of the fact base, the agendas
the follower gives (what the old plan still had to do), and plans it.
"""

from __future__ import annotations

import re
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import planner
from planner.conditional.exploration import explore
from planner.conditional.policy import select
from planner.conditional.sharedplan import to_dict
from planner.model.domain import Domain, Problem
from shary.plans.tasks import SharedPlan
from userfiles import yamlsafe
from userfiles.errors import FileError

__all__ = ["Replanner", "StackFiles", "first_plan", "problem_path"]


def problem_path(name: str) -> Path:
    """A built-in planner problem by name (``stack``), or a path."""
    found = next((p for p in planner.builtin_problems() if p.stem == name), None)
    return found if found is not None else Path(name)


def _renamed(value: Any, names: dict[str, str]) -> Any:
    """The plan's data with the planner's agent names replaced by the run's."""
    if isinstance(value, str):
        return names.get(value, value)
    if isinstance(value, list):
        return [_renamed(v, names) for v in value]
    if isinstance(value, dict):
        return {names.get(k, k): _renamed(v, names) for k, v in value.items()}
    return value


@dataclass(frozen=True)
class StackFiles:
    """The planner's files a shared plan needs, read once before the run starts (and
    not again at each replan): the ``stack`` domain, the problem, the problem's data."""

    domain: Domain
    problem: Problem
    data: dict[str, Any]

    @classmethod
    def read(cls, problem: str) -> StackFiles:
        path = problem_path(problem)
        domain = planner.load_domain("stack")
        return cls(domain, planner.load_problem(path, domain), yamlsafe.load_file(path).data)


def _plan(problem: Problem, names: dict[str, str]) -> SharedPlan:
    return SharedPlan.from_dict(_renamed(to_dict(select(problem, explore(problem))), names))


def first_plan(files: StackFiles, names: dict[str, str]) -> SharedPlan:
    """The problem's plan, its agents named as in the run (``{"robot": "pr2", …}``)."""
    return _plan(files.problem, names)


class Replanner:
    """Plans again from the robot's beliefs (see the module's documentation)."""

    def __init__(self, facts: Any, files: StackFiles, names: dict[str, str], record: Any):
        self.facts = facts
        self.names = names
        self.back = {v: k for k, v in names.items()}
        self.domain = files.domain
        self.data = files.data
        self.record = record

    def __call__(self, agendas: dict[str, list[str]]) -> SharedPlan | None:
        words = re.compile(r"\b(" + "|".join(map(re.escape, self.back)) + r")\b")
        agendas = {self.back.get(agent, agent): [words.sub(lambda m: self.back[m.group(1)], t)
                                                 for t in tasks]
                   for agent, tasks in agendas.items()}
        data = dict(self.data, problem=f"{self.data['problem']}-replanned",
                    agendas={agent: agendas.get(agent, []) for agent in self.data["agendas"]})
        entities = {name: dict(spec) for name, spec in self.data["entities"].items()}
        blocks = [n for n, s in entities.items() if s.get("type") == "Block"]
        for name in blocks:
            spec = entities[name]
            if not spec.get("loose", False) and "on" not in spec:
                continue  # the table
            supports = [str(o) for o in self.facts.objects(name, "isOn") if str(o) in blocks]
            held = [a for a, s in entities.items() if s.get("type") == "Agent"
                    and self.facts.holds(self.names.get(a, a), "isHolding", name)]
            if spec.get("placement"):
                continue
            spec.pop("on", None)
            spec["loose"] = not supports and not held
            if supports:
                spec["on"] = sorted(supports)[0]
        for name in blocks:
            spec = entities[name]
            spec.pop("top", None)
            above = [b for b in blocks if self.facts.holds(b, "isOn", name)]
            if above:
                spec["top"] = sorted(above)[0]
        for agent, spec in entities.items():
            if spec.get("type") == "Agent":
                # a block seen on a support is not held any more (a hold fades out late)
                held = [b for b in blocks if entities[b].get("on") is None
                        and self.facts.holds(self.names.get(agent, agent), "isHolding", b)]
                spec.pop("holding", None)
                if held:
                    spec["holding"] = held[0]
                spec.update(waiting=False, waits=0)
        data["entities"] = entities
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "replan.yaml"
            path.write_text(yamlsafe.dump(data), encoding="utf-8")
            try:
                plan = _plan(planner.load_problem(path, self.domain), self.names)
            except (FileError, ValueError) as err:
                self.record("plan-replan", error=str(err).splitlines()[0], agendas=agendas)
                return None
        self.record("plan-replan", agendas=agendas, tasks=len(plan.primitive))
        return plan
