"""The message port: typed messages between team agents, delivered on the receiver's loop.

Every message between agents and managers goes through one
:class:`MessagePort`.  This one is in-process (the default): ``send`` queues
the delivery on the event loop (so a reply never re-enters its sender in the
middle of a step) and logs the message in the context log.
:class:`~shary.transport.zenohport.ZenohPort` is the same port with the
addresses of other processes reached over Zenoh; nothing above the port
knows which one it talks through.

Faults are injected here, for both: :class:`Faults` drops a share of the
messages and delays the others, on the loop's clock (so a simulated run
with faults is still repeatable for a seed).  The Zenoh port applies them to
what arrives too, so the faults of one process are a bad link both ways.
"""

from __future__ import annotations

import itertools
import random
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from shary.kernel.loop import EventLoop
from shary.transport.messages import Message, summary

Handler = Callable[[Message], Any]


@dataclass(frozen=True)
class Faults:
    """A bad link: ``loss`` is the share of messages dropped, ``latency`` seconds of delay,
    for the messages from or to one of ``agents`` (every message when it is empty)."""

    loss: float = 0.0
    latency: float = 0.0
    seed: int = 0
    agents: frozenset[str] = frozenset()

    def touches(self, message: Message) -> bool:
        """Whether ``message`` travels this link.  The copies of the log do not (they are
        not the team's messages, :mod:`shary.transport.logshare`), nor a rejoining
        member's State (its first step of the shared clock, which faults never touch)."""
        return (message.kind not in ("log", "state")
                and (not self.agents or message.sender in self.agents
                     or message.to in self.agents))

    def __post_init__(self) -> None:
        if not 0.0 <= self.loss <= 1.0:
            raise ValueError(f"loss must be between 0 and 1, not {self.loss}")
        if self.latency < 0:
            raise ValueError(f"latency must not be negative, not {self.latency}")


class MessagePort:
    """In-process delivery of messages to the agents that subscribed, on the loop.

    One handler per address (an agent's or a manager's name); a message to an
    address nobody holds is logged as ``message-lost`` rather than raised:
    on a network, the sender would not know either.
    """

    def __init__(self, loop: EventLoop, record: Callable[..., None] | None = None, *,
                 faults: Faults | None = None):
        self.loop = loop
        self._record = record
        self._handlers: dict[str, Handler] = {}
        self._kinds: dict[str, Handler] = {}
        self._ids = itertools.count(1)
        self.faults = faults
        self._fault_random = random.Random(faults.seed if faults else 0)
        self.sent = 0
        self.down: set[str] = set()
        """Members killed in this process (:meth:`shary.team.Team.kill`): what they send
        goes nowhere, what is sent to them is lost, as when their own process is gone."""

    def subscribe(self, address: str, handler: Handler) -> None:
        self._handlers[address] = handler

    def tap(self, address: str, taker: Callable[[Message], bool]) -> None:
        """Let ``taker`` see each message to ``address`` before its handler does, and keep
        the ones it answers True for (a robot's link to the world takes the world's
        replies to its requests; the robot's agent hears the rest)."""
        inner = self._handlers.get(address)

        def first(message: Message) -> None:
            if not taker(message) and inner is not None:
                inner(message)
        self._handlers[address] = first

    def take(self, kind: str, handler: Handler) -> None:
        """Give every message of ``kind`` that arrives here, whatever its address, to
        ``handler`` (a process's fact base takes every ``FactChange``)."""
        self._kinds[kind] = handler

    def new_id(self, prefix: str) -> str:
        return f"{prefix}{next(self._ids)}"

    def send(self, message: Message) -> None:
        """Deliver ``message`` to its addressee after the current callback."""
        if message.sender in self.down:
            return  # a dead process sends nothing
        self.sent += 1
        known = self.reaches(message.to)
        if self._record is not None:
            self._record("message" if known else "message-lost",
                         agent=message.sender, to=message.to, type=message.kind,
                         id=message.id or None, **summary(message))
        if known and not self.faulted(message, self.route):
            self.route(message)

    def faulted(self, message: Message, then: Handler) -> bool:
        """Whether the faults took ``message`` over: dropped (logged), or handed to
        ``then`` after the latency; False when it goes on now."""
        faults = self.faults
        if faults is None or not faults.touches(message):
            return False
        if faults.loss and self._fault_random.random() < faults.loss:
            if self._record is not None:
                self._record("message-dropped", agent=message.sender, to=message.to,
                             type=message.kind, id=message.id or None)
            return True
        if faults.latency:
            self.loop.call_later(faults.latency, then, message)
            return True
        return False

    def reaches(self, address: str) -> bool:
        """Whether a message to ``address`` goes anywhere (here: a local handler)."""
        return address in self._handlers and address not in self.down

    def route(self, message: Message) -> None:
        """Hand ``message`` on towards its addressee (here: on this loop)."""
        self.deliver(message)

    def deliver(self, message: Message) -> None:
        """Queue ``message`` for its local handler on the loop."""
        handler = self._kinds.get(message.kind) if self._kinds else None
        if handler is None:
            handler = self._handlers.get(message.to)
        if handler is not None:
            self.loop.call_soon(self._hand, handler, message)

    def _hand(self, handler: Handler, message: Message) -> None:
        if message.to not in self.down:  # not killed since it was sent
            handler(message)

    def close(self) -> None:
        """Release what the port holds (nothing, in process)."""
