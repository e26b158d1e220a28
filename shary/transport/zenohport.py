"""The message port over Zenoh: the addresses of other processes reached over the network.

A :class:`ZenohPort` is a :class:`~shary.transport.port.MessagePort` whose
process holds some of the team's addresses (``local``); a message to any
other address is encoded (:mod:`shary.transport.wire`) and published under
``shary/<team>/<to>/<kind>``.  What arrives is only queued by Zenoh's
callbacks (they run on Zenoh's threads); :meth:`ZenohPort.pump`, called by
the agent's own loop, decodes and checks each one and delivers it as an
event on that loop.  A message that does not match the schema is refused and
logged (``message-refused``), never delivered.

Outgoing messages wait in an outbox until the loop is idle, after the context
log's commit: a message another agent acts on has always been logged by its
sender first, so a sender killed afterwards has lost nothing acknowledged.

Every process declares a liveliness token ``shary/<team>/<name>``; whoever
watches (the Task Manager's process) hears joins and leaves within
milliseconds of a crash, and within the lease (1 s here) of a frozen process.

Endpoints are loopback unless given: see :func:`session_config`.
"""

from __future__ import annotations

import json
import queue
from collections.abc import Callable, Iterable
from typing import Any

import zenoh

from shary.kernel.loop import EventLoop
from shary.transport.messages import Clock, LogRecord, Message
from shary.transport.port import Faults, MessagePort
from shary.transport.wire import MAX_BYTES, PREFIX, WireError, decode_timed, encode, key

LEASE_MS = 1000
"""A frozen peer is noticed after this long (Zenoh's default, 10 s, is too slow for a team)."""
LOOPBACK = "tcp/127.0.0.1:7447"
"""Where a team listens unless told otherwise."""


Settings = dict[str, Any]
"""A user's Zenoh settings, path -> value (checked by :mod:`shary.transport.zconfig`)."""


def session_config(*, mode: str = "peer", listen: Iterable[str] = (),
                   connect: Iterable[str] = (), lease_ms: int = LEASE_MS,
                   settings: Settings | None = None) -> zenoh.Config:
    """A Zenoh configuration that reaches exactly the endpoints given.

    No multicast scouting, no gossip, and ``listen`` empty unless given (Zenoh
    would otherwise listen on every interface): a team stays on loopback
    unless a user names another endpoint.  ``settings`` (a user's
    ``--zenoh-config``: TLS, access control …) go over these defaults; the mode
    and the endpoints stay the ones given here.
    """
    conf = zenoh.Config()
    conf.insert_json5("mode", json.dumps(mode))
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("scouting/gossip/enabled", "false")
    conf.insert_json5("transport/link/tx/lease", str(lease_ms))
    for path, value in (settings or {}).items():
        conf.insert_json5(path, json.dumps(value))
    conf.insert_json5("listen/endpoints", json.dumps(list(listen)))
    conf.insert_json5("connect/endpoints", json.dumps(list(connect)))
    return conf


class ZenohPort(MessagePort):
    """See the module's docstring.  ``name`` names this process (its liveliness token)."""

    def __init__(self, loop: EventLoop, record: Callable[..., None] | None = None, *,
                 team: str, name: str, local: Iterable[str], config: zenoh.Config,
                 faults: Faults | None = None):
        super().__init__(loop, record, faults=faults)
        self.team = team
        self.name = name
        self.local = frozenset(local)
        self.inbox: queue.SimpleQueue[tuple[str, str, bytes]] = queue.SimpleQueue()
        self.outbox: list[Message] = []
        self.wire_sent: dict[str, int] = {}
        """Messages published, per link ``"SENDER>TO"`` (the shared clock's accounting)."""
        self.wire_received: dict[str, int] = {}
        self.refused = 0
        self.on_clock: Callable[[Clock], Any] | None = None
        """Told each ``Clock`` message as it is taken (outside the loop's callbacks: a step
        runs what arrived before it at the old time, then moves the clock, so that the
        messages behind it, sent at the new time, are handled at the new time)."""
        self.on_time: Callable[[float], Any] | None = None
        """Told the time a message was sent at, before the message is delivered (a
        member whose clock is behind catches up: a message is never handled before the
        time it was sent, whatever order the network brought it in)."""
        self.on_presence: Callable[[str, bool], Any] | None = None
        """Told ``(name, joined)`` when a process of the team joins or leaves."""
        self.held = False
        """While True, what the loop sends waits in the outbox: a process not yet admitted
        to the team's shared clock says nothing, so that the managers count its messages
        from the moment they know it (:class:`~shary.transport.distributed.Participant`)."""
        self._publishers: dict[tuple[str, str], Any] = {}
        self.session = zenoh.open(config)
        try:
            self._subscribers = [
                self.session.declare_subscriber(key(team, address, "any")[:-3] + "*",
                                                self._arrived)
                for address in sorted(self.local)]
            self._watch = self.session.liveliness().declare_subscriber(
                f"{PREFIX}/{team}/*", self._presence, history=True)
            self._token = self.session.liveliness().declare_token(
                key(team, name, "alive")[:-len("/alive")])
        except BaseException:
            self.session.close()
            raise
        loop.idle_hooks.append(self.flush)

    # -- Zenoh's threads: queue only ------------------------------------------------------

    def _arrived(self, sample: zenoh.Sample) -> None:
        self.inbox.put(("message", str(sample.key_expr), sample.payload.to_bytes()))

    def _presence(self, sample: zenoh.Sample) -> None:
        joined = sample.kind == zenoh.SampleKind.PUT
        self.inbox.put(("join" if joined else "leave", str(sample.key_expr), b""))

    # -- the port ---------------------------------------------------------------------

    def subscribe(self, address: str, handler: Callable[[Message], Any]) -> None:
        """Hold ``address`` here if it is one of this process's (others are remote)."""
        if address in self.local:
            super().subscribe(address, handler)

    def tap(self, address: str, taker: Callable[[Message], bool]) -> None:
        if address in self.local:
            super().tap(address, taker)

    def new_id(self, prefix: str) -> str:
        return f"{prefix}{self.name}.{next(self._ids)}"

    def reaches(self, address: str) -> bool:
        return True  # a remote address may be anywhere on the network

    def route(self, message: Message) -> None:
        if message.to in self.local:
            self.deliver(message)
        else:
            self.outbox.append(message)

    def forward(self, message: Message) -> None:
        """Queue ``message`` for the wire without logging it or faulting it (a copy of a
        log row: :mod:`shary.transport.logshare`)."""
        self.outbox.append(message)

    def publish(self, message: Message) -> None:
        """Put ``message`` on the wire now (the clock's messages do not wait for idle)."""
        payload = encode(message, self.loop.now())
        if len(payload) > MAX_BYTES:  # the receiver would refuse it: say so here
            if self._record is not None and message.kind != LogRecord.kind:
                self._record("message-too-big", agent=message.sender, to=message.to,
                             type=message.kind, size=len(payload))
            return
        route = (message.to, message.kind)
        publisher = self._publishers.get(route)
        if publisher is None:
            publisher = self._publishers[route] = self.session.declare_publisher(
                key(self.team, message.to, message.kind),
                congestion_control=zenoh.CongestionControl.BLOCK)
        publisher.put(payload)
        if message.kind != Clock.kind:
            link = f"{message.sender}>{message.to}"
            self.wire_sent[link] = self.wire_sent.get(link, 0) + 1

    def flush(self) -> None:
        """Publish what the loop sent (an idle hook: after the log's commit), unless
        :attr:`held`."""
        if self.held:
            return
        outbox, self.outbox = self.outbox, []
        for message in outbox:
            self.publish(message)

    def pump(self, timeout: float = 0.0) -> int:
        """Bring what arrived into the loop (waiting up to ``timeout`` s for the first);
        returns how many items were taken.  A step of the shared clock takes effect here,
        in arrival order, so call it from the top of a process's loop (never from a
        callback)."""
        inbox = self.inbox
        try:
            item = inbox.get(timeout=timeout) if timeout > 0 else inbox.get_nowait()
        except queue.Empty:
            return 0
        taken = 0
        while True:
            taken += 1
            self._take(*item)
            try:
                item = inbox.get_nowait()
            except queue.Empty:
                return taken

    def _take(self, what: str, expr: str, payload: bytes) -> None:
        if what != "message":
            who = expr.rsplit("/", 1)[-1]
            if self._record is not None:
                self._record("agent-joined" if what == "join" else "agent-left", agent=who)
            if self.on_presence is not None:
                self.loop.call_soon(self.on_presence, who, what == "join")
            return
        try:
            message, at = decode_timed(payload, key_expr=expr)
        except WireError as exc:
            self.refused += 1
            if self._record is not None:
                self._record("message-refused", key=expr, reason=str(exc),
                             size=len(payload))
            return
        if isinstance(message, Clock):
            if self.on_clock is not None:  # now, not queued: a step moves the clock after
                self.on_clock(message)      # what arrived before it and before what follows
            return
        link = f"{message.sender}>{message.to}"
        self.wire_received[link] = self.wire_received.get(link, 0) + 1
        if at is not None and self.on_time is not None:
            self.on_time(at)
        if not self.faulted(message, self.deliver):  # a bad link delays what arrives too
            self.deliver(message)

    def close(self) -> None:
        """Flush, undeclare and close the session (always: an open one outlives a crash)."""
        try:
            self.flush()
        finally:
            if self.flush in self.loop.idle_hooks:
                self.loop.idle_hooks.remove(self.flush)
            self.session.close()
