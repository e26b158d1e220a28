"""The Interaction Manager: questions and help requests between agents.

HRI/OS (Section 3.4, Fig. 7 and 8): "whenever an agent needs to communicate,
it sends a request to the IM, which asks the RM for the best agent to talk
to".  Questions have a priority, an expiration time, a type (yes/no, choice,
free text) and attached data (an image of the seam); they go to the best
available human, to the next one when a person declines, and fall back to the
question's ``fallback`` (or fail) when nobody answers in time.  Help requests
(a person asks for light on a panel) go to the best robot with the skill,
which serves them at its next breakpoint (:mod:`shary.team.agents`).

The robots' atomic task ``ask`` is :class:`AskExecutor`: a step of a robot's
recipe asks the team, and waits for the answer or goes on, per the question's
urgency (``wait``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from shary.kernel.executors import Reporter, Request
from shary.statechart.clock import Timer
from shary.team.agents import REQUEST_HELP
from shary.team.proxy import HumanProxy
from shary.team.resources import HELP, QUESTION, Need
from shary.team.spec import QuestionSpec
from shary.team.tasks import LOST
from shary.transport.messages import Act, Answer, Message, Progress, Question, loggable

if TYPE_CHECKING:
    from shary.team.robot import RobotAgent
    from shary.team.team import Team

OnAnswer = Callable[[Answer], Any]


@dataclass(eq=False)
class _Open:
    """A question being asked: who holds it now, who declined, when it expires."""

    question: Question
    on_answer: OnAnswer | None
    tried: set[str] = field(default_factory=set)
    lost: set[str] = field(default_factory=set)
    """Those it was taken from when their process went (asked again when they are back)."""
    holder: str | None = None
    timer: Timer | None = None
    asked_at: float = 0.0

    def left(self, now: float) -> float:
        """Seconds the question has left before it expires (what a person asked later,
        another after a loss or a rejoin, is told)."""
        return max(self.question.expires - (now - self.asked_at), 0.0)


@dataclass(eq=False)
class _Help:
    """A help request being placed with a robot."""

    id: str
    requester: str
    skill: str
    args: dict[str, Any]
    release_after: float | None
    tried: set[str] = field(default_factory=set)
    robot: str | None = None


class InteractionManager:
    """Routes questions and help requests (see the module's docstring)."""

    address = "interaction"

    def __init__(self, team: Team):
        self.team = team
        self.open: dict[str, _Open] = {}
        self.helps: dict[str, _Help] = {}
        self.answered = 0
        self.expired = 0
        team.port.subscribe(self.address, self.handle)

    # -- questions ------------------------------------------------------------------

    def ask(self, asker: str, spec: QuestionSpec, *, task: str | None = None,
            data: dict[str, Any] | None = None, on_answer: OnAnswer | None = None) -> str:
        """Ask the team ``spec``'s question; return its id (the answer comes to
        ``on_answer`` and, as a message, to the asker)."""
        question = Question(asker, "", id=self.team.port.new_id("q"), text=spec.text,
                            type=spec.type, choices=spec.choices, priority=spec.priority,
                            expires=spec.expires, fallback=spec.fallback, topic=spec.topic,
                            data=dict(data or {}), task=task)
        self._open(question, on_answer)
        return question.id

    def _open(self, question: Question, on_answer: OnAnswer | None) -> None:
        """Ask the team ``question`` (from its sender): route it, and time its expiry."""
        team = self.team
        entry = _Open(question, on_answer, asked_at=team.loop.now())
        self.open[question.id] = entry
        team.record("question", task=question.task, agent=question.sender,
                    question=question.id, text=question.text, question_type=question.type,
                    choices=list(question.choices) or None, priority=question.priority,
                    expires=question.expires, data=loggable(question.data) or None)
        entry.timer = team.loop.call_later(question.expires, self._expire, question.id)
        self._route(entry)

    def _route(self, entry: _Open) -> None:
        question = entry.question
        need = Need(QUESTION, at=None, kinds=("human",), subject=question.id,
                    requester=question.sender)
        human = self.team.resources.choose(
            need, self.team.agents.values(),
            free=lambda a: a.name not in entry.tried and a.current != LOST)
        if human is None:
            entry.holder = None
            self.team.record("question-waiting", task=question.task, agent=question.sender,
                             question=question.id, reason="nobody left to ask")
            return
        entry.holder = human.name
        entry.tried.add(human.name)
        self.team.port.send(replace(question, sender=self.address, to=human.name,
                                    expires=entry.left(self.team.loop.now())))

    def agent_lost(self, name: str) -> None:
        """``name``'s process is gone: the questions it held go to the next best person
        (or wait for one), the help it was giving to the next robot with the skill."""
        for entry in list(self.open.values()):
            if entry.holder == name:
                self.team.record("question-rerouted", task=entry.question.task, agent=name,
                                 question=entry.question.id, reason="lost")
                entry.lost.add(name)
                self._route(entry)
        for help_ in list(self.helps.values()):
            if help_.robot == name:
                self.team.record("help-rerouted", task=help_.id, agent=name,
                                 reason="lost")
                self._place(help_)

    def agent_back(self, name: str) -> None:
        """``name`` is back: a question taken from it, that nobody else holds now, goes
        to it again if it is still the best one to ask."""
        for entry in list(self.open.values()):
            if name in entry.lost:
                entry.lost.discard(name)
                entry.tried.discard(name)
                if entry.holder is None:
                    self._route(entry)

    def _expire(self, qid: str) -> None:
        entry = self.open.get(qid)
        if entry is None:
            return
        if entry.holder is not None:
            holder = self.team.agents[entry.holder]
            holder.count(QUESTION, False)
            if isinstance(holder, HumanProxy):
                holder.withdraw(qid)
        self.expired += 1
        self._resolve(entry, entry.question.fallback, None, expired=True)

    def _resolve(self, entry: _Open, value: str | None, by: str | None, *,
                 expired: bool) -> None:
        question = entry.question
        del self.open[question.id]
        if entry.timer is not None:
            entry.timer.cancel()
        answer = Answer(by or self.address, question.sender, id=question.id,
                        question=question.id, value=value, expired=expired)
        self.team.record("answer", task=question.task, agent=by, question=question.id,
                         asker=question.sender, value=value, expired=expired or None,
                         after=round(self.team.loop.now() - entry.asked_at, 6))
        self.team.port.send(answer)
        if entry.on_answer is not None:
            entry.on_answer(answer)

    # -- help requests ---------------------------------------------------------------

    def request_help(self, requester: str, skill: str, args: dict[str, Any], *,
                     release_after: float | None = None, id: str | None = None) -> str:
        """Find a robot with ``skill`` to help ``requester``; return the request's id
        (``id``: the one the requester gave its ``REQUEST-HELP`` act)."""
        help_ = _Help(id or self.team.port.new_id("h"), requester, skill, args, release_after)
        self.helps[help_.id] = help_
        self.team.record("help-request", task=help_.id, agent=requester, skill=skill,
                         args=args or None)
        self._place(help_)
        return help_.id

    def _place(self, help_: _Help) -> None:
        requester = self.team.agents.get(help_.requester)
        need = Need(HELP, help_.skill, at=requester.position if requester else None,
                    kinds=("robot",), subject=help_.id, requester=help_.requester)
        robot = self.team.resources.choose(
            need, self.team.agents.values(),
            free=lambda a: a.name not in help_.tried and a.current != LOST)
        if robot is None:
            del self.helps[help_.id]
            self.team.record("help-unserved", task=help_.id, agent=help_.requester,
                             skill=help_.skill)
            self._tell(help_, "failed", "no robot can help now")
            return
        help_.robot = robot.name
        help_.tried.add(robot.name)
        self.team.port.send(Act(self.address, robot.name, id=help_.id, act=REQUEST_HELP,
                                task=help_.id, data={"requester": help_.requester,
                                                     "skill": help_.skill,
                                                     "args": help_.args}))

    def _tell(self, help_: _Help, status: str, reason: str = "") -> None:
        self.team.port.send(Progress(self.address, help_.requester, task=help_.id,
                                     status=status, reason=reason,
                                     data={"robot": help_.robot} if help_.robot else {}))

    def release(self, requester: str, robot: str) -> None:
        """The requester lets the robot go back to its work."""
        self.team.port.send(Act(requester, robot, act="RELEASE"))

    # -- messages ---------------------------------------------------------------------

    def handle(self, message: Message) -> None:
        if isinstance(message, Question):  # an agent asks the team (a robot's ``ask``)
            if message.id in self.open:
                self.team.record("question-duplicate", agent=message.sender,
                                 question=message.id)
                return
            self._open(message, None)
        elif isinstance(message, Act) and message.act == REQUEST_HELP:  # a person's
            args, after = message.data.get("args"), message.data.get("release-after")
            self.request_help(message.sender, str(message.data.get("skill", "")),
                              dict(args) if isinstance(args, dict) else {}, id=message.id,
                              release_after=float(after) if isinstance(after, (int, float))
                              else None)
        elif isinstance(message, Answer):
            entry = self.open.get(message.question)
            if entry is None:
                self.team.record("answer-late", agent=message.sender, question=message.question,
                                 value=message.value)
                return
            self.team.agents[message.sender].count(QUESTION, True)
            self.answered += 1
            self._resolve(entry, message.value, message.sender, expired=False)
        elif isinstance(message, Progress) and message.task in self.open:
            entry = self.open[message.task]
            if message.status == "refused" and entry.holder == message.sender:
                self.team.agents[message.sender].count(QUESTION, False)
                self._route(entry)
        elif isinstance(message, Progress) and message.task in self.helps:
            self._help_progress(self.helps[message.task], message)

    def _help_progress(self, help_: _Help, message: Progress) -> None:
        robot = self.team.agents.get(message.sender)
        if message.status == "refused":
            if robot is not None:
                robot.count(HELP, False)
            self._place(help_)
            return
        self._tell(help_, message.status, message.reason)
        if message.status == "serving" and robot is not None:
            robot.count(HELP, True)
        if message.status in ("served", "failed"):
            del self.helps[help_.id]
            if message.status == "served" and help_.release_after is not None:
                self.team.loop.call_later(help_.release_after, self.release, help_.requester,
                                          message.sender)


class AskExecutor:
    """The atomic task ``ask`` of one robot: a question of the team file, sent to the
    Interaction Manager as a message (it may run in another process), with the data the
    team attaches to its topic (a picture the world takes); the answer comes back to the
    robot as a message (:meth:`answered`)."""

    def __init__(self, team: Team, robot: RobotAgent):
        self.team = team
        self.robot = robot
        self._asked: dict[str, tuple[str | None, Request, Reporter]] = {}
        """Request id -> (question id, None while the attachment is made; the request; its
        reporter) while the robot waits."""

    def start(self, request: Request, reporter: Reporter) -> None:
        team = self.team
        topic = str(request.args.get("topic", ""))
        spec = team.spec.questions.get(topic)
        if spec is None:
            reporter.failed(request, f"the team file declares no question {topic!r}")
            return
        attach = team.attachments.get(topic)
        if attach is None:
            self._ask(request, reporter, spec, {})
            return
        self._asked[request.id] = (None, request, reporter)

        def attached(data: dict[str, Any]) -> None:
            if request.id in self._asked:  # not cancelled meanwhile
                self._ask(request, reporter, spec, data)
        attach(self.robot, request, attached)

    def _ask(self, request: Request, reporter: Reporter, spec: QuestionSpec,
             data: dict[str, Any]) -> None:
        team = self.team
        qid = team.port.new_id("q")
        team.port.send(Question(self.robot.name, InteractionManager.address, id=qid,
                                text=spec.text, type=spec.type, choices=spec.choices,
                                priority=spec.priority, expires=spec.expires,
                                fallback=spec.fallback, topic=spec.topic, data=dict(data),
                                task=self.robot.current))
        if spec.wait:
            self._asked[request.id] = (qid, request, reporter)
        else:
            self._asked.pop(request.id, None)
            reporter.done(request, question=qid)

    def answered(self, answer: Answer) -> bool:
        """The answer to one of this robot's questions (False: not one it waits for)."""
        found = next((rid for rid, (qid, _, _) in self._asked.items()
                      if qid == answer.question), None)
        if found is None:
            return False
        _, request, reporter = self._asked.pop(found)
        spec = self.team.spec.questions[str(request.args.get("topic", ""))]
        if answer.value is None:
            reporter.failed(request, f"nobody answered {spec.text!r} within "
                                     f"{spec.expires:g}s")
        elif spec.accept and answer.value not in spec.accept:
            reporter.failed(request, f"{answer.sender} answered {answer.value!r} to "
                                     f"{spec.text!r}")
        else:
            reporter.done(request, answer=answer.value)
        return True

    def cancel(self, request: Request) -> None:
        """Stop waiting (the question stays asked; its answer is still logged)."""
        found = self._asked.pop(request.id, None)
        if found is not None:
            found[2].cancelled(request)
