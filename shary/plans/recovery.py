"""What a stuck task leads to: NOT_STARTING and NOT_FINISHED always lead somewhere.

In JAHRVIS (Table III, Section VI-C) a task's state is there to be acted on:
a human's task that does not start, or that started and does not end, is a
question the robot must answer, not a state to sit in.  :class:`Recovery`
answers it with a ladder; each rung is tried once per task, the next one when
the task has not moved for ``patience`` seconds after the last:

1. **look**: what the robot cannot see it goes and looks at.  The effect the
   task waits for (``isOn(cube, stick)``) is perceived through the head
   camera only; if the task's objects are not in view (no ``sees`` fact of
   the robot for them: perception's explicit *unknown*), the head turns to
   them (a ``look-at`` node of the task, held by :mod:`shary.kernel.arbiter` for
   ``patience`` seconds).  When everything is in view, this rung is passed;
2. **ask** the partner: a task not started is requested ("Please pick the
   stick."), a task not finished is asked about ("Are you going to place the
   stick?"), once they attend (an ``inform`` task); a partner who never
   attends is not there, and the plan fails;
3. **take over**, if the plan allows it: the robot has a model of the action,
   can reach its objects (``isReachableBy``) and nobody holds them (or the
   robot does, for a place); it does the task itself;
4. **replan** from what is now true (:meth:`PlanFollower.replan`), which ends
   the plan, failed with its reason said aloud, once the replans are spent.

A robot's own task that becomes NOT_FINISHED (its executor never reported)
is stopped, fails, and the plan is replanned (:meth:`Recovery.robot_stuck`).

Every rung is a ``plan-recover`` row of the context log (the task, its agent,
the rung, why).  :class:`Watchdog` is the last resort: when nothing in the
plan has progressed for ``idle`` seconds (no task state changed, nothing
recognized, no rung taken), it writes a ``watchdog`` row with what is due
and acts (the next rung for a human's task, a failure for a robot action that
never ends, a replan otherwise), so that a run never reaches its timeout with
the plan silently ``started``.
"""

from __future__ import annotations

from typing import Any

from shary.kernel.tasktree import ATOMIC
from shary.plans.tasks import ACTION

__all__ = ["RUNGS", "Recovery", "Watchdog"]

RUNGS = ("look", "ask", "take-over", "replan")


class Recovery:
    """The ladder of one plan follower (see the module's documentation)."""

    def __init__(self, follower: Any, patience: float = 8.0):
        self.follower = follower
        self.sup = follower.sup
        self.patience = patience
        self.rungs: dict[tuple[int, int, bool], int] = {}
        """(plan generation, task, started) -> the next rung to try."""
        self.looks: dict[int, list[str]] = {}
        """Task -> the look nodes it asked for (held until they end)."""

    def stuck(self, task: int, why: str) -> None:
        """``task`` (a human's, due) does not move: take its next rung."""
        f = self.follower
        if f.finished or task not in f.current or task in f.executed:
            return
        key = self._key(task)
        rung = self.rungs.get(key, 0)
        while rung < len(RUNGS):
            self.rungs[key] = rung + 1
            action = getattr(self, "_" + RUNGS[rung].replace("-", "_"))
            if action(task, why):
                break
            rung += 1
        f.progressed()
        if rung < len(RUNGS) - 1 and RUNGS[rung] != "ask" and not f.finished:
            self.wait(task, RUNGS[rung])

    def wait(self, task: int, after: str) -> None:
        """Give the task ``patience`` seconds to move after a rung, then take the next."""
        f = self.follower
        self.sup.loop.call_later(self.patience, self._check, task, f.generation,
                                 f.states.state(task, self.sup.robot), after)

    def _key(self, task: int) -> tuple[int, int, bool]:
        """The ladder is climbed once to get a task started, once to get it finished."""
        f = self.follower
        started = f.states.state(task, self.sup.robot) in ("ONGOING", "NOT_FINISHED")
        return (f.generation, task, started)

    def _check(self, task: int, generation: int, state: str, after: str) -> None:
        f = self.follower
        if generation == f.generation and f.states.state(task, self.sup.robot) == state:
            self.stuck(task, f"nothing moved within {self.patience:g}s after the {after}")

    def _record(self, task: int, rung: str, why: str, **extra: Any) -> None:
        f = self.follower
        self.sup.record("plan-recover", task=f.states.fact_name(task),
                        agent=str(f.agents.get(task, f.plan.primitive[task].agent)),
                        rung=rung, why=why, name=f.plan.primitive[task].label(), **extra)

    def robot_stuck(self, task: int, why: str) -> None:
        """The robot's own action does not end (its executor hangs): it is stopped and
        fails, and the plan is replanned as for any failed action."""
        f = self.follower
        if f.finished or f.robot.busy != task:
            return
        f.robot.cancel(f.node(task))
        f.robot.busy = None
        self._record(task, "replan", why)
        f.states.send(task, "failed", reason=why)
        f.replan(f"{f.plan.primitive[task].label()} never ended ({why})", task=task)

    # -- the rungs: each returns whether it acted ------------------------------------

    def unseen(self, task: int) -> list[str]:
        """The task's objects the robot does not see now (perception's *unknown*)."""
        robot, facts = self.sup.robot, self.sup.facts
        holders = [robot, *self.follower.humans]  # what is held is tracked with the hand
        return [str(o) for o in self.follower.objects_of(task)
                if not facts.holds(robot, "sees", o) and str(o) not in holders
                and not any(facts.holds(h, "isHolding", o) for h in holders)]

    def _look(self, task: int, why: str) -> bool:
        unseen = self.unseen(task)
        if not unseen:
            return False
        self._record(task, "look", why, objects=unseen)
        self.look(task, unseen[-1], self.patience)
        return True

    def look(self, task: int, target: str, seconds: float) -> None:
        """Turn the head to ``target`` for ``seconds`` (a node of the task, held meanwhile)."""
        from shary.kernel.arbiter import TASK

        f = self.follower
        node = self.sup.tree.add(ATOMIC, f"look at {target}", f.node(task), state="ongoing",
                                 agent=self.sup.robot)
        self.looks.setdefault(task, []).append(node)
        f.robot.watch(target, node, priority=TASK)
        self.sup.loop.call_later(seconds, self.sup.tree.set_state, node, "done")

    def over(self, task: int) -> None:
        """``task`` is done: the looks it asked for end (the head is free for what follows)."""
        for node in self.looks.pop(task, ()):
            if node in self.sup.tree:
                self.sup.tree.set_state(node, "done")

    def _ask(self, task: int, why: str) -> bool:
        f = self.follower
        started = f.states.state(task, self.sup.robot) in ("ONGOING", "NOT_FINISHED")
        self._record(task, "ask", why)
        f.hpm.ask(task, "ask-going" if started else "request")
        return True

    def _take_over(self, task: int, why: str) -> bool:
        f = self.follower
        spec = f.plan.primitive[task]
        robot = self.sup.robot
        model = f.robot.model_for(spec.name, f.robot.models.robot)
        if spec.kind != ACTION or model is None or model.executor is None or \
                f.robot.busy is not None:
            return False
        objects = [str(o) for o in f.objects_of(task)]
        held = self.sup.facts.objects(robot, "isHolding")
        first = objects[0] if objects else None
        if first is None:
            return False
        if str(first) not in map(str, held):
            if held or not self.sup.facts.holds(first, "isReachableBy", robot) or any(
                    self.sup.facts.holds(h, "isHolding", first) for h in f.humans):
                return False
        self._record(task, "take-over", why)
        generation = f.generation

        def over(status: str, reason: str) -> None:
            if generation != f.generation or f.finished or task in f.executed:
                return
            if status == "done":
                f.taken_over(task)
            else:
                self.stuck(task, f"the robot could not do it: {reason}")

        f.robot.perform(spec, f.node(task), tuple(f.objects_of(task)), over)
        return True

    def _replan(self, task: int, why: str) -> bool:
        f = self.follower
        self._record(task, "replan", why)
        f.replan(f"{f.plan.primitive[task].label()} did not get done ({why})", task=task)
        return True


class Watchdog:
    """Acts when nothing in the plan has progressed for ``idle`` seconds (see the module)."""

    def __init__(self, follower: Any, idle: float = 45.0):
        self.follower = follower
        self.sup = follower.sup
        self.idle = idle
        self._timer: Any = None
        self._mark = -1

    def start(self) -> None:
        self._arm()

    def stop(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _arm(self) -> None:
        self._mark = self.follower.progress_count
        self._timer = self.sup.loop.call_later(self.idle, self._check)

    def _check(self) -> None:
        self._timer = None
        f = self.follower
        if f.finished:
            return
        if f.progress_count != self._mark:
            self._arm()
            return
        due = [t for t in f.current if t not in f.executed]
        labels = [f.plan.primitive[t].label() for t in due]
        humans = [t for t in due if f.agents.get(t) in f.humans]
        if humans:
            action = "recover"
        elif f.robot.busy is not None:
            action = "robot action failed"
        elif due:
            action = "replan"
        else:
            action = "end"
        self.sup.record("watchdog", agent=self.sup.robot, idle=self.idle, due=labels,
                        action=action, why=f"nothing in the plan progressed for {self.idle:g}s")
        why = f"nothing progressed for {self.idle:g}s"
        if action == "recover":
            for task in humans:
                f.recovery.stuck(task, why)
        elif action == "robot action failed":
            f.recovery.robot_stuck(f.robot.busy, why)
        elif action == "replan":
            f.replan(f"{', '.join(labels)}: {why}", task=due[0])
        else:
            f.end_failed(why)
        if not f.finished:
            self._arm()
