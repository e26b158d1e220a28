"""The message port: typed messages between team agents, delivered on the team's loop.

HRI/OS (Section 3.1) has agents talk through an agent framework (OAA) and a
data channel; here every message between agents and managers goes through
one small :class:`MessagePort`.  It is in-process today: ``send`` queues the
delivery on the event loop (so a reply never re-enters its sender in the
middle of a step) and logs the message in the context log.  Messages are
plain frozen dataclasses of JSON-friendly fields, so putting the port on a
network later (Zenoh) only has to encode :meth:`Message.as_dict` and decode
with :func:`message_from_dict`; nothing else changes.

The five kinds:

- :class:`Act`: a communication act between agents (``REQUEST-HELP``,
  ``RELEASE``, ``TAKE-CONTROL``, ``HAND-BACK`` …) with free data;
- :class:`Assignment`: a team task offered to an agent (the Task Manager's);
- :class:`Question`: a question with priority, expiration, type and data;
- :class:`Answer`: the answer to a question (or its fallback when it expired);
- :class:`Progress`: what became of an assignment or a request (accepted,
  refused, started, step, done, failed …).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, fields
from typing import Any, ClassVar

from shary.loop import EventLoop

YES_NO, CHOICE, FREE_TEXT = "yes-no", "choice", "free-text"
QUESTION_TYPES = (YES_NO, CHOICE, FREE_TEXT)
"""A question's type: what an answer may be (HRI/OS: "query type (y/n, multiple choice …)")."""


@dataclass(frozen=True)
class Message:
    """What every message has: who sends it, to whom, and its id."""

    kind: ClassVar[str] = "message"
    sender: str
    to: str
    id: str = ""

    def as_dict(self) -> dict[str, Any]:
        """The message as JSON-friendly data, with its kind (what a transport sends)."""
        return {"kind": self.kind, **asdict(self)}


@dataclass(frozen=True)
class Act(Message):
    """A communication act from one agent to another (a help request, a release …)."""

    kind: ClassVar[str] = "act"
    act: str = ""
    data: dict[str, Any] = field(default_factory=dict)
    task: str | None = None


@dataclass(frozen=True)
class Assignment(Message):
    """A team task offered to one agent: its skill (a task of the agent) and arguments."""

    kind: ClassVar[str] = "assignment"
    task: str = ""
    skill: str = ""
    args: dict[str, Any] = field(default_factory=dict)
    attempt: int = 1


@dataclass(frozen=True)
class Question(Message):
    """A question to the team (``to`` is filled by the Interaction Manager's routing).

    ``expires`` is seconds after asking; ``fallback`` is the answer taken when
    nobody answered in time (None: the question expires unanswered); ``data``
    carries what helps to answer (``{"image": "seam.png"}``).
    """

    kind: ClassVar[str] = "question"
    text: str = ""
    type: str = YES_NO
    choices: tuple[str, ...] = ()
    priority: int = 0
    expires: float = 60.0
    fallback: str | None = None
    topic: str = ""
    data: dict[str, Any] = field(default_factory=dict)
    task: str | None = None


@dataclass(frozen=True)
class Answer(Message):
    """The answer to question ``question``; ``expired``: the fallback, nobody answered."""

    kind: ClassVar[str] = "answer"
    question: str = ""
    value: str | None = None
    expired: bool = False


@dataclass(frozen=True)
class Progress(Message):
    """What became of an assignment or a request: ``status`` and a reason."""

    kind: ClassVar[str] = "progress"
    task: str = ""
    status: str = ""
    reason: str = ""
    data: dict[str, Any] = field(default_factory=dict)


KINDS: dict[str, type[Message]] = {c.kind: c for c in (Act, Assignment, Question, Answer,
                                                         Progress)}


def message_from_dict(data: dict[str, Any]) -> Message:
    """The message that :meth:`Message.as_dict` gave (KeyError/TypeError when it is not one)."""
    cls = KINDS[data["kind"]]
    names = {f.name for f in fields(cls)}
    values = {k: v for k, v in data.items() if k in names}
    if "choices" in values:
        values["choices"] = tuple(values["choices"])
    return cls(**values)


Handler = Callable[[Message], Any]


class MessagePort:
    """In-process delivery of messages to the agents that subscribed, on the loop.

    One handler per address (an agent's or a manager's name); a message to an
    address nobody holds is logged as ``message-lost`` rather than raised:
    on a network, the sender would not know either.
    """

    def __init__(self, loop: EventLoop, record: Callable[..., None] | None = None):
        self.loop = loop
        self._record = record
        self._handlers: dict[str, Handler] = {}
        self._ids = itertools.count(1)
        self.sent = 0

    def subscribe(self, address: str, handler: Handler) -> None:
        self._handlers[address] = handler

    def new_id(self, prefix: str) -> str:
        return f"{prefix}{next(self._ids)}"

    def send(self, message: Message) -> None:
        """Deliver ``message`` to its addressee after the current callback."""
        self.sent += 1
        handler = self._handlers.get(message.to)
        if self._record is not None:
            self._record("message" if handler is not None else "message-lost",
                         agent=message.sender, to=message.to, type=message.kind,
                         id=message.id or None, **_summary(message))
        if handler is not None:
            self.loop.call_soon(handler, message)


def _summary(message: Message) -> dict[str, Any]:
    """The fields worth a log line (not the whole payload: images stay paths)."""
    if isinstance(message, Act):
        return {"act": message.act, "task": message.task, "data": message.data or None}
    if isinstance(message, Assignment):
        return {"task": message.task, "skill": message.skill, "args": message.args or None,
                "attempt": message.attempt}
    if isinstance(message, Question):
        return {"text": message.text, "question_type": message.type,
                "priority": message.priority, "task": message.task,
                "data": message.data or None}
    if isinstance(message, Answer):
        return {"question": message.question, "value": message.value,
                "expired": message.expired or None}
    if isinstance(message, Progress):
        return {"task": message.task, "status": message.status,
                "reason": message.reason or None}
    return {}
