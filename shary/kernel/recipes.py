"""Recipes and the vocabulary around them: tasks, atomic tasks, monitors, chronicles.

SHARY: "Task recipes are methods that compute the partially ordered list of
subtasks of an act X task.  This sub-task tree contains both a set of tasks
needed for the achievement of the act X task but also a list of tasks
required for monitoring the execution."  A recipe library (``recipes/*.yaml``)
declares:

* the **predicates** facts may use and the **atomic** tasks executors perform
  (so that a typo in a monitor or a step is caught when the file is loaded);
* **tasks**: which communication scheme runs a task, chosen by context when
  several are given (SHARY's adapted schemes), and who plays its roles;
* **recipes**, one or several per (task, act), chosen by context: scripted
  steps, a plan from a planner, or a registered Python function;
* **chronicles**: patterns of fact events over time that put a goal on the
  agenda (the robot's initiative).

Terms in files: ``$name`` is a parameter of the task (in a chronicle, a
variable bound by its events), ``_`` anything, everything else a constant.
(``?name`` would read better for variables, but YAML takes ``?`` in ``[?x]``
for a complex key.)
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from shary.statechart.acts import ActRegistry
from shary.statechart.model import Scheme

_REFINEMENT = re.compile(r"^\s*([A-Za-z0-9_][A-Za-z0-9_.:-]*)\s*(?:\((.*)\))?\s*$")
_PLACEHOLDER = re.compile(r"\{([A-Za-z0-9_][A-Za-z0-9_-]*)\}")

ANY_TASK = "*"
"""A recipe for this task serves any task whose own recipes do not fit."""

ROBOT_PARAM = "robot"
"""Every task has this parameter: the robot whose supervisor runs it."""

INITIATOR_PARAM = "initiator"
"""Every recipe may name this parameter: the person who asked for the task (they play the
human roles its parameters leave free, as a clean-up someone asked for has them).  It is
unbound in a task nobody asked for, and a condition about it then holds nothing, negated
or not: a recipe for the person who asked is not chosen when there is none."""


@dataclass(frozen=True)
class Term:
    """A term of a pattern or an argument: a constant, ``$name`` or ``_``."""

    kind: str
    value: Any

    @staticmethod
    def parse(raw: Any) -> Term:
        if isinstance(raw, str):
            if raw == "_":
                return Term("any", None)
            if raw.startswith("$") and len(raw) > 1:
                return Term("param", raw[1:])
        return Term("const", raw)

    def resolve(self, env: dict[str, Any]) -> Any:
        """The value of this term in ``env`` (None for ``_`` and unbound names).

        A constant string may name parameters in braces (``"the {object}"``): they
        are replaced by their values; nothing else in the text is interpreted.
        """
        kind = self.kind
        if kind == "param":  # the common case first: run for every monitor and step
            return env.get(self.value)
        if kind == "const":
            if isinstance(self.value, str) and "{" in self.value:
                return _PLACEHOLDER.sub(lambda m: str(env.get(m.group(1), m.group(0))),
                                        self.value)
            return self.value
        return None  # "any"

    def __str__(self) -> str:
        prefix = {"param": "$", "any": "_", "const": ""}[self.kind]
        return prefix + ("" if self.value is None else str(self.value))


@dataclass(frozen=True)
class Pattern:
    """A triple pattern over facts."""

    subject: Term
    predicate: Term
    object: Term

    def terms(self) -> tuple[Term, Term, Term]:
        return (self.subject, self.predicate, self.object)

    def resolve(self, env: dict[str, Any]) -> tuple[Any, Any, Any]:
        return self.subject.resolve(env), self.predicate.resolve(env), self.object.resolve(env)

    def __str__(self) -> str:
        return "[" + ", ".join(str(t) for t in self.terms()) + "]"


@dataclass(frozen=True)
class Condition:
    """A fact that must hold (or, negated, must not) in the robot's perspective."""

    pattern: Pattern
    negated: bool = False


@dataclass(frozen=True)
class AtomicTask:
    """A leaf of the task tree that an executor performs."""

    name: str
    params: tuple[str, ...] = ()
    doc: str = ""


@dataclass(frozen=True)
class SchemeChoice:
    """One scheme a task may run, used when its conditions hold."""

    scheme: Scheme
    when: tuple[Condition, ...] = ()


@dataclass(frozen=True)
class TaskType:
    """A kind of task: its parameters, who plays its scheme's roles, its scheme(s)."""

    name: str
    params: tuple[str, ...]
    roles: dict[str, Term]
    schemes: tuple[SchemeChoice, ...]
    doc: str = ""


@dataclass(frozen=True)
class Step:
    """A subtask of a recipe: an atomic task or a task with its own scheme."""

    name: str
    atomic: str | None
    task: str | None
    args: dict[str, Term]
    by: Term | None
    after: tuple[str, ...]
    emit: str | None = None
    emit_data: dict[str, Any] | None = field(default=None, compare=False)
    """What the event ``emit`` carries to the scheme when the step is done (its
    ``_event.data``): a thing the step found out, for the scheme's data model."""


@dataclass(frozen=True)
class Monitor:
    """A monitoring task: when a matching fact is added (or removed), emit an event."""

    name: str
    change: str
    pattern: Pattern
    emit: str
    perspective: Term | None = None
    until: str | None = None
    """A step of the recipe: the monitor is dropped when that step starts (a look-away
    matters to an inform until its sentence begins, not while it is said)."""


@dataclass(frozen=True)
class Retry:
    """How often a failed step is tried, and what happens after the last failure."""

    max_attempts: int = 1
    then: str = "fail"
    emit: str | None = None


@dataclass(frozen=True)
class PlanSpec:
    """A planner-backed recipe: which domain and task to plan, and how to refine actions."""

    domain: str
    task: str
    args: dict[str, Term]
    refine: dict[str, str]
    facts: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """Planner attribute -> the predicates its value is read from, first found wins;
    ``^p`` reads ``p`` backwards (the subject of ``? p entity``).  Attributes not
    named here are read from facts whose predicate is the attribute's name."""


@dataclass(frozen=True)
class Recipe:
    """How one act of one task is carried out, in some context."""

    name: str
    task: str
    act: str
    when: tuple[Condition, ...] = ()
    steps: tuple[Step, ...] = ()
    plan: PlanSpec | None = None
    function: str | None = None
    monitors: tuple[Monitor, ...] = ()
    retry: Retry = Retry()
    doc: str = ""
    file: str = ""
    mark: tuple[int, int] = (1, 1)
    on: tuple[str, ...] = ()
    """The recipe serves its act only when the act's state was entered on one of these
    events, as the scheme writes them (``H-DISAGREE``, ``after 15s``): what led to
    the act is context too (GIVE-UP after silence is not GIVE-UP after a failure)."""

    @property
    def kind(self) -> str:
        return "plan" if self.plan else "function" if self.function else "scripted"


@dataclass(frozen=True)
class ChronicleEvent:
    """One fact change of a chronicle, with its timing relative to the previous one."""

    change: str
    pattern: Pattern
    within: float | None = None
    after: float | None = None
    stays: float | None = None


@dataclass(frozen=True)
class ChronicleAll:
    """A step of a chronicle made of several fact events in any order (a partially
    ordered conjunction): all must happen, the first at least ``after`` the previous
    step, and all of them within ``within`` of the first."""

    events: tuple[ChronicleEvent, ...]
    within: float | None = None
    after: float | None = None


@dataclass(frozen=True)
class Chronicle:
    """A pattern of fact events over time that puts a goal on the agenda: a sequence of
    steps, each one event or several in any order (:class:`ChronicleAll`)."""

    name: str
    events: tuple[ChronicleEvent | ChronicleAll, ...]
    task: str
    args: dict[str, Term]
    priority: int = 0
    todo: str = "default"
    doc: str = ""


@dataclass
class RecipeLibrary:
    """Everything loaded from recipe files, checked together."""

    predicates: dict[str, str] = field(default_factory=dict)
    atomic: dict[str, AtomicTask] = field(default_factory=dict)
    tasks: dict[str, TaskType] = field(default_factory=dict)
    recipes: list[Recipe] = field(default_factory=list)
    chronicles: dict[str, Chronicle] = field(default_factory=dict)
    acts: ActRegistry = field(default_factory=ActRegistry)
    """The acts usable with this library: built-in, declared by its files and their schemes."""
    _index: dict[tuple[str, str], list[Recipe]] | None = field(default=None, repr=False)
    _indexed: int = field(default=0, repr=False)

    def recipes_for(self, task: str, act: str) -> list[Recipe]:
        """The recipes of an act within a task, in file order, then those for any task (*)."""
        if self._index is None or self._indexed != len(self.recipes):
            index: dict[tuple[str, str], list[Recipe]] = {}
            for recipe in self.recipes:
                index.setdefault((recipe.task, recipe.act), []).append(recipe)
            self._index, self._indexed = index, len(self.recipes)
        return self._index.get((task, act), []) + self._index.get((ANY_TASK, act), [])


def parse_refinement(text: str) -> tuple[str, dict[str, str]]:
    """``"navigate(place=to)"`` -> ("navigate", {"place": "to"}): the task or atomic task
    that refines a plan action, and which action parameter fills each of its parameters
    (a bare name passes the parameters of the same name)."""
    match = _REFINEMENT.match(text)
    if not match:
        raise ValueError(f"{text!r} is not a refinement: write task or task(param=action_param)")
    mapping = {}
    for part in filter(None, (p.strip() for p in (match.group(2) or "").split(","))):
        key, eq, value = part.partition("=")
        if not eq or not key.strip() or not value.strip():
            raise ValueError(f"{part!r} in {text!r}: write param=action_param")
        mapping[key.strip()] = value.strip()
    return match.group(1), mapping
