"""The typed messages between team agents (what a :mod:`~shary.transport.port` carries).

HRI/OS (Section 3.1) has agents talk through an agent framework (OAA) and a
data channel.  Messages are plain frozen dataclasses of JSON-friendly fields:
the in-process port hands the objects over, the Zenoh port encodes
:meth:`Message.as_dict` with :mod:`shary.transport.wire` and decodes with
:func:`build` after checking every field against the versioned schema.

The kinds between agents:

- :class:`Act`: a communication act between agents (``REQUEST-HELP``,
  ``RELEASE``, ``TAKE-CONTROL``, ``HAND-BACK`` …) with free data;
- :class:`Assignment`: a team task offered to an agent (the Task Manager's);
- :class:`Question`: a question with priority, expiration, type and data;
- :class:`Answer`: the answer to a question (or its fallback when it expired);
- :class:`Progress`: what became of an assignment or a request (accepted,
  refused, started, step, done, failed …);
- :class:`FactChange`: facts an agent shares (added or removed triples);
- :class:`LogRecord`: a row of an agent's context log, for whoever gathers them.

and two between the processes of a distributed team: :class:`Clock` (the
shared simulated clock's steps and the agents' replies, see
:mod:`shary.transport.distributed`) and :class:`State` (what the managers tell
a member that joins a running team, see :mod:`shary.transport.rejoin`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from functools import cache
from typing import Any, ClassVar

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
        """The message as JSON-friendly data, with its kind (what a transport sends).

        Shallow (the fields' values as they are): ``dataclasses.asdict`` deep-copies,
        which costs more than the whole JSON encoding of a small message."""
        data = {"kind": self.kind}
        for name in _names(type(self)):
            data[name] = getattr(self, name)
        return data


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


@dataclass(frozen=True)
class FactChange(Message):
    """Facts an agent shares: ``removed`` then ``added`` triples (subject, predicate, object)
    of one ``perspective``.  Subjects and predicates are names; an object is a name, a
    number or a boolean (what :class:`shary.facts.database.FactDatabase` reads back as itself)."""

    kind: ClassVar[str] = "fact"
    added: tuple[tuple[str, str, Any], ...] = ()
    removed: tuple[tuple[str, str, Any], ...] = ()
    perspective: str = "robot"


@dataclass(frozen=True)
class LogRecord(Message):
    """A row of an agent's context log: its time, kind, task and data."""

    kind: ClassVar[str] = "log"
    time: float = 0.0
    event: str = ""
    task: str | None = None
    data: dict[str, Any] = field(default_factory=dict)
    agent: str | None = None
    """The row's agent (the sender is the process that logged it)."""


@dataclass(frozen=True)
class Clock(Message):
    """The shared simulated clock of a distributed team.

    ``step``: the clock agent tells everyone to advance to ``time``; ``idle``:
    an agent has run everything due by ``time``, says how many messages it has
    ``sent`` to and ``received`` for each address so far, and when its next
    timer is due (``next``; the clock moves on to the earliest one only when
    every agent is idle at ``time`` and every message sent has been received);
    ``stop``: the run is over (``reason``).
    """

    kind: ClassVar[str] = "clock"
    state: str = ""
    time: float = 0.0
    sent: dict[str, Any] = field(default_factory=dict)
    received: dict[str, Any] = field(default_factory=dict)
    next: float | None = None
    reason: str = ""


@dataclass(frozen=True)
class State(Message):
    """What a member joining a running team needs to take part: the managers' view.

    ``tasks``: the team's task table, task -> ``{"state", "agent", "done_by"}``
    (done, running and by whom, offered to whom); ``questions``: the ids of the
    open questions addressed to the member (each is sent again right after, with
    the time it has left); ``associated``: the robots serving the member's help
    requests (for a robot: the person it serves); ``controls``: the robots under
    its control, user mode (for a robot: the person driving it).  The facts it
    subscribes to come from their sharer, all at once on subscribing
    (:mod:`shary.transport.facts`), as on its first start.
    """

    kind: ClassVar[str] = "state"
    time: float = 0.0
    tasks: dict[str, Any] = field(default_factory=dict)
    questions: tuple[str, ...] = ()
    associated: tuple[str, ...] = ()
    controls: tuple[str, ...] = ()


KINDS: dict[str, type[Message]] = {c.kind: c for c in (Act, Assignment, Question, Answer,
                                                         Progress, FactChange, LogRecord,
                                                         Clock, State)}


@cache
def _names(cls: type[Message]) -> tuple[str, ...]:
    """A message class's field names, in order."""
    return tuple(f.name for f in fields(cls))


@cache
def _tuples(cls: type[Message]) -> tuple[tuple[str, bool], ...]:
    """A message class's tuple fields (JSON gives lists): (name, whether of triples)."""
    return tuple((f.name, str(f.type).startswith("tuple[tuple[")) for f in fields(cls)
                 if str(f.type).startswith("tuple["))


def message_from_dict(data: dict[str, Any]) -> Message:
    """The message that :meth:`Message.as_dict` gave (KeyError/TypeError when it is not one)."""
    kind = data["kind"]
    names = _names(KINDS[kind])
    return build(kind, {k: v for k, v in data.items() if k in names})


def build(kind: str, values: dict[str, Any]) -> Message:
    """The message of ``kind`` with these fields (JSON lists made tuples again)."""
    cls = KINDS[kind]
    for name, triples in _tuples(cls):
        if name in values:
            values[name] = (tuple(tuple(t) for t in values[name]) if triples
                            else tuple(values[name]))
    return cls(**values)


PICTURE = "png"
"""The key of a picture's bytes (base64 PNG) in a question's ``data``: the picture travels
with the question to whoever answers, on any machine; logs keep its path (``image``)."""


def loggable(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` without the bulky bytes a log row does not need (a picture's): the row
    says a picture went (``picture: true``) and keeps its path (``image``) if it has one."""
    if PICTURE not in data:
        return data
    return {**{k: v for k, v in data.items() if k != PICTURE}, "picture": True}


def summary(message: Message) -> dict[str, Any]:
    """The fields worth a log line (not the whole payload: images stay paths)."""
    if isinstance(message, Act):
        return {"act": message.act, "task": message.task, "data": message.data or None}
    if isinstance(message, Assignment):
        return {"task": message.task, "skill": message.skill, "args": message.args or None,
                "attempt": message.attempt}
    if isinstance(message, Question):
        return {"text": message.text, "question_type": message.type,
                "priority": message.priority, "task": message.task,
                "data": loggable(message.data) or None}
    if isinstance(message, Answer):
        return {"question": message.question, "value": message.value,
                "expired": message.expired or None}
    if isinstance(message, Progress):
        return {"task": message.task, "status": message.status,
                "reason": message.reason or None}
    if isinstance(message, FactChange):
        return {"added": len(message.added), "removed": len(message.removed)}
    if isinstance(message, State):
        return {"at": message.time, "tasks": len(message.tasks),
                "questions": list(message.questions) or None,
                "associated": list(message.associated) or None,
                "controls": list(message.controls) or None}
    return {}
