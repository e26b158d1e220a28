"""A shared plan under way: which tasks are due, who does them, and what follows.

:class:`PlanFollower` follows one plan (:class:`~shary.plans.tasks.SharedPlan`)
on the engine's loop.  The tasks due now are the next of the last one done: a
robot's task is given to the :class:`~shary.plans.robot.RobotPlanManager`, a
human's to the :class:`~shary.plans.human.HumanPlanManager` (which watches the
recognized actions), the options of a human decision wait for the human's
action to say which branch is taken.  The planner's turn markers (a human's
``WAIT``, an ``IDLE`` agenda) are passed; ``DONE`` ends the plan.

A robot action that fails after its attempts, or a human action the plan
does not expect and that is not useful to it, makes the plan fail at its
level (Listing 1's ``.fail_goal``): the remaining tasks are SUSPENDED, the
``replan`` port is asked for a new plan from what is now true, the old tasks
become UNPLANNED and the new plan is followed.  Without a ``replan`` port, or
when it finds no plan, the shared plan fails.

The task tree shows the plan: a node for the plan, one per abstract task and
one per primitive task once it is due, each with its state in the robot's
view; the context log has every state of every view (``plan-task`` rows).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from shary.kernel.tasktree import ATOMIC, TASK
from shary.plans.beliefs import HumanBeliefs
from shary.plans.human import HumanPlanManager
from shary.plans.recovery import Recovery, Watchdog
from shary.plans.replan import remaining_agendas
from shary.plans.robot import RobotPlanManager
from shary.plans.states import TaskStates
from shary.plans.tasks import ACTION, DONE, SharedPlan, is_open

__all__ = ["PlanFollower"]

_TREE_STATE = {"PLANNED": "planned", "TODO": "todo", "ONGOING": "ongoing",
               "EXECUTED": "done", "SUSPENDED": "suspended", "UNPLANNED": "cancelled",
               "NOT_STARTING": "todo", "NOT_FINISHED": "failed", "NOT_SEEN": "done"}


class PlanFollower:
    """Follows a shared plan with the robot and the humans in it (see the module).

    ``replan(agendas)`` (each agent's tasks still to do, :mod:`shary.plans.replan`)
    returns a new :class:`SharedPlan` from what is now true,
    or None; ``done(outcome)`` is told ``"achieved"`` or ``"failed"`` once.
    """

    def __init__(self, sup: Any, plan: SharedPlan, *, humans: list[str] | None = None,
                 replan: Callable[[dict[str, list[str]]], SharedPlan | None] | None = None,
                 done: Callable[[str], Any] | None = None, decision_wait: float = 6.0,
                 max_replans: int = 3, name: str = "shared-plan", watchdog: float = 45.0):
        if sup.robot_actions is None:
            raise ValueError("the supervisor has no action models: call recognize() first")
        self.sup = sup
        self.name = name
        self.humans = humans if humans is not None else \
            [a for a, kind in plan.agents.items() if kind == "human"]
        self.replanner = replan
        self.on_done = done
        self.max_replans = max_replans
        self.replans = 0
        self.finished: str | None = None
        self.robot = RobotPlanManager(sup, sup.robot_actions.models)
        self.hpm = HumanPlanManager(self, decision_wait)
        self.progress_count = 0
        """Grows with every sign of progress (a task state, a recognition, a rung)."""
        self.recovery = Recovery(self)
        self.watchdog = Watchdog(self, idle=watchdog)
        self.watchers: list[Callable[[str, int], Any]] = []
        """Told ``(event, task)``: a task ``due``, ``started`` by the robot, ``done``
        (what a simulated partner follows)."""
        self.root = sup.tree.add(TASK, f"{name}: {plan.problem}")
        self.generation = 0
        self.beliefs = HumanBeliefs(self)
        """What each human is estimated to believe, across replans."""
        self._load(plan)

    def _load(self, plan: SharedPlan) -> None:
        self.generation += 1
        self.plan = plan
        self.current: list[int] = []
        self.executed: set[int] = set()
        self.params: dict[int, tuple[Any, ...]] = {}
        self.agents: dict[int, Any] = {}
        self.bound: dict[tuple, Any] = {}
        self._nodes: dict[int, str] = {}
        self._abstract_nodes: dict[int, str] = {}
        names = {t.id: t.label() for t in plan.primitive.values()}
        prefix = f"{self.name}-{self.generation}"
        self.sup.record("plan-loaded", task=self.root, agent=self.sup.robot,
                        **_outline(plan, prefix, [self.sup.robot, *self.humans]))
        self.states = TaskStates(self.sup, [self.sup.robot, *self.humans], names,
                                 prefix=prefix,
                                 changed=self._changed)

    # -- the follower's life ----------------------------------------------------------

    def start(self) -> None:
        self.sup.record("shared-plan", task=self.root, agent=self.sup.robot, state="started",
                        problem=self.plan.problem, tasks=len(self.plan.primitive),
                        decisions=len(self.plan.decisions))
        self.sup.tree.set_state(self.root, "ongoing")
        self.hpm.listen()
        self.watchdog.start()
        self._advance(None)

    def progressed(self) -> None:
        """Something moved (what the watchdog waits for)."""
        self.progress_count += 1

    def end_failed(self, why: str) -> None:
        """The plan cannot go on (the watchdog's last word)."""
        self._finish("failed", why)

    def _finish(self, outcome: str, reason: str = "", task: int | None = None) -> None:
        if self.finished is not None:
            return
        self.finished = outcome
        self.watchdog.stop()
        self.hpm.stop()
        if outcome == "failed":
            self._say_why(task)
        self._close_abstract("done" if outcome == "achieved" else "failed", reason)
        for human in self.humans:  # the end of the task: what they missed, they need now
            self.beliefs.needs(human)
        self.sup.tree.set_state(self.root, "done" if outcome == "achieved" else "failed",
                                reason or None)
        self.sup.record("shared-plan", task=self.root, agent=self.sup.robot, state=outcome,
                        reason=reason or None, replans=self.replans)
        if self.on_done is not None:
            self.on_done(outcome)

    def _say_why(self, task: int | None) -> None:
        """A plan that fails says so to its partners, with the task it failed on, whoever
        listens: the verdict is reached, and a partner on the phone would otherwise never
        hear why (an announcement, not an inform that waits for a glance)."""
        from shary.dialogue.attention import announce

        for human in self.humans:
            text = "I cannot go on with our task, so I stop here."
            if task is not None:
                spec = self.plan.primitive[task]
                agent = str(self.agents.get(task, spec.agent))
                about = f"{spec.name}({', '.join([agent, *map(str, self.objects_of(task))])})"
                try:
                    failed = self.sup.speech.say({"act": "inform-failed", "about": about,
                                                  "to": human}, self.sup.robot)
                    text = f"{failed} I cannot go on with our task, so I stop here."
                except (ValueError, KeyError):
                    pass
            self.sup.record("plan-end", agent=human, text=text)
            announce(self.sup, human, text)

    # -- what is due -----------------------------------------------------------------

    def _advance(self, after: int | None) -> None:
        """Make the tasks that follow ``after`` due (passing what is already done)."""
        while True:
            following = self.plan.next(after)
            if len(following) == 1 and following[0].id in self.executed:
                after = following[0].id
                continue
            break
        self.current = [t.id for t in following]
        if not following:
            self._finish("achieved")
            return
        for task in following:
            self.states.send(task.id, "ready")
            self.node(task.id)
            self._tell("due", task.id)
        if len(following) > 1:  # a human decision: their action says which branch
            for task in following:
                self._resolve(task.id)
            self.hpm.due(following)
            self.robot.watch(self._target(following[0].id), self.node(following[0].id))
            return
        task = following[0]
        if task.kind == DONE:
            self._executed(task.id, seen=True)
            self._finish("achieved")
            return
        if task.kind != ACTION:  # a turn marker: nothing to do
            self._executed(task.id, seen=True)
            self.sup.loop.call_soon(self._advance, task.id)
            return
        agent, _ = self._resolve(task.id)
        if agent == self.sup.robot:
            self._robot_when_free(task.id, self.generation)
        else:
            self.hpm.due([task])
            self.beliefs.needs(agent)
            self.robot.watch(self._target(task.id), self.node(task.id))

    def _resolve(self, task: int) -> tuple[Any, tuple[Any, ...]]:
        if task not in self.params:
            busy = {self.sup.robot} if self.robot.busy is not None else set()
            agent, params = self.robot.resolve(self.plan.primitive[task], self.bound, busy)
            self.agents[task], self.params[task] = agent, params
            if is_open(self.plan.primitive[task].agent) or any(
                    is_open(p) for p in self.plan.primitive[task].params):
                self.sup.record("plan-resolve", task=self.states.fact_name(task),
                                agent=agent, params=[str(p) for p in params])
        return self.agents[task], self.params[task]

    def objects_of(self, task: int) -> tuple[Any, ...]:
        """The task's parameters after its agent, open values resolved if they are."""
        agent, params = self._resolve(task)
        return params[1:] if params and params[0] == agent else params

    def _target(self, task: int) -> Any:
        objects = self.objects_of(task)
        return objects[-1] if objects else None

    def ahead(self) -> list[int]:
        """The tasks not done yet from the due ones on (every branch of the plan ahead)."""
        out: list[int] = []
        for task in self.current:
            out.extend(t for t in self.plan.below(task) if t not in self.executed)
        return out

    # -- the robot's tasks -------------------------------------------------------------

    def _tell(self, event: str, task: int) -> None:
        for watcher in self.watchers:
            watcher(event, task)

    def _robot_when_free(self, task: int, generation: int) -> None:
        """Start the robot's task unless a human holds one of its objects: then wait
        (they may be doing it: their action, recognized, will say)."""
        if generation != self.generation or self.finished or task in self.executed:
            return
        held = [h for h in self.humans for o in self.objects_of(task)
                if self.sup.facts.holds(h, "isHolding", o)]
        if not held:
            self._robot_does(task)
            return
        if self.states.state(task, self.sup.robot) == "TODO":
            self.sup.record("plan-wait", task=self.states.fact_name(task), agent=self.sup.robot,
                            why=f"{held[0]} holds what it is about")
        self.sup.loop.call_later(0.5, self._robot_when_free, task, generation)

    def _robot_does(self, task: int) -> None:
        generation = self.generation
        self._tell("started", task)
        self.states.send(task, "start", [self.sup.robot, *[
            h for h in self.humans if self.beliefs.watching(h, task)]])

        def over(status: str, reason: str) -> None:
            if generation != self.generation or self.finished or task in self.executed:
                return
            if status == "done":
                self._executed(task, seen=False)
                self._advance(task)
            else:  # failed, or cancelled by nobody in the plan: the plan decides
                self.states.send(task, "failed", reason=reason)
                self.replan(f"{self.plan.primitive[task].label()} failed: {reason}", task)

        self.robot.perform(self.plan.primitive[task], self.node(task), self.objects_of(task),
                           over)

    def _executed(self, task: int, *, seen: bool) -> None:
        self.executed.add(task)
        self.recovery.over(task)
        self._tell("done", task)
        self.states.send(task, "achieved", [self.sup.robot])
        if seen:
            self.states.send(task, "achieved", self.humans)
        else:
            self.beliefs.robot_did(task)

    # -- the humans' tasks (called by the human plan manager) ------------------------

    def _choose(self, task: int) -> None:
        """A decision's option taken: the other branches leave the plan."""
        if len(self.current) < 2 or task not in self.current:
            return
        decision = self.plan.primitive[task].decision
        self.sup.record("plan-decision", task=self.states.fact_name(task), decision=decision,
                        agent=self.agents.get(task), chosen=self.plan.primitive[task].label())
        for other in self.current:
            if other != task:
                for dropped in self.plan.below(other):
                    self.states.send(dropped, "drop", reason=f"{decision}: another branch")
        self.current = [task]

    def human_started(self, task: int) -> None:
        self._choose(task)
        self.states.send(task, "start")

    def human_did(self, task: int) -> None:
        self._choose(task)
        self._executed(task, seen=True)
        self._advance(task)

    def done_ahead(self, task: int, agent: str) -> None:
        """Someone did ``task`` before its turn: it and the tasks that only prepared it
        (its objects, on the way to it) are done; the robot does not do them again."""
        path = self._way_to(task)
        objects = set(map(str, self.objects_of(task)))
        for step in path:
            if step == task or (self.plan.primitive[step].kind == ACTION and objects
                                & set(map(str, self.objects_of(step)))):
                if self.robot.busy == step:
                    self.robot.cancel(self.node(step))
                    self.robot.busy = None
                self._executed(step, seen=True)
        if self.current and self.current[0] in self.executed and len(self.current) == 1:
            self._advance(self.current[0])

    def _way_to(self, task: int) -> list[int]:
        for start in self.current:
            path = list(self.plan.path(start))
            if task in path:
                return path[:path.index(task) + 1]
        return [task]

    # -- failures ------------------------------------------------------------------------

    def taken_over(self, task: int) -> None:
        """The robot did a human's task (a rung of the recovery): done, on to the next."""
        self._executed(task, seen=False)
        self._advance(task)

    def replan(self, reason: str, task: int | None = None) -> None:
        """The plan failed at its level: suspend, ask for a new plan, follow it."""
        if self.finished:
            return
        old = self.plan
        pending = [t for t in old.primitive if t not in self.executed]
        for waiting in pending:
            self.states.send(waiting, "suspend", reason=reason)
        if self.robot.busy is not None:
            self.robot.cancel(self.node(self.robot.busy))
            self.robot.busy = None
        self.sup.record("shared-plan", task=self.root, agent=self.sup.robot, state="replan",
                        reason=reason)
        new = None
        if self.replanner is not None and self.replans < self.max_replans:
            self.replans += 1
            new = self.replanner(remaining_agendas(old, self.current, self.executed,
                                                   self.agents))
        for waiting in pending:
            self.states.send(waiting, "drop", reason="replanned" if new else reason)
        if new is None:
            self._finish("failed", reason, task)
            return
        self.hpm.stop()
        self.states.stop()
        for looked in list(self.recovery.looks):
            self.recovery.over(looked)
        self._close_abstract("cancelled", "replanned")
        self._load(new)
        self.hpm.listen()
        self.sup.loop.call_soon(self._advance, None)

    # -- the task tree ---------------------------------------------------------------------

    def node(self, task: int) -> str:
        """The task's node in the task tree (under its abstract tasks), made when due."""
        found = self._nodes.get(task)
        if found is None:
            parent = self.root
            for abstract in reversed(self.plan.ancestors(task)):
                if abstract not in self._abstract_nodes:
                    spec = self.plan.abstract[abstract]
                    self._abstract_nodes[abstract] = self.sup.tree.add(
                        TASK, f"{spec.name}({', '.join(map(str, spec.params))})", parent,
                        state="ongoing")
                parent = self._abstract_nodes[abstract]
            spec = self.plan.primitive[task]
            found = self._nodes[task] = self.sup.tree.add(ATOMIC, spec.label(), parent,
                                                          agent=str(spec.agent))
        return found

    def _close_abstract(self, state: str, reason: str) -> None:
        """The plan's abstract tasks end with it (done, failed, or replaced)."""
        for node in self._abstract_nodes.values():
            self.sup.tree.set_state(node, state, reason or None)

    def _changed(self, task: int, view: str, state: str) -> None:
        self.progressed()
        if view == self.sup.robot and task in self._nodes:
            self.sup.tree.set_state(self._nodes[task], _TREE_STATE[state], state)
        if view == self.sup.robot and state in ("NOT_STARTING", "NOT_FINISHED") and \
                self.agents.get(task) in self.humans:
            self.sup.loop.call_soon(self.recovery.stuck, task, f"{state} in the plan")
        elif view == self.sup.robot and state == "NOT_FINISHED" and self.robot.busy == task:
            self.sup.loop.call_soon(self.recovery.robot_stuck, task, f"{state} in the plan")

    def partner_absent(self, task: int, human: str) -> None:
        """Asked for their task, ``human`` never attended: the shared plan fails."""
        self._finish("failed", f"{human} is not there to do "
                               f"{self.plan.primitive[task].label()}", task)


def _outline(plan: SharedPlan, prefix: str, views: list[str]) -> dict[str, Any]:
    """The plan as the context log keeps it (a ``plan-loaded`` row), so that a reader of
    the log (the console, its replay) can show the whole plan before any task changes:
    each task with its agent and what it follows, and each human decision's options.
    Task ids are those of the ``plan-task`` rows (``PREFIX-ID``)."""
    def name(task: int | None) -> str | None:
        return None if task is None else f"{prefix}-{task}"

    def agent(value: Any) -> str:
        return "|".join(map(str, value.get("any-of", ()))) if is_open(value) else str(value)

    return {"problem": plan.problem, "prefix": prefix, "views": views,
            "tasks": [{"id": name(t.id), "label": t.label(), "agent": agent(t.agent),
                       "kind": t.kind, "name": t.name,
                       "objects": [None if is_open(v) else str(v) for v in t.objects()],
                       "after": [name(p) for p in t.preds],
                       "decision": t.decision} for t in plan.primitive.values()],
            "decisions": [{"id": d.id, "agent": d.agent, "after": name(d.after),
                           "options": [name(o) for o in d.options]}
                          for d in plan.decisions.values()]}
