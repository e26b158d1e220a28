"""Act x task: one communication act instantiated within one task.

"An act inside a task ... is defined as a particular data structure: act X
task.  It is the data manipulated by the executive engine and to which will
be attached a recipe, an execution state, etc." (SHARY, section 2.2).

An :class:`ActTask` is created when its task's scheme enters a state carrying
an act.  It picks a recipe by context, grows the task tree with the recipe's
steps, starts the steps whose predecessors are done, attaches the recipe's
monitors to the fact database, retries failed steps, and tells the scheme
``done`` or ``failed`` when the recipe is over.  It can be suspended (running
atomic tasks are cancelled, the tree kept) and resumed (the interrupted steps
start again, finished ones stay finished), or stopped (everything cancelled,
the tree cut).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

from shary.kernel.executors import Outcome, Request
from shary.kernel.recipes import ROBOT_PARAM, Monitor, Recipe, Step
from shary.kernel.tasktree import ACT, ATOMIC, CANCELLED, DONE, FAILED, ONGOING, SUSPENDED, TODO
from shary.statechart.model import State

if TYPE_CHECKING:
    from shary.kernel.supervisor import TaskRun


@dataclass(eq=False, slots=True)
class StepRun:
    """A step of a running recipe: its tree node, its state, what performs it now."""

    step: Step
    node: str
    state: str = TODO
    attempts: int = 0
    request: Request | None = None
    child: TaskRun | None = None


class ActTask:
    """One act of one task, carried out by a recipe (see the module's docstring)."""

    __slots__ = ("run", "sup", "state", "act", "agent", "node", "recipe", "steps",
                 "subscriptions", "until", "started", "replans", "completes", "suspended", "over")

    def __init__(self, run: TaskRun, state: State, agent: str):
        self.run = run
        self.sup = run.sup
        self.state = state
        self.act = state.act or ""
        self.agent = agent
        self.node = self.sup.tree.add(ACT, f"{self.act} x {run.type.name}", run.node,
                                      act=self.act, act_type=state.act_type.name
                                      if state.act_type else None, agent=agent,
                                      scheme_state=state.name)
        self.recipe: Recipe | None = None
        self.steps: dict[str, StepRun] = {}
        self.subscriptions: list[Any] = []
        self.until: dict[str, list[Any]] = {}
        """Step name -> the monitors that stop when it starts (``until:``): a subtask when
        it is launched, an atomic task when its request begins (it may wait for the voice
        or an arm, :mod:`shary.kernel.arbiter`)."""
        self.started = False
        self.replans = 0
        self.completes = False
        self.suspended = False
        self.over = False

    # -- life cycle ----------------------------------------------------------

    def start(self) -> None:
        sup = self.sup
        self.started = True
        sup.tree.set_state(self.node, ONGOING)
        self.recipe = sup.choose_recipe(self.run, self.act)
        if self.recipe is None:
            sup.record("recipe", task=self.node, agent=self.agent, act=self.act,
                       recipe=None, note="no recipe: the act waits for what its scheme expects")
            return
        sup.record("recipe", task=self.node, agent=self.agent, act=self.act,
                   recipe=self.recipe.name, recipe_kind=self.recipe.kind)
        # a scripted recipe without steps only monitors: it never reports done itself
        self.completes = self.recipe.kind != "scripted" or bool(self.recipe.steps)
        for monitor in self.recipe.monitors:
            self._attach(monitor)
        try:
            steps = sup.expand(self.run, self.recipe)
        except LookupError as err:
            sup.record("recipe-failed", task=self.node, act=self.act, reason=str(err))
            self._finish(FAILED, "failed", str(err))
            return
        for step in steps:
            kind = ATOMIC if step.atomic else "task"
            node = sup.tree.add(kind, step.atomic or step.task or step.name, self.node,
                                state=TODO, step=step.name)
            self.steps[step.name] = StepRun(step, node)
        self._advance()

    def suspend(self, reason: str) -> None:
        """Stop what runs, keep the tree: :meth:`resume` starts the interrupted steps again."""
        if self.over or self.suspended:
            return
        self.suspended = True
        self.sup.tree.set_state(self.node, SUSPENDED, reason)
        for run in self.steps.values():
            if run.state == ONGOING:
                self._interrupt(run, SUSPENDED, reason)
        for run in self.steps.values():
            if run.child is not None and not run.child.ended:
                run.child.suspend(reason)

    def resume(self, reason: str) -> None:
        if self.over or not self.suspended:
            return
        self.suspended = False
        self.sup.tree.set_state(self.node, ONGOING, reason)
        for run in self.steps.values():
            if run.child is not None and not run.child.ended:
                if run.state == SUSPENDED:  # the subtask goes on: so does its step
                    run.state = ONGOING
                    self.sup.tree.set_state(run.node, ONGOING, reason)
                run.child.resume(reason)
            elif run.state == SUSPENDED:
                self.sup.tree.set_state(run.node, TODO, reason)
                run.state = TODO
        self._advance()

    def stop(self, reason: str) -> None:
        """The scheme left the act's state: cancel what runs, drop monitors, cut the tree."""
        if self.over and self.sup.tree.state(self.node) in (DONE, FAILED):
            self._detach()
            return
        self.over = True
        self._detach()
        for run in self.steps.values():
            if run.state == ONGOING or run.state == SUSPENDED:
                self._interrupt(run, CANCELLED, reason)
            if run.child is not None and not run.child.ended:
                run.child.cancel(reason)
        if self.node in self.sup.tree:
            self.sup.tree.cut(self.node)

    # -- steps ---------------------------------------------------------------

    def _ready(self, run: StepRun) -> bool:
        return run.state == TODO and all(self.steps[b].state == DONE for b in run.step.after
                                         if b in self.steps)

    def _advance(self) -> None:
        if self.over or self.suspended:
            return
        for run in self.steps.values():
            if self._ready(run):
                self._launch(run)
        if self.completes and all(run.state == DONE for run in self.steps.values()):
            self._finish(DONE, "done")

    def _launch(self, run: StepRun) -> None:
        sup = self.sup
        run.state = ONGOING
        run.attempts += 1
        sup.tree.set_state(run.node, ONGOING)
        env = self.run.env
        args = {k: t.resolve(env) for k, t in run.step.args.items()}
        agent = run.step.by.resolve(env) if run.step.by is not None else self.run.robot
        if run.step.task is not None:
            self.begun(run)
            if run.step.by is not None:
                args[ROBOT_PARAM] = agent  # the subtask's performer plays its robot role
            run.child = sup.start_task(run.step.task, args, parent=self, step=run)
            return
        run.request = sup.execute(run.step.atomic or "", args, str(agent), run.node, self)

    def begun(self, run: StepRun) -> None:
        """A step starts in the world: the monitors that watch until it starts stop."""
        for subscription in self.until.pop(run.step.name, ()):
            self.sup.facts.unsubscribe(subscription)
            self.subscriptions.remove(subscription)

    def _interrupt(self, run: StepRun, state: str, reason: str) -> None:
        run.state = state
        self.sup.tree.set_state(run.node, state, reason)
        if run.request is not None:
            request, run.request = run.request, None
            self.sup.cancel_request(request, reason)

    def outcome(self, run: StepRun, outcome: Outcome) -> None:
        """An executor's report for one of this act's steps."""
        if run.request is None or outcome.request.id != run.request.id:
            return  # a late report for an interrupted attempt
        run.request = None
        self.step_finished(run, outcome.status, outcome.reason)

    def step_finished(self, run: StepRun, status: str, reason: str = "") -> None:
        """A step ended (its atomic task reported, or its subtask's scheme finished)."""
        if self.over or run.state != ONGOING:
            return
        sup = self.sup
        if status == DONE:
            run.state = DONE
            sup.tree.set_state(run.node, DONE)
            if run.step.emit:
                self.run.deliver_soon(run.step.emit, run.step.emit_data, self)
            self._advance()
            return
        retry = self.recipe.retry if self.recipe else None
        if retry is not None and run.attempts < retry.max_attempts:
            sup.record("retry", task=run.node, step=run.step.name, attempt=run.attempts + 1,
                       max_attempts=retry.max_attempts, reason=reason)
            run.state = TODO
            run.child = None
            sup.tree.set_state(run.node, TODO, f"retry after: {reason}")
            self._advance()
            return
        then = retry.then if retry is not None else "fail"
        if then == "replan" and self.replans < (retry.max_attempts if retry else 1):
            self.replan(f"{run.step.name} failed: {reason}")
            return
        if then == "skip":
            run.state = DONE
            sup.tree.set_state(run.node, DONE, f"skipped after: {reason}")
            self._advance()
            return
        run.state = FAILED
        sup.tree.set_state(run.node, FAILED, reason)
        if then == "emit" and retry is not None and retry.emit:
            self._finish(FAILED, retry.emit, reason)
        else:
            self._finish(FAILED, "failed", reason)

    def replan(self, reason: str) -> None:
        """Drop the steps not done yet and ask the recipe for new ones from the current facts
        (a planner-backed recipe plans again: "the bottle is not reachable" is a fact now)."""
        self.replans += 1
        sup = self.sup
        for name, run in list(self.steps.items()):
            if run.state == DONE:
                continue
            if run.state == ONGOING:
                self._interrupt(run, CANCELLED, reason)
            if run.child is not None and not run.child.ended:
                run.child.cancel(reason)
            if run.node in sup.tree:
                sup.tree.cut(run.node)
            del self.steps[name]
        sup.record("replan", task=self.node, reason=reason, attempt=self.replans)
        assert self.recipe is not None
        try:
            steps = sup.expand(self.run, self.recipe)
        except LookupError as err:
            self._finish(FAILED, "failed", f"replanning failed: {err}")
            return
        done = {name for name, run in self.steps.items() if run.state == DONE}
        for step in steps:
            name = step.name if step.name not in self.steps else f"{step.name}@{self.replans}"
            step = replace(step, name=name, after=tuple(a for a in step.after if a not in done))
            kind = ATOMIC if step.atomic else "task"
            node = sup.tree.add(kind, step.atomic or step.task or step.name, self.node,
                                state=TODO, step=step.name)
            self.steps[step.name] = StepRun(step, node)
        self._advance()

    def _finish(self, state: str, event: str, reason: str = "") -> None:
        if self.over:
            return
        self.over = True
        self._detach()
        self.sup.tree.set_state(self.node, state, reason or None)
        self.run.deliver_soon(event, {"reason": reason} if reason else None, self)

    # -- monitors ------------------------------------------------------------

    def _attach(self, monitor: Monitor) -> None:
        env = self.run.env
        s, p, o = monitor.pattern.resolve(env)
        perspective = monitor.perspective.resolve(env) if monitor.perspective else None

        def react(event: Any) -> None:
            if not self.over:
                fact = (event.subject, event.predicate, event.object)
                self.sup.record("monitor", task=self.node, monitor=monitor.name,
                                emit=monitor.emit, fact=list(fact))
                if monitor.emit in ("done", "failed") and not self.steps:
                    # a watching act ends by what it watched for: done or failed, not cut
                    self._finish(DONE if monitor.emit == "done" else FAILED, monitor.emit,
                                 f"{' '.join(map(str, fact))} {event.kind}")
                else:
                    self.run.deliver_soon(monitor.emit, {"fact": fact}, self)

        subscription = self.sup.facts.subscribe(
            react, subject=s, predicate=p, object=o, perspective=perspective,
            kind=monitor.change)
        self.subscriptions.append(subscription)
        if monitor.until is not None:
            self.until.setdefault(monitor.until, []).append(subscription)

    def _detach(self) -> None:
        for subscription in self.subscriptions:
            self.sup.facts.unsubscribe(subscription)
        self.subscriptions.clear()
