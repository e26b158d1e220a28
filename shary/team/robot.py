"""Robot agents: a shary supervisor each, with breakpoints, association, control authority.

A :class:`RobotAgent` wraps one :class:`~shary.kernel.supervisor.Supervisor` (its own
schemes, agenda and task tree, on the team's loop and log).  A team task
becomes a goal on its agenda.  Help requests are served only at a
**breakpoint** of its current task: the moment one atomic task is over and
the next would start (:class:`_Gate`); the robot then **associates** with the
requester (an agenda hold: its own goal stays suspended) until released
(HRI/OS Fig. 7).  **Control authority**: a human may take control (user mode),
send the robot atomic tasks through its executor port, and hand back.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from shary.kernel.executors import (
    Executor,
    ExecutorRegistry,
    Outcome,
    Reporter,
    Request,
    record_outcome,
)
from shary.team.agents import (
    ASSOCIATED,
    ASSOCIATED_PRIORITY,
    CONTROL_PRIORITY,
    HAND_BACK,
    IDLE,
    RELEASE,
    REQUEST_HELP,
    SYSTEM,
    TAKE_CONTROL,
    TEAM_PRIORITY,
    USER,
    WORKING,
    Agent,
)
from shary.team.interaction import AskExecutor
from shary.team.resources import HELP, Need
from shary.team.spec import AgentSpec
from shary.team.tasks import WITHDRAWN
from shary.transport.messages import Act, Answer, Assignment, Message, Progress

if TYPE_CHECKING:
    from shary.kernel.agenda import Goal
    from shary.kernel.supervisor import Supervisor
    from shary.team.team import Team


class RobotAgent(Agent):
    """A robot on the team: one supervisor, its agenda, breakpoints, association, control."""

    def __init__(self, team: Team, spec: AgentSpec, sup: Supervisor):
        super().__init__(team, spec)
        self.sup = sup
        self.world: ExecutorRegistry = sup.executors
        """The executors of the world (the simulation or the robot): the same port for the
        robot's own tasks and for teleoperation."""
        sup.executors = _GatedRegistry(self)
        sup.agenda.listeners.append(self._goal_over)
        self.mode = SYSTEM
        self.controller: str | None = None
        self.associated: str | None = None
        self.pending: list[Act] = []
        """Help requests of one person waiting for the next breakpoint."""
        self.held: tuple[Request, Reporter] | None = None
        self._goals: dict[int, list[tuple[str, str]]] = {}
        """Agenda goal id -> what it is for (team task or help request id) and who asked:
        several, when the agenda merged the same request made twice."""
        self._teleop_ids = itertools.count(1)
        self.last_failure = ""
        """Why the robot's last atomic task failed (the reason its task failed)."""

    def availability(self, need: Need) -> float | None:
        if self.mode == USER:
            return None
        if need.what == HELP:
            if self.associated is not None and self.associated != need.requester:
                return None
            return 1.0 if self.current is None else 0.5
        return super().availability(need)

    def activity_score(self, need: Need) -> float:
        return 1.0 if self.current is None else 0.5

    # -- team tasks -----------------------------------------------------------------

    def handle(self, message: Message) -> None:
        if isinstance(message, Assignment):
            self._assigned(message)
        elif isinstance(message, Act) and message.act == REQUEST_HELP:
            self._help_requested(message)
        elif isinstance(message, Act) and message.act == RELEASE:
            self.release(message.sender)
        elif isinstance(message, Act) and message.act == TAKE_CONTROL:
            self.take_control(message.sender)
        elif isinstance(message, Act) and message.act == HAND_BACK:
            self.hand_back(message.sender)
        elif isinstance(message, Act) and message.act == TELEOPERATE:
            args = message.data.get("args")
            self.teleoperate(message.sender, str(message.data.get("atomic", "")),
                             dict(args) if isinstance(args, dict) else {})
        elif isinstance(message, Answer):
            asking = self.team.own_executor("ask", self)
            if isinstance(asking, AskExecutor):  # an answer nobody waits for is logged
                asking.answered(message)         # by the Interaction Manager already
        elif isinstance(message, Progress):
            if message.status == WITHDRAWN and message.sender == self.team.tasks.address:
                self._withdrawn(message.task, message.reason or WITHDRAWN)
            # else: what became of the help a robot gave, told to the requester
        else:
            super().handle(message)

    def _assigned(self, message: Assignment) -> None:
        reason = ("under user control" if self.mode == USER
                  else f"associated with {self.associated}" if self.associated
                  else f"busy with {self.current}" if self.current not in (None, message.task)
                  else "" if message.skill in self.sup.library.tasks
                  else f"cannot do {message.skill}")
        if reason:
            self.progress(message.sender, message.task, "refused", reason)
            return
        self.current = message.task
        self.activity = WORKING
        goal = self.sup.agenda.add(message.skill, message.args, priority=TEAM_PRIORITY,
                                   source=f"team:{message.task}#{message.attempt}")
        self._goals.setdefault(goal.id, []).append((message.task, message.sender))
        self.progress(message.sender, message.task, "accepted")

    def _withdrawn(self, task: str, reason: str) -> None:
        """The Task Manager took team task ``task`` back (an operator's cancel): its goal
        is cancelled on the agenda (the SHARY task stops as its scheme says), and the
        goal's end tells the Task Manager it is over here."""
        goals = [g for g in self.sup.agenda.goals
                 if g.state not in ("done", "failed", "cancelled")
                 and any(s.startswith(f"team:{task}#") for s in g.sources)]
        if goals:
            self.last_failure = reason  # the progress says why
        for goal in goals:
            self.sup.agenda.cancel(goal, reason)

    def _goal_over(self, goal: Goal) -> None:
        found = self._goals.pop(goal.id, None)
        if found is None:
            return
        outcome = "done" if goal.state == "done" else "failed"
        reason = self.last_failure if outcome == "failed" else ""
        self.last_failure = ""
        for what, who in found:
            if what == self.current:
                self.current = None
                self.activity = IDLE if self.associated is None else ASSOCIATED
                self.progress(who, what, outcome, reason)
            else:  # a help request served
                self.progress(who, what, "served" if outcome == "done" else "failed", reason)
        self.team.loop.call_soon(self._breakpoint_if_idle)

    # -- help requests, breakpoints, association ----------------------------------------

    def _help_requested(self, message: Act) -> None:
        requester = _requester(message)
        if self.mode == USER or (self.associated not in (None, requester)):
            self.progress(message.sender, message.task or "", "refused",
                          "under user control" if self.mode == USER
                          else f"associated with {self.associated}")
            return
        if self.associated == requester:
            self._serve(message)
            return
        waiting_for = _requester(self.pending[0]) if self.pending else requester
        if waiting_for != requester:
            self.progress(message.sender, message.task or "", "refused",
                          f"already waiting to serve {waiting_for}")
            return
        self.pending.append(message)
        self.progress(message.sender, message.task or "", "waiting",
                      "until a breakpoint of the current task")
        self.team.loop.call_soon(self._breakpoint_if_idle)

    def _idle(self) -> bool:
        agenda = self.sup.agenda
        return agenda.active is None or self.held is not None

    def _breakpoint_if_idle(self) -> None:
        if self.pending and self._idle():
            self._associate()

    def at_breakpoint(self, request: Request, reporter: Reporter) -> bool:
        """Called before each atomic task starts: whether the robot stops here to serve a
        waiting request (the atomic task is then held, and cancelled by the suspension)."""
        if not self.pending:
            return False
        self.held = (request, reporter)
        self.team.record("breakpoint", task=self.current, agent=self.name,
                         before=request.atomic, node=request.node)
        self._associate()
        return True

    def release_held(self, request: Request) -> bool:
        """The suspension cancelled the held atomic task: report it cancelled."""
        if self.held is None or self.held[0].id != request.id:
            return False
        _, reporter = self.held
        self.held = None
        reporter.cancelled(request, "suspended at a breakpoint")
        return True

    def _associate(self) -> None:
        messages, self.pending = self.pending, []
        if not messages:
            return
        requester = _requester(messages[0])
        self.associated = requester
        self.activity = ASSOCIATED
        self.team.record("associate", task=messages[0].task, agent=self.name,
                         requester=requester, suspended=self.current)
        self.sup.agenda.hold(f"associated:{requester}", ASSOCIATED_PRIORITY)
        for message in messages:
            self._serve(message)

    def _serve(self, message: Act) -> None:
        skill = str(message.data.get("skill", ""))
        args = dict(message.data.get("args") or {})
        if skill not in self.sup.library.tasks:
            self.progress(message.sender, message.task or "", "failed", f"cannot do {skill}")
            return
        self.team.record("serve", task=message.task, agent=self.name,
                         requester=message.data.get("requester"), skill=skill, args=args or None)
        goal = self.sup.agenda.add(skill, args, priority=ASSOCIATED_PRIORITY,
                                   source=f"help:{message.task}")
        self._goals.setdefault(goal.id, []).append((message.task or "", message.sender))
        self.progress(message.sender, message.task or "", "serving")

    def release(self, requester: str) -> None:
        """The requester lets the robot go: its own task resumes (Fig. 7's end)."""
        if self.associated != requester:
            self.team.record("release-ignored", agent=self.name, by=requester,
                             associated=self.associated)
            return
        self.associated = None
        self.activity = WORKING if self.current else IDLE
        self.team.record("release", task=self.current, agent=self.name, by=requester)
        self.sup.agenda.release(f"associated:{requester}")

    # -- control authority ---------------------------------------------------------------

    def take_control(self, human: str) -> bool:
        """User mode: ``human`` drives the robot; its own goals wait (logged with the task)."""
        if self.mode == USER:
            self.team.record("control-refused", task=self.current, agent=self.name, by=human,
                             controller=self.controller)
            return False
        self.mode, self.controller = USER, human
        self.team.record("control", task=self.current, agent=self.name, mode=USER, by=human)
        self.sup.agenda.hold(f"control:{human}", CONTROL_PRIORITY)
        return True

    def teleoperate(self, human: str, atomic: str, args: dict[str, Any],
                    on_outcome: Callable[[Outcome], Any] | None = None) -> Request | None:
        """One atomic task sent by the human in control, through the world's executors."""
        if self.mode != USER or self.controller != human:
            self.team.record("teleop-refused", agent=self.name, by=human, atomic=atomic,
                             reason="not in control")
            return None
        request = Request(f"{self.sup.ids}t{next(self._teleop_ids)}", atomic, dict(args),
                          self.name, self.current or "teleoperation")

        def report(outcome: Outcome) -> None:
            record_outcome(self.team.record, outcome)
            if on_outcome is not None:
                on_outcome(outcome)

        self.world.dispatch(request, Reporter(report, self.team.loop.call_soon),
                            self.team.record, args=args, by=human)
        return request

    def hand_back(self, human: str) -> bool:
        """System mode again: the robot's own goals go on."""
        if self.mode != USER or self.controller != human:
            self.team.record("control-refused", agent=self.name, by=human, mode=SYSTEM)
            return False
        self.mode, self.controller = SYSTEM, None
        self.team.record("control", task=self.current, agent=self.name, mode=SYSTEM, by=human)
        self.sup.agenda.release(f"control:{human}")
        # a task that became ready while the robot was driven waited for it (it was not
        # available then): offer it now, or nothing else would ever make it go
        self.team.loop.call_soon(self.team.tasks.dispatch)
        return True


TELEOPERATE = "TELEOPERATE"
"""The act by which the human in control sends the robot one atomic task (``data``:
``atomic`` and ``args``)."""


def _requester(message: Act) -> str:
    """Who a help request is for (the Interaction Manager passes it on)."""
    return str(message.data.get("requester", message.sender))


class _Gate:
    """An executor of the world, with the robot's breakpoints in front of it."""

    __slots__ = ("robot", "inner")

    def __init__(self, robot: RobotAgent, inner: Executor):
        self.robot = robot
        self.inner = inner

    def start(self, request: Request, reporter: Reporter) -> None:
        if not self.robot.at_breakpoint(request, reporter):
            self.inner.start(request, _StepReporter(reporter, self.robot, request))

    def cancel(self, request: Request) -> None:
        if not self.robot.release_held(request):
            self.inner.cancel(request)


class _StepReporter(Reporter):
    """Passes an executor's reports on, and tells who delegated the task of each step done
    (the robot's progress events, HRI/OS Section 3.6)."""

    def __init__(self, inner: Reporter, robot: RobotAgent, request: Request):
        self.inner = inner
        self.robot = robot
        self.request = request

    def done(self, request: Request, **result: Any) -> None:
        self.inner.done(request, **result)
        robot = self.robot
        if robot.current is not None and robot.associated is None:
            robot.progress(robot.team.tasks.address, robot.current, "step",
                           atomic=request.atomic)

    def failed(self, request: Request, reason: str) -> None:
        self.robot.last_failure = f"{request.atomic}: {reason}"
        self.inner.failed(request, reason)

    def cancelled(self, request: Request, reason: str = "cancelled") -> None:
        self.inner.cancelled(request, reason)


class _GatedRegistry(ExecutorRegistry):
    """The supervisor's view of the world's executors: each behind the robot's gate, plus
    the team's own atomic tasks (``ask``)."""

    def __init__(self, robot: RobotAgent):
        super().__init__()
        self.robot = robot
        self._gates: dict[str, _Gate] = {}

    def register(self, atomic: str, executor: Executor) -> None:
        self.robot.world.register(atomic, executor)

    def get(self, atomic: str) -> Executor | None:
        inner = self.robot.team.own_executor(atomic, self.robot) or self.robot.world.get(atomic)
        if inner is None:
            return None
        gate = self._gates.get(atomic)
        if gate is None or gate.inner is not inner:
            gate = self._gates[atomic] = _Gate(self.robot, inner)
        return gate

    def names(self) -> list[str]:
        return self.robot.world.names()
