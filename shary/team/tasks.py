"""The Task Manager: the goal's high-level tasks, delegated one per agent at a time.

HRI/OS (Section 3.2): "decomposing the overall goal of the system into
high-level tasks, which are assigned to humans or robots for execution.  Only
a single task is assigned to a given agent at a time ... the TM does not know
anything about low-level task details."  Fig. 2's constraints ("both panels
mounted before the seam is welded, then inspected") are the team file's
``after`` lists: a task is ready when every task it comes after is done, and
ready tasks with no constraint between them run in parallel.

Each ready task is offered (an :class:`~shary.transport.messages.Assignment`) to
the best free agent the Resource Manager finds; an agent that refuses, or
does not reply within the task's ``reply-within``, is passed over for the
next.  A task that fails is tried again (``attempts``); a task with
``respawn`` (an inspection) that fails makes the task it names (the weld) and
everything between them pending again, so the weld is redone and then
inspected again.  Every agent's progress comes back as ``Progress``
messages, all logged.

A **watchdog** keeps the goal from stalling silently: when nothing has
progressed for ``watchdog`` seconds (the team file's ``goal: watchdog:``, five
minutes unless it says otherwise; no task made ready, offered, accepted,
done or failed), it writes a ``watchdog`` row (what is running, what is
ready, what it does) and acts: a running task whose holder has said nothing
since is withdrawn (retried, respawned or given up as the team file says);
a ready task that no agent could ever take (none capable, or all lost) ends
the goal failed; so does a goal with nothing running, offered or ready.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from shary.statechart.clock import Timer
from shary.team.resources import TASK, Need
from shary.team.spec import TaskSpec
from shary.transport.messages import Assignment, Message, Progress

if TYPE_CHECKING:
    from shary.team.agents import Agent
    from shary.team.team import Team

PENDING, READY, OFFERED, RUNNING, DONE, FAILED = (
    "pending", "ready", "offered", "running", "done", "failed")
LOST = "(lost)"
"""What a lost agent holds instead of a task, so that nothing is offered to it."""


@dataclass(eq=False)
class TeamTask:
    """One high-level task as the Task Manager follows it."""

    spec: TaskSpec
    state: str = PENDING
    attempts: int = 0
    """Attempts that ended (failed, or nobody accepted)."""
    agent: str | None = None
    refused: set[str] = field(default_factory=set)
    """Agents that refused (or ignored) the current attempt."""
    timer: Timer | None = None
    respawns: int = 0
    done_by: list[str] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.spec.name


WITHDRAWN = "withdrawn"
"""The status of the Progress that tells a holder its team task was taken back: a robot
cancels the task's goal, a person's proxy drops the assignment; either then says it is
over, and is offered work again."""


class TaskManager:
    """Runs the goal (see the module's docstring)."""

    address = "tasks"

    def __init__(self, team: Team, tasks: dict[str, TaskSpec], watchdog: float):
        self.team = team
        self.watchdog = watchdog
        """Seconds without progress after which the watchdog acts (see the module)."""
        self.progress = 0
        self._progress_at = 0.0
        """When ``progress`` last grew: the watchdog acts ``watchdog`` seconds after it."""
        self._watch_timer: Timer | None = None
        self.tasks = {name: TeamTask(spec) for name, spec in tasks.items()}
        self._after: dict[str, list[str]] = {name: [] for name in tasks}
        for spec in tasks.values():
            for before in spec.after:
                self._after[before].append(spec.name)
        self.outcome: str | None = None
        self.listeners: list[Callable[[str], Any]] = []
        """Told when the goal is over ("done" or "failed")."""
        self.delegations = 0
        self._ready: list[TeamTask] = []
        self.started = False
        """Whether :meth:`start` ran (a goal starts once)."""
        team.port.subscribe(self.address, self.handle)

    def start(self) -> None:
        """Make the tasks without constraints ready and delegate them (once)."""
        if self.started:
            return
        self.started = True
        self.team.record("goal", tasks=len(self.tasks),
                         constraints=sum(len(t.spec.after) for t in self.tasks.values()))
        for task in self.tasks.values():
            self._maybe_ready(task)
        self.team.loop.call_soon(self.dispatch)
        self._watch()

    # -- the watchdog ----------------------------------------------------------------

    def _progressed(self) -> None:
        self.progress += 1
        self._progress_at = self.team.loop.now()

    def _watch(self) -> None:
        left = self._progress_at + self.watchdog - self.team.loop.now()
        self._watch_timer = self.team.loop.call_later(max(left, 0.0), self._idle)

    def _idle(self) -> None:
        self._watch_timer = None
        if self.outcome is not None:
            return
        if self.team.loop.now() < self._progress_at + self.watchdog - 1e-9:
            self._watch()  # it progressed meanwhile: `watchdog` seconds from then
            return
        running = [t for t in self.tasks.values() if t.state == RUNNING]
        ready = [t for t in self.tasks.values() if t.state in (READY, OFFERED)]
        hopeless = [t for t in ready if t.state == READY and not any(
            self.team.agents[a.name].current != LOST for a in self._capable(t))]
        why = f"nothing progressed for {self.watchdog:g}s"
        action = ("withdraw" if running else "end" if hopeless or not ready else "wait")
        self.team.record("watchdog", idle=self.watchdog, action=action, why=why,
                         running=[t.name for t in running] or None,
                         ready=[t.name for t in ready] or None)
        if action == "withdraw":
            for task in running:
                self.withdraw(task.name, f"{task.agent} said nothing of it: {why}")
        elif action == "end":
            reason = (f"no agent can do {', '.join(t.name for t in hopeless)}" if hopeless
                      else "nothing is running, offered or ready")
            self._over("failed", f"{reason} ({why})")
        if self.outcome is None:
            self._progress_at = self.team.loop.now()  # the next look, `watchdog` from now
            self._watch()

    def _maybe_ready(self, task: TeamTask) -> None:
        if task.state == PENDING and all(self.tasks[b].state == DONE for b in task.spec.after):
            task.state = READY
            self._progressed()
            task.refused.clear()
            self._ready.append(task)
            self.team.record("task-ready", task=task.name, skill=task.spec.skill)

    # -- delegation ----------------------------------------------------------------

    def dispatch(self) -> None:
        """Offer every ready task to the best free agent (one task per agent)."""
        if self.outcome is not None:
            return
        free: dict[str, list[Agent]] = {}
        for agent in self.team.agents.values():
            if agent.current is None:
                for skill in agent.skills:
                    free.setdefault(skill, []).append(agent)
        waiting: list[TeamTask] = []
        ready, self._ready = self._ready, []
        for task in ready:
            if task.state != READY:
                continue
            candidates = [a for a in free.get(task.spec.skill, ()) if a.current is None
                          and (not task.spec.by or a.name in task.spec.by)
                          and a.resources.issuperset(task.spec.needs)]
            if not candidates:
                waiting.append(task)  # all busy: wait for one to be free
            elif all(a.name in task.refused for a in candidates):
                if all(a.name in task.refused or a.current == LOST
                       for a in self._capable(task)):
                    self._nobody(task)  # not waiting for the lost: they may never be back
                else:
                    waiting.append(task)  # a busy one that has not refused may take it
            elif not self.delegate(task, candidates):
                waiting.append(task)  # the free ones cannot take it now (user mode …)
        self._ready = waiting + self._ready  # + those made ready meanwhile

    def delegate(self, task: TeamTask, candidates: list[Agent]) -> bool:
        """Offer ``task`` to the best of ``candidates`` that has not refused it; False if
        none can take it now."""
        team = self.team
        need = Need(TASK, task.spec.skill, task.spec.at, by=task.spec.by,
                    needs=task.spec.needs, subject=task.name)
        agent = team.resources.choose(need, candidates, free=lambda a: (
            a.current is None and a.name not in task.refused))
        if agent is None:
            return False
        self.delegations += 1
        self._progressed()
        task.state = OFFERED
        task.agent = agent.name
        agent.current = task.name
        agent.took(team.loop.now())
        team.port.send(Assignment(self.address, agent.name, id=team.port.new_id("a"),
                                  task=task.name, skill=task.spec.skill, args=task.spec.args,
                                  attempt=task.attempts + 1))
        task.timer = team.loop.call_later(task.spec.reply_within, self._no_reply, task,
                                          agent.name)
        return True

    def _capable(self, task: TeamTask) -> list[Agent]:
        """Every agent that may do ``task``, busy or not."""
        return [a for a in self.team.agents.values() if task.spec.skill in a.skills
                and (not task.spec.by or a.name in task.spec.by)
                and a.resources.issuperset(task.spec.needs)]

    def _nobody(self, task: TeamTask) -> None:
        """Every free capable agent refused this attempt: it counts as a failed one."""
        self.team.record("task-unassigned", task=task.name,
                         refused=sorted(task.refused))
        self._attempt_over(task, "nobody accepted it")
        self.team.loop.call_soon(self.dispatch)

    def _no_reply(self, task: TeamTask, agent: str) -> None:
        if task.state == OFFERED and task.agent == agent:
            self.team.record("assignment-expired", task=task.name, agent=agent,
                             after=task.spec.reply_within)
            self.team.agents[agent].count(TASK, False)
            self._passed_over(task, agent)

    def _passed_over(self, task: TeamTask, agent: str) -> None:
        task.refused.add(agent)
        self._free(agent, task)
        task.state = READY
        task.agent = None
        self._ready.append(task)
        self.team.loop.call_soon(self.dispatch)

    def _free(self, agent: str, task: TeamTask) -> None:
        member = self.team.agents[agent]
        if member.current == task.name:
            member.current = None
        if task.timer is not None:
            task.timer.cancel()
            task.timer = None

    # -- members lost and back (a distributed team: their process died, or came back) ----

    def agent_lost(self, name: str) -> None:
        """``name`` is gone: the task it was offered or ran goes to another agent, and it
        is offered nothing until it is back (not counted as an attempt: it did not fail)."""
        member = self.team.agents[name]
        for task in self.tasks.values():
            if task.agent == name and task.state in (OFFERED, RUNNING):
                self.team.record("agent-lost", task=task.name, agent=name,
                                 state=task.state)
                self._passed_over(task, name)
        member.current = LOST

    def agent_back(self, name: str) -> None:
        """``name`` is back: it may be offered tasks again."""
        member = self.team.agents[name]
        if member.current == LOST:
            member.current = None
            for task in self.tasks.values():
                task.refused.discard(name)  # it was lost, it did not refuse: offer it again
            self.team.loop.call_soon(self.dispatch)

    # -- progress ------------------------------------------------------------------

    def withdraw(self, name: str, reason: str) -> str | None:
        """End the attempt at team task ``name`` here, as failed with ``reason`` (an
        operator's cancel): it is retried,
        respawned or given up as the team file says; the holder is told (a
        :data:`WITHDRAWN` progress) and offered nothing new until it says the task is over
        (a robot's goal cancelled, a person's assignment dropped), wherever it runs.  Why
        not, or None."""
        task = self.tasks.get(name)
        if task is None or task.agent is None or task.state not in (OFFERED, RUNNING):
            return f"team task {name} is not offered or running now"
        holder = task.agent
        if task.timer is not None:
            task.timer.cancel()
            task.timer = None
        self.team.record("task-failed", task=name, agent=holder, reason=reason)
        self.team.port.send(Progress(self.address, holder, task=name, status=WITHDRAWN,
                                     reason=reason))
        self._attempt_over(task, reason)
        self.team.loop.call_soon(self.dispatch)
        return None

    def handle(self, message: Message) -> None:
        if not isinstance(message, Progress):
            return
        self._progressed()
        task = self.tasks.get(message.task)
        if task is None or task.agent != message.sender:
            holder = self.team.agents.get(message.sender)
            if holder is not None and holder.current == message.task and \
                    message.status in ("refused", "done", "failed"):
                holder.current = None  # over with a withdrawn task: free for another
                self.team.loop.call_soon(self.dispatch)
            return  # progress of a withdrawn offer
        status = message.status
        if status == "accepted" and task.state == OFFERED:
            task.state = RUNNING
            if task.timer is not None:
                task.timer.cancel()
                task.timer = None
            self.team.agents[message.sender].count(TASK, True)
            self.team.record("task-running", task=task.name, agent=message.sender)
        elif status == "refused" and task.state == OFFERED:
            self.team.agents[message.sender].count(TASK, False)
            self._passed_over(task, message.sender)
        elif status == "done" and task.state == RUNNING:
            self._free(message.sender, task)
            task.state = DONE
            task.done_by.append(message.sender)
            self.team.record("task-done", task=task.name, agent=message.sender)
            for after in self._after[task.name]:
                self._maybe_ready(self.tasks[after])
            self._check_over()
            self.team.loop.call_soon(self.dispatch)
        elif status == "failed" and task.state == RUNNING:
            self._free(message.sender, task)
            self.team.record("task-failed", task=task.name, agent=message.sender,
                             reason=message.reason or None)
            self._attempt_over(task, message.reason or "failed")
            self.team.loop.call_soon(self.dispatch)

    def _attempt_over(self, task: TeamTask, reason: str) -> None:
        task.attempts += 1
        task.agent = None
        if task.attempts >= task.spec.attempts:
            task.state = FAILED
            self.team.record("task-given-up", task=task.name, attempts=task.attempts,
                             reason=reason)
            self._over("failed")
            return
        if task.spec.respawn is not None:
            self._respawn(task, reason)
            return
        task.state = PENDING
        self.team.record("task-retry", task=task.name, attempt=task.attempts + 1,
                         reason=reason)
        self._maybe_ready(task)

    def _respawn(self, task: TeamTask, reason: str) -> None:
        """Make ``task.spec.respawn`` and every task between it and ``task`` pending."""
        target = task.spec.respawn
        assert target is not None
        again = self._between(target, task.name)
        task.respawns += 1
        self.team.record("respawn", task=target, by=task.name, reason=reason,
                         tasks=sorted(again), attempt=task.attempts + 1)
        for name in again:
            other = self.tasks[name]
            if other.timer is not None:
                other.timer.cancel()
                other.timer = None
            other.state = PENDING
            other.agent = None
        for name in again:
            self._maybe_ready(self.tasks[name])

    def _between(self, first: str, last: str) -> set[str]:
        """``first``, ``last`` and the tasks on a path of constraints from one to the other."""
        return (_reach(first, lambda name: self._after[name])
                & _reach(last, lambda name: self.tasks[name].spec.after))

    def _check_over(self) -> None:
        if all(t.state == DONE for t in self.tasks.values()):
            self._over("done")

    def _over(self, outcome: str, reason: str | None = None) -> None:
        if self.outcome is not None:
            return
        self.outcome = outcome
        if self._watch_timer is not None:
            self._watch_timer.cancel()
            self._watch_timer = None
        self.team.record("goal-over", outcome=outcome, reason=reason,
                         done=sum(t.state == DONE for t in self.tasks.values()),
                         tasks=len(self.tasks))
        for listener in self.listeners:
            listener(outcome)

    def summary(self) -> dict[str, int]:
        """How many tasks are in each state."""
        counts: dict[str, int] = {}
        for task in self.tasks.values():
            counts[task.state] = counts.get(task.state, 0) + 1
        return counts


def _reach(start: str, following: Callable[[str], Iterable[str]]) -> set[str]:
    """``start`` and every task reached from it by ``following`` (a constraint's direction)."""
    seen: set[str] = set()
    todo = [start]
    while todo:
        name = todo.pop()
        if name not in seen:
            seen.add(name)
            todo.extend(following(name))
    return seen
