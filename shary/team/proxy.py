"""Human proxies: a person on the team, real or simulated.

HRI/OS (Section 3.8): "a human proxy agent that represents user capabilities
and accepts task assignments, much in the same way that the Robot Agent does
for robots".  A :class:`HumanProxy` accepts assignments and questions and
answers for the person.  With a :class:`~shary.team.spec.Behaviour` the person
is simulated on the loop (accept, refuse, answer late, ignore, ask for help
on their own), as the simulated people of ``sim`` play a profile; without
one, a user interface calls :meth:`HumanProxy.reply`, :meth:`HumanProxy.report`,
:meth:`HumanProxy.answer` and :meth:`HumanProxy.decline`, and hears what the
person receives through :attr:`HumanProxy.listeners`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from shary.team.agents import ANSWERING, IDLE, REQUEST_HELP, WORKING, Agent
from shary.team.resources import QUESTION, Need
from shary.team.spec import ACCEPT, ANSWER, IGNORE, AgentSpec, Delay, HelpRequest
from shary.team.tasks import WITHDRAWN
from shary.transport.messages import Act, Answer, Assignment, Message, Progress, Question

if TYPE_CHECKING:
    from shary.team.team import Team


class HumanProxy(Agent):
    """A person on the team (see the module's docstring)."""

    def __init__(self, team: Team, spec: AgentSpec):
        super().__init__(team, spec)
        self.remote = spec.remote
        self.behaviour = spec.behaviour
        self.assignments: dict[str, Assignment] = {}
        self.questions: list[Question] = []
        """Questions waiting for this person, the most urgent first."""
        self.listeners: list[Callable[[Message], Any]] = []
        """A user interface hears each message the person receives here."""
        self.performers: dict[str, Callable[[Assignment], Any]] = {}
        """Skill -> what carries out the person's accepted task in a simulated world (the
        astronauts carry a panel); it calls :meth:`report` when the work is over."""
        self._answering: str | None = None

    def availability(self, need: Need) -> float | None:
        if need.what != QUESTION and self.remote:
            return None  # a remote person does not carry panels
        if need.what == QUESTION:
            return 1.0 / (1.0 + len(self.questions))
        return super().availability(need)

    def handle(self, message: Message) -> None:
        for listener in self.listeners:
            listener(message)
        if isinstance(message, Assignment):
            self.assignments[message.task] = message
            self.current = message.task
            if self.behaviour is not None:
                self._simulate_assignment(message)
        elif isinstance(message, Question):
            self.questions.append(message)
            self.questions.sort(key=lambda q: -q.priority)
            if self.behaviour is not None:
                self._next_question()
        elif isinstance(message, Progress) or isinstance(message, Answer):
            self.team.record("heard", agent=self.name, type=message.kind,
                             task=getattr(message, "task", None),
                             status=getattr(message, "status", None))
            if isinstance(message, Progress) and message.status == WITHDRAWN \
                    and message.task in self.assignments:
                self.report(message.task, "failed", message.reason or WITHDRAWN)
        else:
            super().handle(message)

    # -- what a person (or their interface) does ------------------------------------------

    def reply(self, task: str, accept: bool, reason: str = "") -> None:
        """Accept or refuse an assignment."""
        message = self.assignments.get(task)
        if message is None:
            return
        if accept:
            self.activity = WORKING
            self.progress(message.sender, task, "accepted")
            performer = self.performers.get(message.skill)
            if performer is not None:
                performer(message)
        else:
            del self.assignments[task]
            self.current = None
            self.progress(message.sender, task, "refused", reason or "the person said no")

    def report(self, task: str, status: str, reason: str = "") -> None:
        """A task the person accepted is ``done`` or ``failed``."""
        message = self.assignments.pop(task, None)
        if message is None:
            return
        self.current = None
        self.activity = ANSWERING if self._answering else IDLE
        self.progress(message.sender, task, status, reason)

    def answer(self, question: str, value: str) -> None:
        """Answer a question the person was asked."""
        found = next((q for q in self.questions if q.id == question), None)
        if found is None:
            return
        self.questions.remove(found)
        self.send(Answer(self.name, found.sender, question=found.id, value=value))
        self._answered()

    def decline(self, question: str, reason: str = "") -> None:
        """Say one cannot answer (the Interaction Manager asks someone else)."""
        found = next((q for q in self.questions if q.id == question), None)
        if found is None:
            return
        self.questions.remove(found)
        self.progress(found.sender, found.id, "refused", reason or "cannot answer")
        self._answered()

    def withdraw(self, question: str) -> None:
        """The question expired or was answered by someone else."""
        self.questions = [q for q in self.questions if q.id != question]
        if self._answering == question:
            self._answered()

    def _answered(self) -> None:
        self._answering = None
        self.activity = WORKING if self.current else IDLE
        if self.behaviour is not None:
            self._next_question()

    def request_help(self, skill: str, args: dict[str, Any] | None = None, *,
                     release_after: float | None = None) -> str:
        """Ask the team for help (a robot's skill): the Interaction Manager finds one (a
        ``REQUEST-HELP`` act to it, wherever it runs); the request's id."""
        help_id = self.team.port.new_id("h")
        data: dict[str, Any] = {"skill": skill, "args": dict(args or {})}
        if release_after is not None:
            data["release-after"] = release_after
        self.send(Act(self.name, self.team.interaction.address, id=help_id, act=REQUEST_HELP,
                      task=help_id, data=data))
        return help_id

    # -- the simulated person -----------------------------------------------------------

    def _draw(self, delay: Delay) -> float:
        low, high = delay
        return low if high <= low else self.team.loop.random.uniform(low, high)

    def _simulate_assignment(self, message: Assignment) -> None:
        behaviour = self.behaviour
        assert behaviour is not None
        reply = behaviour.assignments
        if reply.reply == IGNORE:
            self.team.record("ignored", task=message.task, agent=self.name)
            return
        loop = self.team.loop
        accept = reply.reply == ACCEPT

        def answer() -> None:
            if self.assignments.get(message.task) is not message:
                return  # withdrawn meanwhile
            self.reply(message.task, accept)
            if accept and message.skill not in self.performers:
                loop.call_later(self._draw(behaviour.work_time(message.skill)),
                                self._finish, message)

        loop.call_later(self._draw(reply.after), answer)

    def _finish(self, message: Assignment) -> None:
        if self.assignments.get(message.task) is message:
            self.report(message.task, "done")

    def _next_question(self) -> None:
        behaviour = self.behaviour
        if behaviour is None or self._answering is not None or not self.questions:
            return
        question = self.questions[0]
        reply = behaviour.questions
        if reply.reply == IGNORE:
            return
        self._answering = question.id
        self.activity = ANSWERING

        def answer() -> None:
            if self._answering != question.id:
                return
            if reply.reply == ANSWER:
                self.answer(question.id, self._answer_to(question))
            else:
                self.decline(question.id, "the person will not answer")

        self.team.loop.call_later(self._draw(reply.after), answer)

    def _answer_to(self, question: Question) -> str:
        behaviour = self.behaviour
        assert behaviour is not None
        if question.topic in behaviour.answers:
            return behaviour.answers[question.topic]
        if question.choices:
            return question.choices[0]
        return "yes" if question.type == "yes-no" else "ok"

    def start_script(self) -> None:
        """Put the person's own help requests on the clock."""
        if self.behaviour is None:
            return
        for request in self.behaviour.requests:
            self.team.loop.call_later(request.at, self._scripted_request, request)

    def _scripted_request(self, request: HelpRequest) -> None:
        self.request_help(request.ask, dict(request.args), release_after=request.release)
