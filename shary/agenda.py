"""The Task Agenda and chronicles: which goal the robot pursues, and its initiative.

SHARY: "The Task Agenda maintains several TODO lists that specify the robot
tasks ... the Agenda adds a high-level goal into the appropriate TODO list if
the goal is not already present.  This means that if the robot detects the
need to serve a drink and takes the initiative to do it, and if at the same
time the person requests to serve him a drink, the task will be added only
once ... It is able to suspend an ongoing task in order to execute tasks with
a higher priority."

:class:`TaskAgenda` runs one goal at a time: the highest priority, the oldest
first among equals.  A goal of higher priority suspends the running one (its
acts stop acting, its tree is kept); the suspended goal resumes when nothing
more urgent is left.

:class:`ChronicleRecognizer` watches fact events for the patterns of the
library's chronicles ("a person comes near the table, stays, leaves") and puts
their goals on the agenda, as the robot's own initiative.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from shary.recipes import Chronicle, ChronicleEvent

if TYPE_CHECKING:
    from shary.supervisor import Supervisor, TaskRun

PENDING, ACTIVE, SUSPENDED, DONE, FAILED = "pending", "active", "suspended", "done", "failed"


@dataclass(eq=False)
class Goal:
    """A high-level goal in a TODO list."""

    id: int
    task: str
    args: dict[str, Any]
    priority: int
    todo: str
    sources: set[str] = field(default_factory=set)
    state: str = PENDING
    run: TaskRun | None = None

    @property
    def key(self) -> tuple[str, tuple[tuple[str, str], ...]]:
        return _key(self.task, self.args)


def _key(task: str, args: dict[str, Any]) -> tuple[str, tuple[tuple[str, str], ...]]:
    return task, tuple(sorted((k, str(v)) for k, v in args.items()))


class TaskAgenda:
    """TODO lists of goals, run one at a time by priority (see the module's docstring)."""

    def __init__(self, sup: Supervisor):
        self.sup = sup
        self.goals: list[Goal] = []
        self._ids = itertools.count(1)
        self.holds: dict[str, int] = {}
        """Holder -> priority: while held, goals of lower priority do not run (a robot
        associated with a person serves only that person's requests, HRI/OS Fig. 7)."""
        self.listeners: list[Callable[[Goal], Any]] = []
        """Told when a goal is over (done or failed): who delegated it hears back."""

    def todo(self, name: str = "default") -> list[Goal]:
        """The goals of one TODO list that are not over, in the order they were added."""
        return [g for g in self.goals if g.todo == name and g.state not in (DONE, FAILED)]

    @property
    def active(self) -> Goal | None:
        return next((g for g in self.goals if g.state == ACTIVE), None)

    def add(self, task: str, args: dict[str, Any] | None = None, *, priority: int = 0,
            todo: str = "default", source: str = "request") -> Goal:
        """Add a goal unless the same one (task and arguments) is already there."""
        args = dict(args or {})
        if task not in self.sup.library.tasks:
            raise KeyError(f"unknown task {task!r}")
        key = _key(task, args)
        for goal in self.goals:
            if goal.key == key and goal.state not in (DONE, FAILED):
                goal.sources.add(source)
                if priority > goal.priority:
                    goal.priority = priority
                self.sup.record("goal-merged", goal=goal.id, name=task, source=source)
                self.sup.loop.call_soon(self._schedule)
                return goal
        goal = Goal(next(self._ids), task, args, priority, todo, {source})
        self.goals.append(goal)
        self.sup.record("goal-added", goal=goal.id, name=task, args=args, priority=priority,
                        todo=todo, source=source)
        self.sup.loop.call_soon(self._schedule)
        return goal

    def hold(self, holder: str, priority: int) -> None:
        """Run only goals of ``priority`` or more until :meth:`release` (the running goal,
        if lower, is suspended at once)."""
        self.holds[holder] = priority
        self.sup.record("agenda-hold", holder=holder, priority=priority)
        self.sup.loop.call_soon(self._schedule)

    def release(self, holder: str) -> None:
        """End a :meth:`hold`; the goals it kept waiting go on."""
        if self.holds.pop(holder, None) is not None:
            self.sup.record("agenda-release", holder=holder)
            self.sup.loop.call_soon(self._schedule)

    def _floor(self) -> int | None:
        return max(self.holds.values()) if self.holds else None

    def _best(self) -> Goal | None:
        floor = self._floor()
        waiting = [g for g in self.goals if g.state in (PENDING, SUSPENDED, ACTIVE)
                   and (floor is None or g.priority >= floor)]
        if not waiting:
            return None
        return max(waiting, key=lambda g: (g.priority, -g.id))

    def _schedule(self) -> None:
        best = self._best()
        current = self.active
        if best is current:
            return
        if current is not None:
            floor = self._floor()
            held = floor is not None and current.priority < floor
            if not held and best is not None and current.priority >= best.priority:
                return
            current.state = SUSPENDED
            why = (f"held by {_holder(self.holds)}" if held or best is None
                   else f"goal {best.id} ({best.task}) is more urgent")
            self.sup.record("goal-suspended", task=current.run.node if current.run else None,
                            goal=current.id, name=current.task,
                            by=best.id if best is not None else None, reason=why)
            if current.run is not None:
                current.run.suspend(why)
        if best is None:
            return
        if best.state == SUSPENDED and best.run is not None:
            best.state = ACTIVE
            self.sup.record("goal-resumed", task=best.run.node, goal=best.id, name=best.task)
            best.run.resume("the more urgent goal is over")
            return
        best.state = ACTIVE
        self.sup.record("goal-started", goal=best.id, name=best.task)
        best.run = self.sup.start_task(best.task, best.args,
                                       on_finish=lambda run, g=best: self._finished(g, run))

    def _finished(self, goal: Goal, run: TaskRun) -> None:
        goal.state = DONE if run.outcome == "done" else FAILED
        self.sup.record("goal-over", task=run.node, goal=goal.id, name=goal.task,
                        outcome=run.outcome)
        for listener in self.listeners:
            listener(goal)
        self._schedule()


def _holder(holds: dict[str, int]) -> str:
    """Who holds the agenda at the highest priority."""
    return max(holds.items(), key=lambda item: item[1])[0]


@dataclass(eq=False)
class _Partial:
    """A chronicle recognized up to some event, with its variable bindings."""

    chronicle: Chronicle
    index: int
    bindings: dict[str, Any]
    time: float
    timer: Any = None


class ChronicleRecognizer:
    """Recognizes the library's chronicles in fact events and adds their goals."""

    def __init__(self, sup: Supervisor, perspective: str = "robot"):
        self.sup = sup
        self.perspective = perspective
        self.partials: list[_Partial] = []
        self.fired: set[tuple] = set()
        predicates = sorted({str(e.pattern.predicate.value)
                             for c in sup.library.chronicles.values() for e in c.events})
        self.subscriptions = [sup.facts.subscribe(self._on_fact, predicate=p,
                                                  perspective=perspective)
                              for p in predicates]

    def close(self) -> None:
        for subscription in self.subscriptions:
            self.sup.facts.unsubscribe(subscription)
        for partial in self.partials:
            if partial.timer is not None:
                partial.timer.cancel()
        self.partials.clear()

    def _on_fact(self, event: Any) -> None:
        now = self.sup.loop.now()
        fact = (event.subject, event.predicate, event.object)
        advanced: list[_Partial] = []
        for partial in list(self.partials):
            if partial.timer is not None:
                stayed = partial.chronicle.events[partial.index - 1]
                if self._breaks(stayed, partial.bindings, event.kind, fact):
                    partial.timer.cancel()
                    self.partials.remove(partial)
                continue
            expected = partial.chronicle.events[partial.index]
            bindings = self._match(expected, event.kind, fact, partial.bindings)
            if bindings is None:
                continue
            elapsed = now - partial.time
            if expected.within is not None and elapsed > expected.within:
                self.partials.remove(partial)
                continue
            if expected.after is not None and elapsed < expected.after:
                continue
            self.partials.remove(partial)
            advanced.append(_Partial(partial.chronicle, partial.index + 1, bindings, now))
        for chronicle in self.sup.library.chronicles.values():
            bindings = self._match(chronicle.events[0], event.kind, fact, {})
            if bindings is not None:
                advanced.append(_Partial(chronicle, 1, bindings, now))
        for partial in advanced:
            self._progress(partial)

    def _progress(self, partial: _Partial) -> None:
        done_event = partial.chronicle.events[partial.index - 1]
        if done_event.stays is not None:
            self.partials.append(partial)
            partial.timer = self.sup.loop.call_later(done_event.stays, self._stayed, partial)
            return
        if partial.index == len(partial.chronicle.events):
            self._fire(partial)
        else:
            self.partials.append(partial)

    def _stayed(self, partial: _Partial) -> None:
        if partial not in self.partials:
            return
        partial.timer = None
        partial.time = self.sup.loop.now()
        if partial.index == len(partial.chronicle.events):
            self.partials.remove(partial)
            self._fire(partial)

    def _fire(self, partial: _Partial) -> None:
        chronicle = partial.chronicle
        args = {k: t.resolve(partial.bindings) for k, t in chronicle.args.items()}
        key = (chronicle.name, tuple(sorted((k, str(v)) for k, v in partial.bindings.items())))
        self.sup.record("chronicle", chronicle=chronicle.name, bindings=partial.bindings)
        if key in self.fired and any(g.state not in (DONE, FAILED) and g.key == _key(
                chronicle.task, args) for g in self.sup.agenda.goals):
            return
        self.fired.add(key)
        self.sup.agenda.add(chronicle.task, args, priority=chronicle.priority,
                            todo=chronicle.todo, source=f"chronicle:{chronicle.name}")

    @staticmethod
    def _match(expected: ChronicleEvent, kind: str, fact: tuple,
               bindings: dict[str, Any]) -> dict[str, Any] | None:
        if expected.change != kind:
            return None
        out = dict(bindings)
        for term, value in zip(expected.pattern.terms(), fact, strict=True):
            if term.kind == "any":
                continue
            if term.kind == "param":
                if term.value in out and str(out[term.value]) != str(value):
                    return None
                out[term.value] = value
            elif str(term.value) != str(value):
                return None
        return out

    def _breaks(self, stayed: ChronicleEvent, bindings: dict[str, Any], kind: str,
                fact: tuple) -> bool:
        """Whether a fact event undoes the fact a chronicle waits to see stay."""
        opposite = "removed" if stayed.change == "added" else "added"
        return kind == opposite and self._match(
            ChronicleEvent(opposite, stayed.pattern), kind, fact, bindings) is not None
