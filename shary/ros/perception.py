"""Perception and people from ROS 2 topics: facts, staleness, and what people say.

:class:`RosPerception` subscribes to a binding's ``facts`` and ``speech``
topics.  Each message of a fact topic gives the topic's whole current set of
facts (templates over its fields, once per element with ``each``, or lines
``SUBJECT PREDICATE OBJECT``, whose object ``true``, ``false``, a number or
``"quoted text"`` is read as JSON reads it); only the difference with the topic's previous
set is written to the fact database, in the robot's perspective, so monitors
and chronicles hear of changes, not of messages (as the simulator's
perception does).  A topic silent for longer than its ``stale`` time has its
facts removed: a person no longer tracked is no longer perceived.

A sentence on a speech topic is a person's act: *yes* or *no* is an answer
(H-AGREE, H-DISAGREE) to the task that expects one; anything else goes to the
communication manager's requests grammar (``hear``: a request becomes the
person's ASK-TASK).

Callbacks only put the messages on the engine's loop; everything else runs
there.  Perception may come thousands of times a second: each topic is taken
in bursts (:meth:`~shary.ros.node.RosNode.drained_subscription`, one event on
the loop for all the messages waiting), and a message whose facts are those
of the topic's previous message (a robot republishing what it sees) costs
one comparison of its text.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from rdflib import Literal

from shary.ros import messages
from shary.ros.binding import Binding, FactSource, SpeechSource, import_interface
from shary.ros.node import RosNode

Triple = tuple[Any, Any, Any]
DEPTH = 10_000
"""Messages a topic may queue while the engine is busy: with one thread (shary.ros.node),
the history is the only buffer while the loop works (1.7 s of a 6,000 a second stream;
peak memory unchanged from a depth of 1,000, docs/benchmarks.md)."""
ANSWERS = {"yes": "H-AGREE", "yes please": "H-AGREE", "ok": "H-AGREE", "okay": "H-AGREE",
           "sure": "H-AGREE", "no": "H-DISAGREE", "no thanks": "H-DISAGREE",
           "no thank you": "H-DISAGREE"}
"""Sentences that answer the robot's question rather than ask for something."""


class RosPerception:
    """Facts and speech from a binding's topics (see the module's docstring)."""

    def __init__(self, node: RosNode, binding: Binding, facts: Any, loop: Any, *,
                 perspective: str = "robot",
                 act: Callable[[str, str], Any] | None = None,
                 hear: Callable[[str, str], Any] | None = None,
                 record: Callable[..., Any] | None = None, qos: Any = None):
        self.node = node
        self.facts = facts
        self.loop = loop
        self.perspective = perspective
        self.act = act or (lambda agent, act: None)
        """``act(agent, act)``: a person's answer (the supervisor's ``receive_act``)."""
        self.hear = hear or (lambda agent, sentence: None)
        """``hear(agent, sentence)``: anything else said (the dialogue's ``Initiative.hear``)."""
        self.record = record or (lambda *args, **data: None)
        self.qos = qos
        """Told of each subscription, to report publishers it cannot hear
        (:class:`~shary.ros.qos.QosWatch`), or None."""
        self.published: dict[int, set[Triple]] = {}
        self.heard_at: dict[int, float] = {}
        self._last_text: dict[int, str] = {}
        """A ``lines`` topic's last text: the same again states the same facts."""
        self.messages = 0
        self.missing: list[str] = []
        """Topics whose type is not installed here (not subscribed)."""
        for index, source in enumerate(binding.facts):
            self._subscribe(source, lambda taken, i=index, s=source: node.put(
                self._facts, i, s, taken))
        for source in binding.speech:
            self._subscribe(source, lambda taken, s=source: node.put(self._speech, s, taken))
        stale = [s.stale for s in binding.facts if s.stale is not None]
        if stale:
            self._period = min(stale) / 4
            loop.call_later(self._period, self._check_stale, list(binding.facts))

    def _subscribe(self, source: FactSource | SpeechSource, callback: Callable) -> None:
        """Subscribe with the source's quality of service (shary's default: reliable,
        volatile, :data:`DEPTH` deep)."""
        from rclpy.qos import QoSProfile

        from shary.ros.qos import profile

        cls = import_interface(source.type)
        if cls is None:
            self.missing.append(source.topic)
            return
        asked = profile(source.qos, QoSProfile(depth=DEPTH))
        self.node.drained_subscription(
            cls, source.topic, callback, qos=asked,
            events=self.qos.callbacks(source.topic, asked) if self.qos is not None else None)

    # -- facts (on the engine's loop) ---------------------------------------------------

    def _facts(self, index: int, source: FactSource, taken: list[Any]) -> None:
        """Messages of a fact topic, oldest first: each one's facts in turn (a fact seen
        for one message is a change monitors hear of)."""
        self.messages += len(taken)
        self.heard_at[index] = self.loop.now()
        for message in taken:
            if source.lines:
                text = messages.read_field(message, source.lines)
                if text == self._last_text.get(index):
                    continue
                self._last_text[index] = text
            self._publish(index, self.triples(source, message), source.topic)

    @staticmethod
    def triples(source: FactSource, message: Any) -> set[Triple]:
        """The facts one message of ``source`` states."""
        if source.lines:
            found = set()
            for line in str(messages.read_field(message, source.lines) or "").splitlines():
                parts = line.split(maxsplit=2)
                if len(parts) == 3:
                    found.add((parts[0], parts[1], _literal(parts[2])))
            return found
        items = messages.read_field(message, source.each) if source.each else [None]
        return {tuple(_part(p, message, item) for p in template)  # type: ignore[misc]
                for item in items or () for template in source.facts}

    def _publish(self, index: int, now: set[Triple], topic: str = "") -> None:
        """Make the topic's facts ``now``: one change of the fact database (kept as its
        terms, so that a fact that goes is not converted again).  A robot may send
        anything: a fact naming nothing the database can name (``foo:x`` with an unknown
        prefix, ``a?b``) is refused with a ``refused`` row, and the others still count."""
        term = self.facts.term
        try:
            now = {(term(s), term(p), term(o)) for s, p, o in now}
        except (TypeError, ValueError):  # rare: find which facts, and keep the others
            now = self._terms(now, topic)
        before = self.published.get(index, set())
        if now != before:
            self.facts.change(before - now, now - before, perspective=self.perspective)
        self.published[index] = now

    def _terms(self, facts: set[Triple], topic: str) -> set[Triple]:
        """The facts as terms, one by one: each that names nothing is refused."""
        term, terms = self.facts.term, set()
        for fact in facts:
            try:
                terms.add((term(fact[0]), term(fact[1]), term(fact[2])))
            except (TypeError, ValueError) as error:
                self.record("refused", topic=topic, line=" ".join(map(str, fact)),
                            reason=str(error))
        return terms

    def _check_stale(self, sources: list[FactSource]) -> None:
        now = self.loop.now()
        for index, source in enumerate(sources):
            if (source.stale is not None and self.published.get(index)
                    and now - self.heard_at.get(index, now) > source.stale):
                self.record("stale", topic=source.topic, facts=len(self.published[index]))
                self._publish(index, set())
                self._last_text.pop(index, None)
        self.loop.call_later(self._period, self._check_stale, sources)

    # -- speech ---------------------------------------------------------------------------

    def _speech(self, source: SpeechSource, taken: list[Any]) -> None:
        for message in taken:
            sentence = str(messages.read_field(message, source.text) or "").strip()
            if not sentence:
                continue  # an empty final: nothing was said
            speaker = messages.text(source.speaker, message) if source.speaker else "someone"
            answer = ANSWERS.get(sentence.lower().strip(" .!"))
            if answer is not None:
                self.record("heard", agent=speaker, text=sentence)
                self.act(speaker, answer)
            else:
                self.hear(speaker, sentence)


def _literal(text: str) -> Any:
    """An object written on a line: ``true``, ``false``, numbers and ``"quoted text"`` as
    JSON reads them (a fact's truth value, quantity or text literal), anything else as a
    name."""
    if text[:1] == '"':
        try:
            return Literal(json.loads(text))
        except ValueError:
            return text
    if text in ("true", "false") or text[:1].isdigit() or text[:1] == "-":
        try:
            value = json.loads(text)
        except ValueError:
            return text
        if isinstance(value, (bool, int, float)):
            return value
    return text


def _part(template: Any, message: Any, item: Any) -> Any:
    if not isinstance(template, str) or "{" not in template:
        return template
    return messages.text(template, message, item)
