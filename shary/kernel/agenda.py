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

from shary.kernel.recipes import Chronicle, ChronicleAll, ChronicleEvent

if TYPE_CHECKING:
    from shary.kernel.supervisor import Supervisor, TaskRun

PENDING, ACTIVE, SUSPENDED, DONE, FAILED = "pending", "active", "suspended", "done", "failed"
CANCELLED = "cancelled"
OVER = (DONE, FAILED, CANCELLED)


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
    scheme: Any = None
    """The scheme variant to run it with (None: the task's own choice)."""
    initiator: str | None = None
    """The person who asked for it (None: a goal of the robot's or of its operator)."""

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
        """Told when a goal is over (done, failed or cancelled): who delegated it hears
        back; a session is idle again."""
        self.admits: list[Callable[[Goal], bool]] = []
        """Gates a pending goal must pass to start (``gate(goal) -> bool``): the
        interaction sessions' (:mod:`shary.dialogue.sessions`): no task with a person
        outside a session with them.  A gate that changes its mind calls
        :meth:`reconsider`."""

    def todo(self, name: str = "default") -> list[Goal]:
        """The goals of one TODO list that are not over, in the order they were added."""
        return [g for g in self.goals if g.todo == name and g.state not in OVER]

    @property
    def active(self) -> Goal | None:
        return next((g for g in self.goals if g.state == ACTIVE), None)

    def add(self, task: str, args: dict[str, Any] | None = None, *, priority: int = 0,
            todo: str = "default", source: str = "request", scheme: Any = None,
            initiator: str | None = None) -> Goal:
        """Add a goal unless the same one (task and arguments) is already there."""
        args = dict(args or {})
        if task not in self.sup.library.tasks:
            raise KeyError(f"unknown task {task!r}")
        key = _key(task, args)
        for goal in self.goals:
            if goal.key == key and goal.state not in OVER:
                goal.sources.add(source)
                if priority > goal.priority:
                    goal.priority = priority
                self.sup.record("goal-merged", goal=goal.id, name=task, source=source)
                self.sup.loop.call_soon(self._schedule)
                return goal
        goal = Goal(next(self._ids), task, args, priority, todo, {source}, scheme=scheme,
                    initiator=initiator)
        self.goals.append(goal)
        self.sup.record("goal-added", goal=goal.id, name=task, args=args, priority=priority,
                        todo=todo, source=source)
        self.sup.loop.call_soon(self._schedule)
        return goal

    def reconsider(self) -> None:
        """Look again at which goal to run (a gate of :attr:`admits` changed its mind)."""
        self.sup.loop.call_soon(self._schedule)

    def cancel(self, goal: Goal, reason: str) -> None:
        """Drop a goal: its task, if it runs, stops at once (everything it does is
        cancelled), and the next goal starts."""
        if goal.state in OVER:
            return
        goal.state = CANCELLED
        if goal.run is not None:
            goal.run.cancel(reason)
        self.sup.record("goal-over", task=goal.run.node if goal.run else None, goal=goal.id,
                        name=goal.task, outcome=CANCELLED, reason=reason)
        for listener in self.listeners:
            listener(goal)
        self.sup.loop.call_soon(self._schedule)

    def _admitted(self, goal: Goal) -> bool:
        return goal.state != PENDING or all(gate(goal) for gate in self.admits)

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
                   and (floor is None or g.priority >= floor) and self._admitted(g)]
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
                                       on_finish=lambda run, g=best: self._finished(g, run),
                                       scheme=best.scheme, initiator=best.initiator)

    def _finished(self, goal: Goal, run: TaskRun) -> None:
        if goal.state in OVER:
            return
        goal.state = DONE if run.outcome == "done" else FAILED
        because = {"reason": run.stopped_by} if goal.state == FAILED and run.stopped_by \
            else {}
        self.sup.record("goal-over", task=run.node, goal=goal.id, name=goal.task,
                        outcome=run.outcome, **because)
        for listener in self.listeners:
            listener(goal)
        self._schedule()


def _holder(holds: dict[str, int]) -> str:
    """Who holds the agenda at the highest priority."""
    return max(holds.items(), key=lambda item: item[1])[0]


@dataclass(eq=False)
class _Partial:
    """A chronicle recognized up to some step, with its variable bindings.

    ``index`` is the step waited for; ``time`` when the step before it was over.
    In a step of several events (:class:`~shary.kernel.recipes.ChronicleAll`), ``done``
    are the events of it seen so far, the first of them at ``first``.
    """

    chronicle: Chronicle
    index: int
    bindings: dict[str, Any]
    time: float
    timer: Any = None
    done: frozenset[int] = frozenset()
    first: float | None = None


def _members(step: ChronicleEvent | ChronicleAll) -> tuple[ChronicleEvent, ...]:
    return step.events if isinstance(step, ChronicleAll) else (step,)


class ChronicleRecognizer:
    """Recognizes the library's chronicles in fact events and adds their goals.

    A chronicle is a sequence of steps; a step is one fact event, or several in
    any order (``all:``, a partially ordered conjunction: "comes near the robot"
    and "looks at it", whichever first)."""

    def __init__(self, sup: Supervisor, perspective: str = "robot",
                 chronicles: dict[str, Chronicle] | None = None,
                 recognized: Callable[[Chronicle, dict[str, Any]], Any] | None = None):
        """``chronicles`` default to the library's; ``recognized(chronicle, args)``,
        when given, is called instead of adding the chronicle's goal (the sessions
        open a session on the will to interact)."""
        self.sup = sup
        self.perspective = perspective
        self.chronicles = sup.library.chronicles if chronicles is None else chronicles
        self.recognized = recognized
        self.partials: list[_Partial] = []
        self.fired: set[tuple] = set()
        predicates = sorted({str(e.pattern.predicate.value)
                             for c in self.chronicles.values() for step in c.events
                             for e in _members(step)})
        self.subscriptions = [sup.facts.subscribe(self._on_fact, predicate=p,
                                                  perspective=perspective)
                              for p in predicates]

    @property
    def timing(self) -> bool:
        """Whether a chronicle waits for a fact to stay (a goal may come of it): a run
        that ends when nothing is left to do waits for it."""
        return any(partial.timer is not None for partial in self.partials)

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
                assert isinstance(stayed, ChronicleEvent)
                if self._breaks(stayed, partial.bindings, event.kind, fact):
                    partial.timer.cancel()
                    self.partials.remove(partial)
                continue
            step = partial.chronicle.events[partial.index]
            if isinstance(step, ChronicleAll):
                if (step.within is not None and partial.first is not None
                        and now - partial.first > step.within):
                    self.partials.remove(partial)  # the rest came too late
                    continue
                found = self._member(step, partial, event.kind, fact, now)
                if found is not None:
                    self.partials.remove(partial)
                    advanced.append(found)
                continue
            bindings = self._match(step, event.kind, fact, partial.bindings)
            if bindings is None:
                continue
            elapsed = now - partial.time
            if step.within is not None and elapsed > step.within:
                self.partials.remove(partial)
                continue
            if step.after is not None and elapsed < step.after:
                continue
            self.partials.remove(partial)
            advanced.append(_Partial(partial.chronicle, partial.index + 1, bindings, now))
        for chronicle in self.chronicles.values():
            first = chronicle.events[0]
            if isinstance(first, ChronicleAll):
                found = self._member(first, _Partial(chronicle, 0, {}, now), event.kind, fact,
                                     now)
                if found is not None:
                    advanced.append(found)
                continue
            bindings = self._match(first, event.kind, fact, {})
            if bindings is not None:
                advanced.append(_Partial(chronicle, 1, bindings, now))
        for partial in advanced:
            self._progress(partial)

    def _member(self, step: ChronicleAll, partial: _Partial, kind: str, fact: tuple,
                now: float) -> _Partial | None:
        """The partial once one more event of ``step`` is seen (None: none fits); when
        it is the last, the next step is waited for."""
        if partial.first is None and step.after is not None and now - partial.time < step.after:
            return None
        for i, member in enumerate(step.events):
            if i in partial.done:
                continue
            bindings = self._match(member, kind, fact, partial.bindings)
            if bindings is None:
                continue
            done = partial.done | {i}
            if len(done) == len(step.events):
                return _Partial(partial.chronicle, partial.index + 1, bindings, now)
            return _Partial(partial.chronicle, partial.index, bindings, partial.time,
                            done=done, first=partial.first if partial.first is not None
                            else now)
        return None

    def _progress(self, partial: _Partial) -> None:
        if partial.done:  # a step of several events, some still to come
            self.partials.append(partial)
            return
        done_step = partial.chronicle.events[partial.index - 1]
        if isinstance(done_step, ChronicleEvent) and done_step.stays is not None:
            self.partials.append(partial)
            partial.timer = self.sup.loop.call_later(done_step.stays, self._stayed, partial)
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
        if self.recognized is not None:
            self.recognized(chronicle, args)
            return
        if key in self.fired and any(g.state not in OVER and g.key == _key(
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
