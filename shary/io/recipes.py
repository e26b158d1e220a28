"""Loading recipe libraries: schema first, then meaning, across all files at once.

Files refer to each other (a recipe in one file serves a task declared in
another), so :func:`load_library` reads every file, then checks the whole:
unknown tasks, acts, parameters, atomic tasks and predicates, acts that the
task's scheme never carries out, cyclic orderings of steps, missing arguments,
chronicle goals using unbound variables.  Every problem names its file,
line and column.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import networkx as nx

from shary import builtin
from shary.dialogue.speech import check_say
from shary.io import schema
from shary.io.schemes import load_scheme
from shary.kernel.recipes import (
    ANY_TASK,
    INITIATOR_PARAM,
    ROBOT_PARAM,
    AtomicTask,
    Chronicle,
    ChronicleAll,
    ChronicleEvent,
    Condition,
    Monitor,
    Pattern,
    PlanSpec,
    Recipe,
    RecipeLibrary,
    Retry,
    SchemeChoice,
    Step,
    TaskType,
    Term,
    parse_refinement,
)
from shary.statechart.acts import ACT_TYPES, ActRegistry, acts_from_data, builtin_acts
from shary.statechart.model import Scheme
from userfiles.errors import FileError, Problem
from userfiles.limits import seconds
from userfiles.reader import Reader, checked, confine, spelled
from userfiles.schema import did_you_mean

ANY = TaskType(ANY_TASK, (), {}, ())
"""What a recipe for any task may assume: only the robot."""


def builtin_library_files() -> list[Path]:
    return builtin.files("recipes")


def load_library(paths: list[str | os.PathLike[str]] | None = None, *,
                 acts: ActRegistry | None = None, with_builtin: bool = True) -> RecipeLibrary:
    """Load and check recipe files (the built-in ones first, unless told otherwise)."""
    files = [Path(p) for p in (builtin_library_files() if with_builtin else [])]
    loaded = {f.resolve() for f in files}  # a built-in file given by path is loaded once
    for path in map(Path, paths or []):
        if path.resolve() not in loaded:
            loaded.add(path.resolve())
            files.append(path)
    problems: list[Problem] = []
    documents: list[Reader] = []
    for path in files:
        # Every file's shape problems are reported, and the names a file that is a
        # mapping declares stay known (no cascade of "unknown task" in the others);
        # its meaning is only checked once its shape is right, so that meaning
        # checks never meet a number where the schema promised a list.
        try:
            reader = checked(path, schema.validator("recipes"))
        except FileError as err:
            problems.extend(err.problems)
            continue
        if isinstance(reader.data, dict):
            documents.append(reader)
        else:
            problems.extend(reader.problems)
    builder = _Builder(acts or builtin_acts())
    for reader in documents:
        builder.declare_acts(reader)
    for reader in documents:
        builder.declare(reader)
    for reader in documents:
        if reader.shape_ok:
            builder.define(reader)
    builder.check_starts()
    for reader in documents:
        problems.extend(reader.problems)
    if problems:
        raise FileError(problems)
    builder.library.acts = builder.acts
    return builder.library


class _Builder:
    def __init__(self, acts: ActRegistry):
        self.acts = acts
        self.library = RecipeLibrary()
        self.schemes: dict[str, Scheme | None] = {}
        self.starts = nx.DiGraph()
        """Task -> the subtask an unconditional recipe of it starts first, with where."""

    # -- first pass: the vocabulary ----------------------------------------

    def declare_acts(self, reader: Reader) -> None:
        """Acts declared under ``acts:``: usable by every file of the library, and by the
        scenarios that load it."""
        own = reader.data.get("acts")
        if not isinstance(own, dict):
            return
        for name in own:
            if name in ACT_TYPES:
                reader.problem(("acts", name), f"{name!r} is an act type, not an act "
                             "name", key=True)
        self.acts = self.acts.extended(acts_from_data(
            {k: v if isinstance(v, dict) else None for k, v in own.items()}, reader.file))

    def declare(self, reader: Reader) -> None:
        data = reader.data
        for name, doc in _items(data.get("predicates")):
            self.library.predicates[name] = doc if isinstance(doc, str) else ""
        for name, spec in _items(data.get("atomic")):
            spec = spec if isinstance(spec, dict) else {}
            self.library.atomic[name] = AtomicTask(name, tuple(_strings(spec.get("params"))),
                                                   spec.get("doc", "") or "")
        for name, spec in _items(data.get("tasks")):
            if isinstance(spec, dict):
                self._task(reader, name, spec)

    def _task(self, reader: Reader, name: str, spec: dict[str, Any]) -> None:
        path = ("tasks", name)
        if name in self.library.tasks:
            reader.problem(path, f"task {name!r} is declared twice", key=True)
            return
        params = tuple(_strings(spec.get("params")))
        for implicit in (ROBOT_PARAM, INITIATOR_PARAM):
            if implicit in params:
                reader.problem(path + ("params",), f"'{implicit}' is implicit: every "
                             "task has it")
        env = {ROBOT_PARAM, *params}
        raw = spec.get("scheme")
        if isinstance(raw, str):
            options = [(path + ("scheme",), raw, path, None)]
        else:
            options = [(path + ("scheme", i, "scheme"), c.get("scheme"),
                        path + ("scheme", i, "when"), c.get("when"))
                       for i, c in enumerate(raw if isinstance(raw, list) else [])
                       if isinstance(c, dict)]
        choices = []
        for where, scheme_name, when_path, when in options:
            scheme = self._scheme(reader, where, scheme_name)
            conditions = self._conditions(reader, when_path, when, env)
            if scheme is not None:
                choices.append(SchemeChoice(scheme, conditions))
        roles = {k: Term.parse(v) for k, v in _items(spec.get("roles"))}
        for role, term in roles.items():
            self._check_term(reader, path + ("roles", role), term, env)
        for choice in choices:
            for role in choice.scheme.roles:
                if role not in roles and role != ROBOT_PARAM and role not in params:
                    reader.problem(path, f"scheme {choice.scheme.name!r} has the role "
                                 f"{role!r}; say who plays it under 'roles:' (e.g. "
                                 f"{role}: $someone)", key=True)
        self.library.tasks[name] = TaskType(name, params, roles, tuple(choices),
                                            spec.get("doc", "") or "")

    def _scheme(self, reader: Reader, path: tuple, name: Any) -> Scheme | None:
        if not isinstance(name, str):
            return None
        ref = name
        if name.endswith((".yaml", ".yml")) or "/" in name:
            full, refusal = confine(reader.file, name, roots=[builtin.folder("schemes")])
            if refusal is not None:
                reader.problem(path, refusal)
                return None
            ref = spelled(full, like=reader.file)
        if ref not in self.schemes:
            try:
                self.schemes[ref] = load_scheme(ref, acts=self.acts)
                # The acts the scheme declares are usable by the recipes that follow.
                self.acts = self.acts.extended(self.schemes[ref].acts.acts)
            except FileError as err:
                self.schemes[ref] = None
                if ref == name and not name.endswith((".yaml", ".yml")):  # an unknown name
                    messages = "; ".join(p.message for p in err.problems[:3])
                    reader.problem(path, f"scheme {name!r} cannot be used: {messages}")
                else:  # the scheme's own problems, reported once, under its own name
                    reader.problems.extend(err.problems)
                    reader.problem(path, f"depends on {ref}, which has errors")
        return self.schemes[ref]

    # -- second pass: recipes and chronicles ---------------------------------

    def define(self, reader: Reader) -> None:
        data = reader.data
        recipes = data.get("recipes")
        for index, spec in enumerate(recipes if isinstance(recipes, list) else []):
            if isinstance(spec, dict):
                self._recipe(reader, ("recipes", index), spec)
        for name, spec in _items(data.get("chronicles")):
            if isinstance(spec, dict):
                self._chronicle(reader, ("chronicles", name), name, spec)

    def _recipe(self, reader: Reader, path: tuple, spec: dict[str, Any]) -> None:
        task_name, act = spec.get("task"), spec.get("act")
        if not isinstance(task_name, str) or not isinstance(act, str):
            return
        task = ANY if task_name == ANY_TASK else self.library.tasks.get(task_name)
        if task is None:
            reader.problem(path + ("task",), f"unknown task {task_name!r}"
                         f"{did_you_mean(task_name, self.library.tasks)}")
            return
        if act not in self.acts:
            reader.problem(path + ("act",), f"unknown act {act!r}"
                         f"{did_you_mean(act, self.acts.acts)}")
            return
        if task.schemes and not any(any(s.act == act for s in c.scheme.states.values())
                                    for c in task.schemes):
            names = ", ".join(c.scheme.name for c in task.schemes)
            reader.problem(path + ("act",), f"no state of the scheme(s) of task "
                         f"{task_name!r} ({names}) carries out {act!r}")
        env = {ROBOT_PARAM, INITIATOR_PARAM, *task.params}
        steps = self._steps(reader, path + ("steps",), spec.get("steps"), env)
        monitors = tuple(self._monitor(reader, path + ("monitors", i), m, env)
                         for i, m in enumerate(spec.get("monitors") or [])
                         if isinstance(m, dict))
        for i, monitor in enumerate(monitors):
            if monitor.until is not None and monitor.until not in {s.name for s in steps}:
                reader.problem(path + ("monitors", i, "until"),
                               f"no step named {monitor.until!r} in this recipe")
        plan = None
        if isinstance(spec.get("plan"), dict):
            raw = spec["plan"]
            args = {k: Term.parse(v) for k, v in _items(raw.get("with"))}
            for key, term in args.items():
                self._check_term(reader, path + ("plan", "with", key), term, env)
            refine = {k: str(v) for k, v in _items(raw.get("refine"))}
            for action, text in refine.items():
                self._check_refinement(reader, path + ("plan", "refine", action), text)
            facts = {}
            for attribute, given in _items(raw.get("facts")):
                predicates = ((given,) if isinstance(given, str)
                              else tuple(given) if isinstance(given, list) else ())
                for i, predicate in enumerate(predicates):
                    name = str(predicate).removeprefix("^")
                    if name not in self.library.predicates:
                        at = path + ("plan", "facts", attribute)
                        reader.problem(at + ((i,) if not isinstance(given, str) else ()),
                                     f"unknown predicate {name!r}"
                                     + did_you_mean(name, self.library.predicates))
                facts[str(attribute)] = tuple(str(p) for p in predicates)
            plan = PlanSpec(str(raw.get("domain")), str(raw.get("task")), args, refine, facts)
        retry = Retry()
        if isinstance(spec.get("retry"), dict):
            raw = spec["retry"]
            then = raw.get("then", "fail")
            retry = Retry(int(raw.get("max_attempts", 1)),
                          "emit" if isinstance(then, dict) else str(then),
                          then.get("emit") if isinstance(then, dict) else None)
        given = [k for k in ("steps", "plan", "function") if k in spec]
        if len(given) > 1:
            reader.problem(path + (given[1],), f"a recipe has steps, a plan or a "
                         f"function, not {' and '.join(given)}", key=True)
        when = self._conditions(reader, path + ("when",), spec.get("when"), env)
        on = tuple(str(e) for e in spec.get("on") or ())
        if on and task.schemes:
            entering = {e for c in task.schemes for e in _events_into(c.scheme, act)}
            for i, event in enumerate(on):
                if event not in entering:
                    reader.problem(path + ("on", i), f"no transition of the scheme(s) "
                                   f"of task {task_name!r} enters {act} on {event!r}"
                                   f"{did_you_mean(event, entering)}; events: "
                                   f"{', '.join(sorted(entering)) or 'none'}")
        if not when and task is not ANY:
            self._note_starts(reader, path, task_name, spec.get("steps"))
        rank = len(self.library.recipes_for(task_name, act)) + 1
        name = spec.get("name") or f"{task_name}/{act}#{rank}"
        self.library.recipes.append(Recipe(
            name, task_name, act, when, steps, plan,
            spec.get("function") if isinstance(spec.get("function"), str) else None,
            monitors, retry, spec.get("doc", "") or "", reader.file,
            reader.located.key_at(path), on))

    def _note_starts(self, reader: Reader, path: tuple, task: str, raw: Any) -> None:
        """Record the subtasks a recipe starts before anything else (no ``after``)."""
        for index, spec in enumerate(raw if isinstance(raw, list) else []):
            first = spec.get("after") == [] if "after" in spec else index == 0
            if first and isinstance(spec.get("task"), str) \
                    and not self.starts.has_edge(task, spec["task"]):
                self.starts.add_edge(task, spec["task"], at=(reader, path + ("steps", index)))

    def check_starts(self) -> None:
        """Refuse tasks that start themselves before anything happens, at the step that does.

        A recipe without ``when:`` whose first step is its own task (or a
        task whose first step leads back to it) starts that task again at the
        same instant, with nothing done in between that could end it: a run
        would only stop when Python's stack does.
        """
        for component in nx.strongly_connected_components(self.starts):
            task = min(component)
            if len(component) == 1 and not self.starts.has_edge(task, task):
                continue
            cycle = nx.find_cycle(self.starts.subgraph(component), task)
            loop = " -> ".join([a for a, _ in cycle] + [cycle[0][0]])
            reader, at = self.starts.edges[cycle[0]]["at"]
            reader.problem(at, f"task {task!r} starts itself before anything else happens "
                           f"({loop}: each recipe on the way, none with 'when:', starts the "
                           "next task first): a run would start it again without end")

    def _steps(self, reader: Reader, path: tuple, raw: Any,
               env: set[str]) -> tuple[Step, ...]:
        if not isinstance(raw, list):
            return ()
        steps: list[Step] = []
        names: dict[str, int] = {}
        order = nx.DiGraph()
        for index, spec in enumerate(raw):
            if not isinstance(spec, dict):
                continue
            where = path + (index,)
            name = spec.get("name") or spec.get("do") or spec.get("task") or f"step{index + 1}"
            if name in names:
                name = f"{name}-{index + 1}" if "name" not in spec else name
                if name in names:
                    reader.problem(where + ("name",), f"two steps are named {name!r}")
                    continue
            names[name] = index
            after = tuple(_strings(spec.get("after"))) if "after" in spec else \
                ((steps[-1].name,) if steps else ())
            args = {k: Term.parse(v) for k, v in _items(spec.get("with"))}
            for key, term in args.items():
                self._check_term(reader, where + ("with", key), term, env)
            by = Term.parse(spec["by"]) if "by" in spec else None
            if by is not None:
                self._check_term(reader, where + ("by",), by, env)
            atomic, task = spec.get("do"), spec.get("task")
            if isinstance(atomic, str):
                self._check_call(reader, where, "atomic task", atomic, self.library.atomic,
                                 self.library.atomic.get(atomic) and
                                 self.library.atomic[atomic].params, args)
            if atomic == "say":  # a generated sentence: its act and action are checked now
                for key, message in check_say(dict(_items(spec.get("with"))), env):
                    reader.problem(where + ("with", key), message)
            if isinstance(task, str):
                self._check_call(reader, where, "task", task, self.library.tasks,
                                 self.library.tasks.get(task) and
                                 self.library.tasks[task].params, args)
            step = Step(name, atomic if isinstance(atomic, str) else None,
                        task if isinstance(task, str) else None, args, by, after,
                        spec.get("emit"))
            steps.append(step)
            order.add_node(name)
        for step in steps:
            for before in step.after:
                if before not in names:
                    reader.problem(path + (names[step.name], "after"),
                                 f"step {step.name!r} comes after {before!r}, which is not a "
                                 f"step of this recipe{did_you_mean(before, names)}")
                else:
                    order.add_edge(before, step.name)
        try:
            cycle = nx.find_cycle(order)
        except nx.NetworkXNoCycle:
            cycle = []
        if cycle:
            loop = " -> ".join([a for a, _ in cycle] + [cycle[0][0]])
            reader.problem(path, f"the steps are ordered in a cycle: {loop}")
        return tuple(steps)

    def _check_refinement(self, reader: Reader, path: tuple, text: str) -> None:
        try:
            target, mapping = parse_refinement(text)
        except ValueError as err:
            reader.problem(path, str(err))
            return
        known = {**{n: a.params for n, a in self.library.atomic.items()},
                 **{n: t.params for n, t in self.library.tasks.items()}}
        if target not in known:
            reader.problem(path, f"unknown task or atomic task {target!r}"
                         f"{did_you_mean(target, known)}")
            return
        params = known[target]
        wrong = [k for k in mapping if k not in params]
        missing = [p for p in params if p not in mapping]
        if wrong or missing:
            reader.problem(path, f"{target} takes {', '.join(params) or 'nothing'}"
                         + (f"; unknown: {', '.join(wrong)}" if wrong else "")
                         + (f"; missing: {', '.join(missing)}" if missing else ""))

    def _check_call(self, reader: Reader, where: tuple, what: str, name: str,
                    known: dict, params: Any, args: dict[str, Term]) -> None:
        key = "do" if what == "atomic task" else "task"
        if name not in known:
            reader.problem(where + (key,), f"unknown {what} {name!r}"
                         f"{did_you_mean(name, known)}" + ("; declare it under 'atomic:'"
                                                          if what == "atomic task" else ""))
            return
        params = tuple(params or ())
        for arg in args:
            if arg not in params:
                reader.problem(where + ("with", arg), f"{what} {name!r} has no "
                             f"parameter {arg!r}{did_you_mean(arg, params)}; its parameters: "
                             f"{', '.join(params) or 'none'}", key=True)
        missing = [p for p in params if p not in args]
        if missing:
            reader.problem(where + (key,), f"{what} {name!r} needs "
                         f"{', '.join(missing)} (under 'with:')")

    def _monitor(self, reader: Reader, path: tuple, spec: dict[str, Any],
                 env: set[str]) -> Monitor:
        change = "added" if "added" in spec else "removed"
        pattern = self._pattern(reader, path + (change,), spec.get(change), env)
        perspective = Term.parse(spec["perspective"]) if "perspective" in spec else None
        if perspective is not None:
            self._check_term(reader, path + ("perspective",), perspective, env)
        name = spec.get("name") or f"{change}-{pattern.predicate}"
        until = str(spec["until"]) if "until" in spec else None
        return Monitor(name, change, pattern, str(spec.get("emit", "")), perspective, until)

    def _pattern(self, reader: Reader, path: tuple, raw: Any, env: set[str],
                 variables: set[str] | None = None) -> Pattern:
        items = raw if isinstance(raw, list) and len(raw) == 3 else ["_", "_", "_"]
        terms = [Term.parse(x) for x in items]
        for index, term in enumerate(terms):
            if term.kind == "param" and variables is not None:
                variables.add(term.value)
            else:
                self._check_term(reader, path + (index,), term, env)
        predicate = terms[1]
        if predicate.kind != "const":
            reader.problem(path + (1,), "the predicate of a pattern must be a constant")
        elif predicate.value not in self.library.predicates:
            reader.problem(path + (1,), f"unknown predicate {predicate.value!r}"
                         f"{did_you_mean(str(predicate.value), self.library.predicates)}; "
                         "declare it under 'predicates:'")
        return Pattern(*terms)

    def _conditions(self, reader: Reader, path: tuple, raw: Any,
                    env: set[str]) -> tuple[Condition, ...]:
        out = []
        for index, spec in enumerate(raw if isinstance(raw, list) else []):
            if isinstance(spec, dict) and spec:
                negated = "not" in spec
                key = "not" if negated else "holds"
                pattern = self._pattern(reader, path + (index, key), spec.get(key), env)
                if pattern.subject.kind == "any" or pattern.predicate.kind == "any":
                    reader.problem(path + (index, key), "a condition needs a subject "
                                 "and a predicate (only the object may be _)")
                out.append(Condition(pattern, negated))
        return tuple(out)

    def _check_term(self, reader: Reader, path: tuple, term: Term,
                    env: set[str]) -> None:
        if term.kind == "param" and term.value not in env:
            reader.problem(path, f"unknown parameter ${term.value}"
                         f"{did_you_mean(term.value, sorted(env))}; parameters here: "
                         f"{', '.join('$' + p for p in sorted(env))}")

    def _chronicle(self, reader: Reader, path: tuple, name: str,
                   spec: dict[str, Any]) -> None:
        variables: set[str] = set()
        events = []
        for index, raw in enumerate(spec.get("events") or []):
            if not isinstance(raw, dict):
                continue
            timing = {k: amount for k in ("within", "after", "stays")
                      if (amount := _duration(raw.get(k))) is not None}
            if "all" in raw:  # several events in any order
                if "stays" in timing:
                    reader.problem(path + ("events", index, "stays"), "'stays' follows one "
                                   "event; give it to a step of its own after the 'all'",
                                   key=True)
                members = []
                for i, member in enumerate(raw.get("all") or []):
                    if isinstance(member, dict):
                        change = "added" if "added" in member else "removed"
                        members.append(ChronicleEvent(change, self._pattern(
                            reader, path + ("events", index, "all", i, change),
                            member.get(change), set(), variables)))
                events.append(ChronicleAll(tuple(members), timing.get("within"),
                                           timing.get("after")))
                continue
            change = "added" if "added" in raw else "removed"
            pattern = self._pattern(reader, path + ("events", index, change), raw.get(change),
                                    set(), variables)
            events.append(ChronicleEvent(change, pattern, **timing))
        goal = spec.get("goal") if isinstance(spec.get("goal"), dict) else {}
        task_name = goal.get("task")
        args = {k: Term.parse(v) for k, v in _items(goal.get("with"))}
        task = self.library.tasks.get(task_name) if isinstance(task_name, str) else None
        if isinstance(task_name, str) and task is None:
            reader.problem(path + ("goal", "task"), f"unknown task {task_name!r}"
                         f"{did_you_mean(task_name, self.library.tasks)}")
        for key, term in args.items():
            if term.kind == "param" and term.value not in variables:
                reader.problem(path + ("goal", "with", key), f"${term.value} is not "
                             "bound by any event of the chronicle")
            if task is not None and key not in task.params:
                reader.problem(path + ("goal", "with", key), f"task {task_name!r} has "
                             f"no parameter {key!r}", key=True)
        if task is not None:
            missing = [p for p in task.params if p not in args]
            if missing:
                reader.problem(path + ("goal",), f"the goal needs {', '.join(missing)} "
                             "(under 'with:')")
        self.library.chronicles[name] = Chronicle(
            name, tuple(events), str(task_name), args, int(goal.get("priority", 0)),
            str(goal.get("todo", "default")), spec.get("doc", "") or "")


def _items(value: Any) -> list[tuple[str, Any]]:
    return list(value.items()) if isinstance(value, dict) else []


def _strings(value: Any) -> list[str]:
    return [v for v in value if isinstance(v, str)] if isinstance(value, list) else []


def _duration(value: Any) -> float | None:
    """Seconds in a duration as files write it; None when the schema check refused it."""
    try:
        return seconds(value)
    except ValueError:
        return None


def _events_into(scheme: Any, act: str) -> set[str]:
    """The events (as written: ``H-DISAGREE``, ``after 15s``) of the transitions that
    enter a state carrying ``act`` in ``scheme``."""
    found: set[str] = set()
    for state in scheme.states.values():
        for transition in state.transitions:
            if not any(scheme.states[t].act == act for t in transition.targets
                       if t in scheme.states):
                continue
            if transition.after is not None:
                found.add(transition.label().split(" [")[0])
            else:
                found.update(transition.events or ())
    return found
