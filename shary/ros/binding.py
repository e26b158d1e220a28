"""The robot binding file: shary's atomic tasks, facts and speech on a robot's ROS 2 interfaces.

A binding (``binding:`` at the top, schema ``shary/schemas/robot-binding.schema.json``)
says, for one robot:

* ``tasks``: each atomic task (navigate, pick, give, speak …) as an action, a
  service or a topic, by name and type; the goal's fields built from the
  task's parameters and the facts (``{place}``, ``{code:place}``,
  ``{fact:place:position:0}``); deadlines per phase (server, acknowledgement,
  execution, cancel); a progress text per feedback; when a result counts as a
  success and what the failure's reason reads;
* ``facts``: topics whose messages become facts of the robot's perspective
  (templates over the message's fields, once per element of a sequence with
  ``each``), dropped when the topic has been silent for ``stale``;
* ``speech``: topics that carry what people say, each sentence read by the
  communication manager's requests grammar;
* each fact, speech or published topic's ``qos`` (:mod:`shary.ros.qos`), each task's
  ``resources`` (the parts of the robot it uses: :mod:`shary.ros.resources`);
* ``frames``: the TF frames of the markers shary shows (:mod:`shary.ros.views`);
* ``alive``: how shary notices that a node of the robot is gone (a driver that
  crashed): a topic whose publisher offers a ROS 2 liveliness lease, and the
  atomic tasks that node performs (:mod:`shary.ros.liveliness`).

``codes`` numbers names for interfaces whose goals carry only numbers (the
simulated Jido's, built from the message packages that are on PyPI).

Loading checks the file's shape, then its meaning: each task is an atomic task
of the recipe library and its templates name only that task's parameters;
each type is imported, and when it is, every field path (goal, feedback, reason,
``succeeded-if``, facts, speech) is checked against its fields as rosidl generated
them.  A type that an installed package does not have is an error, with the types
it has and the closest (a misspelt ``test_msgs/action/Fibonaci``).  A type whose
package cannot be imported here (``nav2_msgs`` is not on PyPI) is a *note* ("not
installed"), not an error: the binding is meant for a robot that has it, and
``shary ros`` warns of it as it starts (its tasks fail at once).  Importing a
message package never imports rclpy.
"""

from __future__ import annotations

import importlib
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from userfiles.errors import Problem
from userfiles.reader import Reader, read

DEFAULT_DEADLINES = {"server": 0.0, "ack": 1.0, "exec": 300.0, "cancel": 2.0}
"""Seconds per phase when a binding does not say: fail at once without a server
(BehaviorTree.ROS2's behaviour), 1 s for the acknowledgement (its default), 5 min of
execution, 2 s for a cancelled goal to end."""

DEFAULT_RESOURCES = {"navigate": ("base",), "look-at": ("head",), "speak": ("voice",),
                     **dict.fromkeys(("move-arm", "pick", "place", "dump", "give", "put-back"),
                                     ("arm",))}
"""The parts of the robot the core library's atomic tasks use when a binding does not say
(``resources:``): one goal at a time per part (:mod:`shary.ros.resources`)."""

INTEGER_TYPES = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
                 "octet", "char"}
FLOAT_TYPES = {"float", "double"}

TEMPLATE = re.compile(r"\{([^{}]*)\}")
_PARAM = re.compile(r"^(?:(code):([A-Za-z_][\w-]*)|(fact):([A-Za-z_][\w-]*):([A-Za-z_][\w-]*)"
                    r"(?::(\d+))?|([A-Za-z_][\w-]*))$")
_FIELD = re.compile(r"^(item|[a-z][a-z0-9_]*)(\.[a-z][a-z0-9_]*)*$")


@dataclass(frozen=True)
class TaskBinding:
    """One atomic task on one ROS 2 interface."""

    atomic: str
    kind: str
    """``action``, ``service`` or ``topic``."""
    name: str
    type: str
    goal: dict[str, Any] = field(default_factory=dict)
    deadlines: dict[str, float] = field(default_factory=lambda: dict(DEFAULT_DEADLINES))
    feedback: str = ""
    succeeded_if: dict[str, Any] = field(default_factory=dict)
    reason: str = ""
    resources: tuple[str, ...] = ()
    """The parts of the robot its goals use (the action's server is one besides)."""
    qos: Any = None
    """A topic's quality of service (:mod:`shary.ros.qos`): a preset or policies."""


@dataclass(frozen=True)
class FactSource:
    """A topic whose messages become facts."""

    topic: str
    type: str
    facts: tuple[tuple[Any, Any, Any], ...] = ()
    each: str = ""
    lines: str = ""
    stale: float | None = None
    qos: Any = None


@dataclass(frozen=True)
class SpeechSource:
    """A topic that carries what people say."""

    topic: str
    type: str
    text: str
    speaker: str = ""
    qos: Any = None


@dataclass(frozen=True)
class AliveSource:
    """A topic whose publishers' liveliness says that a node of the robot is there."""

    topic: str
    type: str
    lease: float
    tasks: tuple[str, ...]
    """The atomic tasks that node performs."""


@dataclass
class Binding:
    """A robot binding, loaded and checked (see the module's docstring)."""

    name: str
    robot: str
    file: str
    tasks: dict[str, TaskBinding]
    facts: list[FactSource] = field(default_factory=list)
    speech: list[SpeechSource] = field(default_factory=list)
    codes: dict[str, int] = field(default_factory=dict)
    alive: list[AliveSource] = field(default_factory=list)
    doc: str = ""
    notes: list[Problem] = field(default_factory=list)
    frames: dict[str, str] = field(default_factory=dict)
    """The TF frames of the markers: ``robot``, ``person`` (``{agent}``: the name)."""
    """Types that cannot be imported here, each at its place in the file."""


def import_interface(name: str) -> Any | None:
    """The Python class of ``package/msg|srv|action/Name``, or None when its package is
    not installed here."""
    package, kind, cls = name.split("/")
    try:
        module = importlib.import_module(f"{package}.{kind}")
    except ImportError:
        return None
    return getattr(module, cls, None)


def field_type(cls: Any, path: str) -> str | None:
    """The type of field ``a.b.c`` of a message class (as rosidl names it), or None
    when it has no such field."""
    current, kind = cls, None
    for part in path.split("."):
        if current is None:
            return None
        fields = current.get_fields_and_field_types()
        if part not in fields:
            return None
        kind = fields[part]
        current = _nested(kind)
    return kind


def _nested(kind: str) -> Any | None:
    """The class of a nested message type ``pkg/Name`` (None for a primitive or sequence)."""
    if "/" not in kind or kind.startswith("sequence<"):
        return None
    package, name = kind.split("/")
    return import_interface(f"{package}/msg/{name}")


def templates(value: Any) -> list[str]:
    """The templates (the text between braces) of a binding value."""
    return TEMPLATE.findall(value) if isinstance(value, str) else []


def load_binding(path: str | os.PathLike[str], *, atomic: dict[str, tuple[str, ...]] | None = None
                 ) -> Binding:
    """Read and check a binding (raises :class:`~userfiles.errors.FileError` with every
    problem).  ``atomic`` is the recipe library's atomic tasks and their parameters
    (the built-in library's by default)."""
    from shary.io import schema

    if atomic is None:
        atomic = builtin_atomic()
    return read(path, schema.validator("robot-binding"),
                lambda reader: _meaning(reader, atomic))


def builtin_atomic() -> dict[str, tuple[str, ...]]:
    """The built-in recipe library's atomic tasks and their parameters."""
    from shary.io.recipes import load_library

    return {name: tuple(task.params) for name, task in load_library().atomic.items()}


def _meaning(reader: Reader, atomic: dict[str, tuple[str, ...]]) -> Binding:
    data = reader.data
    notes: list[Problem] = []
    codes = dict(data.get("codes") or {})
    tasks: dict[str, TaskBinding] = {}
    for name, raw in (data.get("tasks") or {}).items():
        where = ("tasks", name)
        if name not in atomic:
            from userfiles.schema import did_you_mean
            reader.problem(where, f"{name!r} is not an atomic task of the recipe library "
                           f"({', '.join(sorted(atomic))}){did_you_mean(name, atomic)}", key=True)
            continue
        kind = next(k for k in ("action", "service", "topic") if k in raw)
        deadlines = dict(DEFAULT_DEADLINES)
        for phase, value in (raw.get("deadlines") or {}).items():
            deadlines[phase] = reader.duration((*where, "deadlines", phase), value)
        cls = _interface(reader, notes, (*where, "type"), raw["type"], kind)
        goal_cls = _part(cls, kind, "Goal" if kind == "action" else "Request")
        for key, value in (raw.get("goal") or {}).items():
            _check_goal_value(reader, (*where, "goal", key), value, atomic[name], codes)
            if goal_cls is not None:
                _check_goal_field(reader, (*where, "goal", key), goal_cls, raw["type"], key,
                                  value)
        if kind != "topic" and "qos" in raw:
            reader.problem((*where, "qos"), f"{'an' if kind == 'action' else 'a'} {kind} has "
                           "no qos: only a topic task has (what it publishes)", key=True)
        if kind != "action" and "feedback" in raw:
            reader.problem((*where, "feedback"), f"a {kind} has no feedback: only an action has",
                           key=True)
        result_cls = _part(cls, kind, "Result" if kind == "action" else "Response")
        feedback_cls = _part(cls, kind, "Feedback")
        _check_fields(reader, (*where, "feedback"), raw.get("feedback", ""), feedback_cls)
        _check_fields(reader, (*where, "reason"), raw.get("reason", ""), result_cls)
        for key in raw.get("succeeded-if") or {}:
            if result_cls is not None and field_type(result_cls, key) is None:
                reader.problem((*where, "succeeded-if", key),
                               f"{raw['type']} has no result field {key!r}", key=True)
        resources = tuple(raw["resources"]) if "resources" in raw else \
            DEFAULT_RESOURCES.get(name, ())
        tasks[name] = TaskBinding(name, kind, raw[kind], raw["type"], dict(raw.get("goal") or {}),
                                  deadlines, raw.get("feedback", ""),
                                  dict(raw.get("succeeded-if") or {}), raw.get("reason", ""),
                                  resources, raw.get("qos"))
    facts = []
    for i, raw in enumerate(data.get("facts") or []):
        where = ("facts", i)
        cls = _interface(reader, notes, (*where, "type"), raw["type"], "msg")
        if raw.get("each") and cls is not None and field_type(cls, raw["each"]) is None:
            reader.problem((*where, "each"), f"{raw['type']} has no field {raw['each']!r}")
        if raw.get("lines") and cls is not None and field_type(cls, raw["lines"]) != "string":
            reader.problem((*where, "lines"), f"{raw['type']} has no string field "
                           f"{raw['lines']!r}")
        for j, triple in enumerate(raw.get("facts") or []):
            for k, part in enumerate(triple):
                _check_fields(reader, (*where, "facts", j, k), part, cls, each=raw.get("each"))
        stale = reader.duration((*where, "stale"), raw["stale"]) if "stale" in raw else None
        facts.append(FactSource(raw["topic"], raw["type"],
                                tuple(tuple(t) for t in raw.get("facts") or []),
                                raw.get("each", ""), raw.get("lines", ""), stale,
                                raw.get("qos")))
    speech = []
    for i, raw in enumerate(data.get("speech") or []):
        where = ("speech", i)
        cls = _interface(reader, notes, (*where, "type"), raw["type"], "msg")
        if cls is not None and field_type(cls, raw["text"]) != "string":
            reader.problem((*where, "text"), f"{raw['type']} has no string field {raw['text']!r}")
        _check_fields(reader, (*where, "speaker"), raw.get("speaker", ""), cls)
        speech.append(SpeechSource(raw["topic"], raw["type"], raw["text"], raw.get("speaker", ""),
                                   raw.get("qos")))
    alive = []
    for i, raw in enumerate(data.get("alive") or []):
        where = ("alive", i)
        _interface(reader, notes, (*where, "type"), raw["type"], "msg")
        lease = reader.duration((*where, "lease"), raw["lease"])
        if lease <= 0:
            reader.problem((*where, "lease"), "a lease must be longer than 0 s")
        for j, name in enumerate(raw.get("tasks") or []):
            if name not in tasks:
                reader.problem((*where, "tasks", j), f"{name!r} is not a task of this binding "
                               f"({', '.join(sorted(tasks)) or 'it has none'})")
        alive.append(AliveSource(raw["topic"], raw["type"], lease,
                                 tuple(raw.get("tasks") or tasks)))
    return Binding(data["binding"], data["robot"], reader.file, tasks, facts, speech, codes,
                   alive, data.get("doc", ""), notes, dict(data.get("frames") or {}))


def _interface(reader: Reader, notes: list[Problem], where: tuple, name: str,
               kind: str) -> Any | None:
    """The type's class, a problem when it is of the wrong kind, a note when absent here."""
    expected = {"action": "action", "service": "srv", "topic": "msg", "msg": "msg"}[kind]
    if name.split("/")[1] != expected:
        reader.problem(where, f"{name} is not a {expected} type (a {kind} needs "
                       f"package/{expected}/Name)")
        return None
    cls = import_interface(name)
    if cls is None:
        package, sort, cls_name = name.split("/")
        known = installed_types(package, sort)
        if known is None:
            notes.append(reader.located.problem(where, f"{name} is not installed here (package "
                                                       f"{package!r}): its fields are checked "
                                                       "on a machine that has it"))
        else:
            from userfiles.schema import did_you_mean

            listed = f" ({', '.join(known)})" if 0 < len(known) <= 12 else ""
            reader.problem(where, f"{package} has no {sort} type {cls_name!r}"
                           + (f"{listed}{did_you_mean(cls_name, known)}" if known
                              else f" (it has no {sort} types)"))
    return cls


def installed_types(package: str, sort: str) -> list[str] | None:
    """The ``sort`` (msg, srv, action) types of an installed interface package, as rosidl
    generated them (an empty list when it has none of that sort), or None when the package
    is not installed here."""
    try:
        importlib.import_module(package)
    except ImportError:
        return None
    try:
        module = importlib.import_module(f"{package}.{sort}")
    except ImportError:
        return []
    # an action's or service's parts (Fibonacci_SendGoal_Request) are no type of their own
    return sorted(n for n in dir(module) if n[:1].isupper() and "_" not in n
                  and not n.startswith("Metaclass") and isinstance(getattr(module, n), type))


def _part(cls: Any, kind: str, part: str) -> Any | None:
    if cls is None:
        return None
    if kind == "topic":
        return cls if part in ("Goal", "Request") else None
    return getattr(cls, part, None)


def _check_goal_field(reader: Reader, where: tuple, cls: Any, type_name: str, path: str,
                      value: Any) -> None:
    """A goal's field path exists in the type, names a value (not a nested message), and
    a constant fits it."""
    kind = field_type(cls, path)
    if kind is None:
        from userfiles.schema import did_you_mean

        *parents, last = path.split(".")
        siblings = list(_fields(cls, parents))
        reader.problem(where, f"{type_name} has no goal field {path!r}"
                       f"{did_you_mean(last, siblings)}", key=True)
    elif "/" in kind and not kind.startswith("sequence<"):
        reader.problem(where, f"{path} is a message ({kind}), not a value: give its fields "
                       f"({path}.FIELD)", key=True)
    elif not templates(value):
        try:
            convert(value, kind)
        except (TypeError, ValueError):
            reader.problem(where, f"{value!r} is not a {kind} (the type of {path})")


def convert(value: Any, kind: str) -> Any:
    """``value`` as a field of rosidl type ``kind`` wants it."""
    if kind in INTEGER_TYPES:
        return int(value)
    if kind in FLOAT_TYPES:
        return float(value)
    if kind == "boolean":
        return value if isinstance(value, bool) else str(value).lower() in ("true", "1", "yes")
    if kind.startswith("string"):
        return str(value)
    return value


def _fields(cls: Any, parents: list[str]) -> list[str]:
    """The field names of the message at ``parents`` in ``cls`` (none when there is none)."""
    current = cls
    for part in parents:
        kind = current.get_fields_and_field_types().get(part) if current is not None else None
        current = _nested(kind) if kind else None
    return list(current.get_fields_and_field_types()) if current is not None else []


def _check_goal_value(reader: Reader, where: tuple, value: Any, params: tuple[str, ...],
                      codes: dict[str, int]) -> None:
    for text in templates(value):
        m = _PARAM.match(text)
        if m is None:
            reader.problem(where, f"{{{text}}} is not a template (write {{PARAM}}, "
                           "{code:PARAM} or {fact:PARAM:PREDICATE[:INDEX]})")
            continue
        param = m.group(2) or m.group(4) or m.group(7)
        if param not in params:
            reader.problem(where, f"{{{text}}} names {param!r}, which is not a parameter of "
                           f"the task ({', '.join(params) or 'it has none'})")
        if m.group(1) and not codes:
            reader.problem(where, f"{{{text}}} needs the names numbered in 'codes:'")


def _check_fields(reader: Reader, where: tuple, value: Any, cls: Any, *,
                  each: str | None = None) -> None:
    for text in templates(value):
        if not _FIELD.match(text):
            reader.problem(where, f"{{{text}}} is not a field path (a.b.c)")
        elif text.split(".")[0] == "item":
            if not each:
                reader.problem(where, f"{{{text}}} needs 'each:' (the sequence it is an "
                               "element of)")
        elif cls is not None and field_type(cls, text) is None:
            reader.problem(where, f"the message has no field {text!r}")


def shipped_bindings() -> list[Path]:
    """The example bindings that ship with shary (``shary/ros/bindings/``)."""
    return sorted((Path(__file__).parent / "bindings").glob("*.yaml"))


def _check_bindings(files: list[Path], context: Any) -> list[Problem]:
    from userfiles.errors import FileError

    problems: list[Problem] = []
    for path in files:
        try:
            binding = load_binding(path)
        except FileError as err:
            problems.extend(err.problems)
            continue
        context.notes.extend(binding.notes)
    return problems


def _kinds() -> tuple[Any, ...]:
    from shary.io.filekinds import FileKind

    return (FileKind("robot-binding", _check_bindings, 5, detect=lambda d: "binding" in d,
                     keys="binding:", shipped=shipped_bindings),)


KINDS = _kinds()
"""The kind of file ``shary validate`` learns from this module (entry point
``shary.file_kinds``)."""
