"""Action models: how the robot recognizes human actions and executes its own (JAHRVIS VI-A.1.b).

A human action is ``⟨Action(Agent, Params), PrecondL, MoveL, ProgEffectL,
NecessEffectL⟩``; the paper's ``place``, in this project's YAML::

    human:
      place:
        agent: Human
        params: {Pickable: Cube, Support: Support}
        precond:   ["isHolding(Human, Pickable)"]
        move:      ["handMovingToward(Human, Support)"]
        progress:  ["not isHolding(Human, Pickable)"]
        necessary: ["isOn(Pickable, Support)"]

A fact is ``predicate(Role, Role)``: the triple (subject, predicate, object)
of the fact base with roles in place of entities; ``not`` means its removal
(for ``progress``, ``necessary``) or its absence (for ``precond``).  A robot
action gives its executor (an atomic task), the executor's arguments from the
roles, the role the head looks at, and ``max-attempts`` before its failure is
signalled to the task level (Listing 1).

Each action has a class of the action ontology (:mod:`.ontology`), by default
the class the ontology gives its name for its agent (``place`` for a Human is
``HumanPlaceAction``); its roles must be the class's parameters, each filled
by that parameter's class or a subclass, so that what is recognized can be
said with the class's label.  Files are read through :mod:`userfiles.reader`
(safe YAML, ``shary/schemas/action-models.schema.json``, then these meaning
checks), so every mistake is refused at its line.
"""

from __future__ import annotations

import functools
import os
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from shary.facts.database import FactDatabase
from shary.io import schema
from shary.recognition.ontology import ActionOntology, load_action_ontology
from userfiles.errors import FileError, Problem
from userfiles.reader import Reader, checked

__all__ = ["ActionModels", "Fact", "HumanActionModel", "RobotActionModel", "builtin_models",
           "load_action_models"]

MODELS = Path(__file__).with_name("models")
"""The action models shipped with the package (one file per task)."""

NEAR_ROLES = ("Human", "Object")
"""The roles the attribution criterion's facts speak of."""

_FACT = re.compile(r"\s*(?P<not>not\s+)?(?P<predicate>[A-Za-z_][\w.-]*)\s*\(\s*"
                   r"(?P<subject>[A-Za-z_][\w-]*)\s*,\s*(?P<object>[A-Za-z_][\w-]*)\s*\)\s*")


@dataclass(frozen=True)
class Fact:
    """A fact pattern: ``predicate(subject, object)`` over roles; ``negated``: its removal."""

    negated: bool
    predicate: str
    subject: str
    object: str

    def __str__(self) -> str:
        return f"{'not ' if self.negated else ''}{self.predicate}({self.subject}, {self.object})"


@dataclass(frozen=True)
class HumanActionModel:
    """A human action to recognize: ⟨Action(Agent, Params), PrecondL, MoveL, ProgEffectL,
    NecessEffectL⟩."""

    name: str
    action_class: str
    agent: str
    """The agent's role, which is also its class (Human)."""
    params: tuple[tuple[str, str], ...]
    """(role, class) in the ontology's order."""
    precond: tuple[Fact, ...] = ()
    move: tuple[Fact, ...] = ()
    progress: tuple[Fact, ...] = ()
    necessary: tuple[Fact, ...] = ()

    @property
    def roles(self) -> tuple[str, ...]:
        return (self.agent, *(role for role, _ in self.params))

    @functools.cached_property
    def classes(self) -> dict[str, str]:
        """role -> the class of what fills it (the agent's role is its own class)."""
        return {self.agent: self.agent, **dict(self.params)}


@dataclass(frozen=True)
class RobotActionModel:
    """A robot action: how to execute it and what to do when it fails (Listing 1)."""

    name: str
    action_class: str
    agent: str
    params: tuple[tuple[str, str], ...]
    executor: str | None
    """The atomic task that performs it; None for an action with nothing to move (wait)."""
    args: dict[str, str] = field(default_factory=dict)
    """The executor's arguments: argument -> role."""
    look_at: str | None = None
    max_attempts: int = 1

    @property
    def roles(self) -> tuple[str, ...]:
        return (self.agent, *(role for role, _ in self.params))


@dataclass
class ActionModels:
    """Every action model loaded for a run, with the ontology they are classes of."""

    ontology: ActionOntology
    human: dict[str, HumanActionModel] = field(default_factory=dict)
    robot: dict[str, RobotActionModel] = field(default_factory=dict)
    near: tuple[Fact, ...] = ()
    """The attribution criterion (roles Human and Object); empty: effects without a
    start are attributed to nobody."""
    near_within: float = 3.0
    settle: float = 1.0
    forget: float = 30.0
    files: tuple[str, ...] = ()

    def predicates(self) -> list[str]:
        """Every predicate the human models and the attribution criterion name: what the
        recognizer subscribes to, and nothing else."""
        found = {fact.predicate for model in self.human.values()
                 for facts in (model.precond, model.move, model.progress, model.necessary)
                 for fact in facts}
        return sorted(found | {fact.predicate for fact in self.near})


def builtin_models(name: str) -> Path:
    """The shipped models file ``name`` (``"stack"``), or FileNotFoundError."""
    path = MODELS / f"{name}.yaml"
    if not path.is_file():
        shipped = ", ".join(sorted(p.stem for p in MODELS.glob("*.yaml")))
        raise FileNotFoundError(f"no built-in action models {name!r} (shipped: {shipped})")
    return path


def load_action_models(paths: Iterable[str | os.PathLike[str]], facts: FactDatabase | None = None,
                       *, atomic: dict[str, Any] | None = None) -> ActionModels:
    """Read action model files (and the ontology files they name) into one set.

    The core action ontology and the files' own Turtle are loaded into
    ``facts``' a-priori graph (a fresh fact base when None, to check files).
    ``atomic`` (the recipe library's atomic tasks, name -> object with
    ``params``) lets robot executors and their arguments be checked.  Raises
    FileError with every problem of every file.
    """
    facts = facts if facts is not None else FactDatabase()
    files = [os.fspath(p) for p in paths]
    readers = [checked(file, schema.validator("action-models")) for file in files]
    problems: list[Problem] = [p for r in readers for p in r.problems]
    turtle: list[Path] = []
    for reader in readers:
        if reader.shape_ok:
            for i, name in enumerate(reader.data.get("ontology") or []):
                full = reader.confined_path(("ontology", i), name)
                if full is not None:
                    turtle.append(full)
    problems += [p for r in readers for p in r.problems if p not in problems]
    if problems:
        raise FileError(problems)
    ontology = load_action_ontology(facts, turtle)
    models = ActionModels(ontology, files=tuple(files))
    for reader in readers:
        _Meaning(reader, models, atomic).read()
    problems = [p for r in readers for p in r.problems]
    if problems:
        raise FileError(problems)
    return models


class _Meaning:
    """The meaning checks of one file, adding its models to the set."""

    def __init__(self, reader: Reader, models: ActionModels, atomic: dict[str, Any] | None):
        self.reader = reader
        self.models = models
        self.ontology = models.ontology
        self.atomic = atomic

    def read(self) -> None:
        reader, data, models = self.reader, self.reader.data, self.models
        if "settle" in data:
            models.settle = reader.duration(("settle",), data["settle"])
        if "forget" in data:
            models.forget = reader.duration(("forget",), data["forget"])
        near = data.get("near")
        if near is not None:
            models.near += tuple(self.facts(("near", "facts"), near["facts"], NEAR_ROLES))
            if "within" in near:
                models.near_within = reader.duration(("near", "within"), near["within"])
            if not any(NEAR_ROLES[0] in (f.subject, f.object) for f in models.near):
                reader.problem(("near", "facts"), "the criterion must name the Human role")
        for kind in ("human", "robot"):
            for name, spec in (data.get(kind) or {}).items():
                known = models.human if kind == "human" else models.robot
                if name in known:
                    reader.problem((kind, name), f"the {kind} action {name!r} is already "
                                   "modelled in another file", key=True)
                    continue
                model = self.human(name, spec) if kind == "human" else self.robot(name, spec)
                if model is not None:
                    known[name] = model  # type: ignore[assignment]

    # -- one action ------------------------------------------------------------------------------

    def signature(self, kind: Literal["human", "robot"], name: str,
                  spec: dict[str, Any]) -> tuple[str, tuple[tuple[str, str], ...]] | None:
        """The action's class and (role, class) parameters, checked against the ontology."""
        reader, ontology, where = self.reader, self.ontology, (kind, name)
        agent = spec["agent"]
        if agent not in ontology:
            reader.problem(where + ("agent",), f"unknown agent class {agent!r} (the agent's role "
                           "is also its class: Human, Robot, or a class of your ontology)")
            return None
        cls = spec.get("class") or ontology.action_class(name, agent=agent)
        if cls is None or cls not in ontology:
            at = where + ("class",) if "class" in spec else where
            reader.problem(at, f"no class of the action ontology is called {cls or name!r}; "
                           "name one with class:, or add it in a Turtle file named by "
                           "ontology:", key="class" not in spec)
            return None
        if not ontology.is_a(agent, ontology.agent_class(cls)):
            reader.problem(where + ("agent",), f"{cls} is done by a {ontology.agent_class(cls)}, "
                           f"and {agent} is not one")
        expected = ontology.parameters(cls)
        given = spec.get("params") or {}
        params: list[tuple[str, str]] = []
        for parameter in expected:
            role_class = given.get(parameter.role)
            if role_class is None:
                reader.problem(where + (("params",) if "params" in spec else ()),
                               f"{cls} has the parameter {parameter.role} (a "
                               f"{parameter.role_class}); give its class in params:")
                continue
            if role_class not in ontology or not ontology.is_a(role_class,
                                                               parameter.role_class):
                reader.problem(where + ("params", parameter.role),
                               f"{role_class!r} is not a class of the action ontology that is a "
                               f"{parameter.role_class}")
            params.append((parameter.role, role_class))
        for role in given:
            if role not in {p.role for p in expected}:
                roles = ", ".join(p.role for p in expected) or "none"
                reader.problem(where + ("params", role), f"{cls} has no parameter {role!r} "
                               f"(its parameters: {roles})", key=True)
        if agent in given:
            reader.problem(where + ("params", agent), f"{agent} is the agent's role", key=True)
        return cls, tuple(params)

    def human(self, name: str, spec: dict[str, Any]) -> HumanActionModel | None:
        found = self.signature("human", name, spec)
        if found is None:
            return None
        cls, params = found
        roles = (spec["agent"], *(role for role, _ in params))
        lists = {key: tuple(self.facts(("human", name, key), spec.get(key) or [], roles))
                 for key in ("precond", "move", "progress", "necessary")}
        for i, fact in enumerate(lists["move"]):
            if spec["agent"] not in (fact.subject, fact.object) or fact.negated:
                self.reader.problem(("human", name, "move", i),
                                    f"a movement is the agent's: name {spec['agent']} in it, "
                                    "without not")
        return HumanActionModel(name, cls, spec["agent"], params, **lists)

    def robot(self, name: str, spec: dict[str, Any]) -> RobotActionModel | None:
        found = self.signature("robot", name, spec)
        if found is None:
            return None
        cls, params = found
        roles = (spec["agent"], *(role for role, _ in params))
        where = ("robot", name)
        executor, args = spec.get("executor"), dict(spec.get("args") or {})
        for argument, role in args.items():
            if role not in roles:
                self.reader.problem(where + ("args", argument), _unknown_role(role, roles))
        if executor is None and args:
            self.reader.problem(where + ("args",), "arguments without an executor")
        if executor is not None and self.atomic is not None:
            task = self.atomic.get(executor)
            if task is None:
                self.reader.problem(where + ("executor",), f"no atomic task {executor!r} "
                                    f"(known: {', '.join(sorted(self.atomic))})")
            else:
                wanted = list(task.params)
                missing = [a for a in wanted if a not in args]
                extra = [a for a in args if a not in wanted]
                if missing or extra:
                    self.reader.problem(where + ("args",) if "args" in spec else where,
                                        f"{executor} takes {', '.join(wanted) or 'nothing'}"
                                        + (f"; missing: {', '.join(missing)}" if missing else "")
                                        + (f"; unknown: {', '.join(extra)}" if extra else ""))
        look_at = spec.get("look-at")
        if look_at is not None and look_at not in roles:
            self.reader.problem(where + ("look-at",), _unknown_role(look_at, roles))
        return RobotActionModel(name, cls, spec["agent"], params, executor, args, look_at,
                                spec.get("max-attempts", 1))

    def facts(self, where: tuple, texts: list[str], roles: Iterable[str]) -> list[Fact]:
        """Parse fact patterns, each argument one of ``roles``."""
        roles = tuple(roles)
        out: list[Fact] = []
        for i, text in enumerate(texts):
            match = _FACT.fullmatch(text)
            if match is None:
                self.reader.problem(where + (i,), f"{text!r} is not a fact: write "
                                    "predicate(Role, Role) or not predicate(Role, Role)")
                continue
            bad = [g for g in ("subject", "object") if match[g] not in roles]
            for group in bad:
                self.reader.problem_inside(where + (i,), match.start(group),
                                           _unknown_role(match[group], roles))
            if not bad:
                out.append(Fact(bool(match["not"]), match["predicate"], match["subject"],
                                match["object"]))
        return out


def _unknown_role(role: str, roles: tuple[str, ...]) -> str:
    return f"unknown role {role!r} (the roles here: {', '.join(roles)})"


def check_files(files: list[Path]) -> list[Problem]:
    """Every problem of action model files, for ``shary validate`` (each file alone, its
    executors checked against the built-in atomic tasks)."""
    from shary.io.recipes import load_library

    atomic = load_library().atomic
    problems: list[Problem] = []
    for path in files:
        try:
            load_action_models([path], atomic=atomic)
        except FileError as err:
            problems.extend(err.problems)
    return problems


def shipped_files() -> list[Path]:
    """The action model files that ship with the package."""
    return sorted(MODELS.glob("*.yaml"))
