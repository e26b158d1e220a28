"""A team spread over processes: the conductor (managers and shared clock) and members.

``shary team up`` runs the :class:`Conductor`: the Task, Resource and
Interaction Managers, the software agents, and the team's simulated clock, in
a Zenoh router listening on loopback.  ``shary agent NAME`` runs a
:class:`Member`: one agent of the team file in its own process, with its own
loop, clock and context log (``LOGDIR/NAME.sqlite``), a Zenoh client of the
conductor.  Both build the same :class:`~shary.team.team.Team` from the team
file; each process holds only its own addresses on the port, so the other
members' objects are shadows (the Task Manager's view of who holds what).
In a team with robots, the world (``shary world SCENARIO``, in ``sim``) is a
member too: both it and :class:`Member` are :class:`Participant` of the clock.

**The shared simulated clock** is a barrier: the conductor tells every member
to advance to time *t* (``Clock`` ``step``); each member runs its timers up to
*t* and everything that arrives, and reports ``idle`` with its message counts
and its next timer.  The conductor moves on, to the earliest next timer of
anyone, only when every live member is idle at *t* and every message sent to
a live address has been received there.  So a message sent at *t* is handled
at *t*, in whatever process, as in one process, and a run with fixed delays
gives the in-process run's events at the same times.  ``pace`` makes a
simulated second last that many wall seconds (``0``: as fast as possible).

**Faults**: a member whose process dies leaves (its liveliness token goes
within milliseconds of a kill -9, within the lease of a freeze); the Task
Manager takes its task back (``agent-lost``) and offers it to another; the
clock no longer waits for it, and when nothing else can happen the run waits
(``rejoin_wait``) for it to come back.  A member that joins later (a restart)
is told the current state (:mod:`shary.transport.rejoin`: the State is its
first step of the clock) and takes part from then on.

**Log records**: a member forwards its log's rows to the managers
(:mod:`shary.transport.logshare`); :attr:`Conductor.records` is the team's
merged view, live.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from shary.kernel.loop import EventLoop
from shary.team.world import WORLD
from shary.transport.facts import SUBSCRIBE
from shary.transport.logshare import LOGS, Forwarder, SharedLog, TeamRecords
from shary.transport.messages import Act, Clock, Message, State
from shary.transport.port import Faults
from shary.transport.rejoin import learn, state_for
from shary.transport.zenohport import LOOPBACK, Settings, ZenohPort, session_config

CLOCK = "clock"
"""The shared clock's address, in the conductor's process."""
CONDUCTOR = "managers"
"""The conductor's process name (its liveliness token, its log file)."""
MANAGERS = ("tasks", "interaction", CLOCK, LOGS)
WAIT = 0.2
"""Seconds a process waits for a message before looking around again."""
DRAIN = 2.0
"""Wall seconds the managers wait, once the run is over, for what is still on its way."""
STALL = 10.0
"""Wall seconds the clock waits at one time before it says what for (a ``clock-waiting``
row, on the display): a member busy for long, or a count that can never balance."""


def agent_log(logdir: Path | None, name: str, seed: int) -> Any:
    """The context log of process ``name`` in ``logdir`` (None without a folder); a
    restarted process writes a new file beside its first life's."""
    if logdir is None:
        return None
    from shary.log.contextlog import ContextLog

    logdir.mkdir(parents=True, exist_ok=True)
    path, n = logdir / f"{name}.sqlite", 1
    while path.exists():  # a restart keeps the log of the process that died
        path, n = logdir / f"{name}.{n}.sqlite", n + 1
    return ContextLog(path, seed=seed)


class Participant:
    """One process on the team's shared clock: it advances when the conductor says and
    reports when it is idle (see the module's docstring).  :class:`Member` is an agent
    of the team file; the world (``shary world``) is another."""

    def __init__(self, name: str, loop: EventLoop, port: ZenohPort, log: Any):
        self.name = name
        self.loop = loop
        self.port = port
        self.log = log
        port.on_clock = self._clock
        port.on_time = self._sent_at
        port.on_presence = self._presence
        port.held = True  # until admitted: see _admitted
        self.at: float | None = None
        """The time of the last step (None before the first)."""
        self.stopped: str | None = None

    def _sent_at(self, at: float) -> None:
        """A message sent at ``at`` arrived before the step to ``at`` did (it came by
        another path): move to ``at`` first, as the step will (the conductor steps to
        the earliest thing anyone has to do, so nothing here is due before it)."""
        if self.at is not None and at > self.loop.now():
            self.loop.advance(at - self.loop.now())
            self.at = at

    def start(self) -> None:
        """The run begins (the first step, at the team's current time)."""

    def _admitted(self) -> None:
        """The first step of the clock (or, on a restart, the State) came: the managers
        know this process, so what it has to say goes out now.  Before, it stays held: a
        restarted process's first log rows, counted by the managers before they learn of
        its new life, would leave the clock waiting forever for a message it already
        has."""
        self.port.held = False

    def _presence(self, name: str, joined: bool) -> None:
        if name == CONDUCTOR and not joined:
            self.stopped = "the managers left"

    def _clock(self, message: Clock) -> None:
        if message.state == "stop":
            self.stopped = message.reason or "stopped"
            return
        if message.state != "step":
            return
        loop = self.loop
        if self.at is None:
            loop.clock.advance_to(message.time)
            self._admitted()
            self.start()
        elif message.time > loop.now():
            loop.advance(message.time - loop.now())
        self.at = message.time

    def run(self) -> str:
        """Take part until the conductor stops the run (or it vanishes); the reason."""
        port, loop = self.port, self.loop
        try:
            while self.stopped is None:
                took = port.pump(WAIT)
                loop.run_until_idle()
                port.flush()
                if took and self.at is not None and self.stopped is None:
                    port.publish(Clock(self.name, CLOCK, state="idle", time=self.at,
                                       sent=dict(port.wire_sent),
                                       received=dict(port.wire_received),
                                       next=loop.clock.next_due()))
            return self.stopped
        finally:
            self.close()

    def close(self) -> None:
        _close(self.port, self.log)


class Member(Participant):
    """One agent of a team file in this process (see the module's docstring).  In a team
    with robots, the world agent performs the robots' atomic tasks and the on-site
    people's work (:func:`shary.team.world.connect_world`), and a robot subscribes to the
    facts the world perceives."""

    def __init__(self, spec: Any, name: str, *, connect: str = LOOPBACK,
                 logdir: Path | None = None, seed: int = 0, faults: Faults | None = None,
                 share_log: bool = True, settings: Settings | None = None):
        from shary.team import Team
        from shary.team.spec import ROBOT
        from shary.team.world import connect_world

        if name not in spec.agents:
            raise KeyError(name)
        log = agent_log(logdir, name, seed)
        self.forwarder = Forwarder(name) if share_log else None
        """Sends the log's rows to the managers (None: ``share_log`` off)."""
        ports: list[ZenohPort] = []

        def port(loop: EventLoop, record: Callable[..., None]) -> ZenohPort:
            ports.append(ZenohPort(loop, record, team=spec.name, name=name, local=[name],
                                   config=session_config(mode="client", connect=[connect],
                                                         settings=settings),
                                   faults=faults))
            return ports[0]

        self.team = Team(spec, log=SharedLog(log, self.forwarder) if self.forwarder else log,
                         port=port)
        self.team.loop.random.seed(seed)
        super().__init__(name, self.team.loop, ports[0], log)
        if self.forwarder is not None:
            self.forwarder.attach(self.port)
        self.robot = spec.agents[name].kind == ROBOT
        if spec.of_kind(ROBOT):
            connect_world(self.team)
        self.port.tap(name, self._rejoined)

    def start(self) -> None:
        self._subscribe()
        starting = getattr(self.team.agents[self.name], "start_script", None)
        if starting is not None:
            starting()

    def _subscribe(self) -> None:
        """A robot asks the world for its facts: all of them now, then each change."""
        if self.robot:
            self.port.send(Act(self.name, WORLD, act=SUBSCRIBE))

    def _rejoined(self, state: Message) -> bool:
        """A State (this process joined a running team) is the process's to take in: the
        managers' view, whose time is our first step (the person's own script does not
        start again; a robot asks the world for its facts).  The rest is the agent's."""
        if not isinstance(state, State):
            return False
        loop = self.loop
        first = self.at is None
        if first:
            loop.clock.advance_to(state.time)
            self._admitted()
        elif state.time > loop.now():
            loop.advance(state.time - loop.now())
        self.at = max(self.at or 0.0, state.time)
        learn(self.team, self.name, state)
        if first:
            self._subscribe()
        return True


class Conductor:
    """The managers and the shared clock (see the module's docstring)."""

    def __init__(self, spec: Any, *, listen: str = LOOPBACK, logdir: Path | None = None,
                 seed: int = 0, members: list[str] | None = None, pace: float = 0.0,
                 faults: Faults | None = None, settings: Settings | None = None,
                 rejoin_wait: float = 30.0,
                 display: Callable[[str, dict[str, Any]], Any] | None = None):
        from shary.team import Team
        from shary.team.spec import ROBOT, SOFTWARE

        world = [WORLD] if spec.of_kind(ROBOT) else []  # the robots' world is a member too
        self.members = list(members if members is not None else
                            [*(a.name for a in spec.agents.values() if a.kind != SOFTWARE),
                             *world])
        local = [*MANAGERS, *(a for a in spec.agents if a not in self.members)]
        self.log = agent_log(logdir, CONDUCTOR, seed)
        self.display = display or (lambda what, data: None)
        ports: list[ZenohPort] = []

        def port(loop: EventLoop, record: Callable[..., None]) -> ZenohPort:
            ports.append(ZenohPort(loop, self._record(record), team=spec.name,
                                   name=CONDUCTOR, local=local,
                                   config=session_config(mode="router", listen=[listen],
                                                         settings=settings),
                                   faults=faults))
            return ports[0]

        self.records = TeamRecords()
        """The team's logs merged, live: our rows and the rows the members forward."""
        self.team = Team(spec, log=SharedLog(self.log, self.records.tap(CONDUCTOR)),
                         port=port)
        self.team.record = self._record(self.team.record)  # type: ignore[method-assign]
        self.team.loop.random.seed(seed)
        self.port = ports[0]
        self.port.on_clock = self._idle
        self.port.on_presence = self._presence
        self.port.subscribe(LOGS, self.records.handle)
        self.pace = pace
        self.rejoin_wait = rejoin_wait
        """Wall seconds the run waits for a lost member when nothing else can happen."""
        self.live: set[str] = set()
        self.reports: dict[str, Clock] = {}
        self.lost: list[str] = []
        self.offsets: dict[str, int] = {}
        """Per link, sent - received left over from a member's earlier life (a restart)."""
        self.halted: str | None = None
        """Why the run cannot go on (the world left: nobody performs the robots' tasks)."""
        self.gate: Callable[[float, float], float] | None = None
        """Asked ``(now, next)`` before each step of the clock, when everyone is idle: the
        wall seconds to hold (an operator's pause, the console's speed; the run looks
        again after them, since the gate may have acted on the team), or 0 to step."""

    def _record(self, record: Callable[..., None]) -> Callable[..., None]:
        """The team's record, shown on the display too (the rows worth a line)."""
        shown = {"agent-joined", "agent-left", "agent-lost", "task-running", "task-done",
                 "task-failed", "goal-over", "message-refused", "question", "answer",
                 "rejoined", "waiting-for-members", "clock-waiting"}

        def both(kind: str, **data: Any) -> None:
            record(kind, **data)
            if kind in shown and data.get("agent") != CONDUCTOR:
                self.display(kind, {k: v for k, v in data.items() if v is not None})
        return both

    # -- members -------------------------------------------------------------------

    def _presence(self, name: str, joined: bool) -> None:
        if name not in self.members:
            return
        if joined:
            self.live.add(name)
            if self.team.tasks.started:  # a restart: its counts start again from zero
                sent, received = self._totals()
                for link in sent.keys() | received.keys():
                    if name in link.split(">"):
                        self.offsets[link] = sent.get(link, 0) - received.get(link, 0)
                if name in self.team.agents:
                    self._rejoin(name)
                else:  # the world: it starts from the team's time
                    self._tell(name, self.team.loop.now())
        else:
            self.live.discard(name)
            self.reports.pop(name, None)
            self.lost.append(name)
            if name == WORLD:
                self.halted = "the world left"
            if name in self.team.agents:
                self.team.tasks.agent_lost(name)
                self.team.interaction.agent_lost(name)

    def _rejoin(self, name: str) -> None:
        """``name`` came back while the goal runs: tell it the state (its first step of
        the clock), then offer it work."""
        messages = state_for(self.team, name, self.records)
        state = messages[0]
        assert isinstance(state, State)
        holds = sorted(t for t, row in state.tasks.items() if row["agent"] == name)
        self.team.record("rejoined", agent=name, at=state.time, tasks=len(state.tasks),
                         done=sum(row["state"] == "done" for row in state.tasks.values()),
                         holds=holds or None, questions=len(state.questions))
        for message in messages:
            self.port.send(message)
        self.team.tasks.agent_back(name)
        self.team.interaction.agent_back(name)

    def _idle(self, message: Clock) -> None:
        if message.state == "idle" and message.sender in self.live:
            self.reports[message.sender] = message

    def _tell(self, name: str, at: float) -> None:
        self.port.publish(Clock(CLOCK, name, state="step", time=at))

    def _balanced(self, at: float) -> bool:
        return self._waiting(at) is None

    def _waiting(self, at: float) -> str | None:
        """What the clock waits for before it steps from ``at`` (None: nothing): every
        live member idle at ``at``, every message between live addresses received
        (counted per link: what a lost member sent, or was sent, is not waited for)."""
        if self.port.outbox or self.port.inbox.qsize():
            return "the managers' own messages"
        for m in self.live:
            report = self.reports.get(m)
            if report is None or report.time != at:
                return f"{m} to be idle at {at:g} s"
        sent, received = self._totals()
        alive = self.live | self.port.local
        for link in sent.keys() | received.keys():
            source, _, target = link.partition(">")
            if (source in alive and target in alive
                    and sent.get(link, 0) - received.get(link, 0) != self.offsets.get(link, 0)):
                return (f"{link}: {sent.get(link, 0)} sent, {received.get(link, 0)} "
                        f"received, {self.offsets.get(link, 0)} of an earlier life")
        return None

    def _totals(self) -> tuple[dict[str, int], dict[str, int]]:
        """Messages sent and received per link, by everyone live, as last reported."""
        sent: dict[str, int] = dict(self.port.wire_sent)
        received: dict[str, int] = dict(self.port.wire_received)
        for name in self.live:
            report = self.reports.get(name)
            if report is not None:
                for link, n in report.sent.items():
                    sent[link] = sent.get(link, 0) + n
                for link, n in report.received.items():
                    received[link] = received.get(link, 0) + n
        return sent, received

    # -- running --------------------------------------------------------------------

    def wait_for_members(self, timeout: float) -> list[str]:
        """Wait until every member has joined; the ones still missing after ``timeout``."""
        end = time.monotonic() + timeout
        while not self.live.issuperset(self.members) and time.monotonic() < end:
            self.port.pump(WAIT)
            self.team.loop.run_until_idle()
        return sorted(set(self.members) - self.live)

    def run(self, limit: float, *, settle: bool = False) -> str | None:
        """Run the goal on the shared clock until it is over or ``limit`` simulated seconds
        have passed; the goal's outcome ("done", "failed") or None.  ``settle``: once the
        goal is over, go on until nobody has anything left to do (the world's last motion,
        a question's expiry), as a scenario run in one process does."""
        team, port, loop = self.team, self.port, self.team.loop
        if WORLD in self.members:  # the world's facts: poses for the spatial reasoner and
            port.send(Act(team.tasks.address, WORLD, act=SUBSCRIBE))  # the distances
        team.tasks.start()
        start = time.monotonic()
        stalled: float | None = None
        at = loop.now()
        for name in self.live:
            self._tell(name, at)
        try:
            waiting: float | None = None  # since when the clock waits at ``at`` (wall)
            said = False
            while (team.tasks.outcome is None or settle) and self.halted is None:
                port.pump(WAIT if not self._balanced(at) else 0.0)
                loop.run_until_idle()
                port.flush()
                if (why := self._waiting(at)) is not None:
                    waiting = waiting or time.monotonic()
                    if not said and time.monotonic() - waiting >= STALL:
                        team.record("clock-waiting", at=at, why=why, seconds=STALL)
                        said = True
                    continue
                waiting, said = None, False
                dues = [r.next for r in self.reports.values() if r.next is not None]
                own = loop.clock.next_due()
                if own is not None:
                    dues.append(own)
                missing = sorted(set(self.members) - self.live)
                if not dues and missing:  # only a lost member can go on: wait for it
                    if stalled is None:
                        stalled = time.monotonic()
                        team.record("waiting-for-members", missing=missing,
                                    within=self.rejoin_wait)
                    if time.monotonic() - stalled < self.rejoin_wait:
                        port.pump(WAIT)
                        continue
                stalled = None
                if not dues or min(dues) > limit:
                    break
                if self.gate is not None and (hold := self.gate(at, min(dues))) > 0:
                    port.pump(hold)
                    continue
                if self.pace and self._paced(start + min(dues) * self.pace):
                    continue  # something happened meanwhile (a member left …): look again
                at = min(dues)
                for name in self.live:  # the step first: what we send at ``at`` comes after
                    self._tell(name, at)
                loop.advance(at - loop.now())
                port.flush()
            self._drain(at)
            return team.tasks.outcome
        finally:
            for name in self.members:
                port.publish(Clock(CLOCK, name, state="stop",
                                   reason=team.tasks.outcome or "time is up"))

    def _drain(self, at: float) -> None:
        """The run is over: take in what is still on its way at ``at`` (the members' last
        log rows, a reply sent with the one that ended the goal) before they are told to
        stop, for :data:`DRAIN` seconds at most (a member gone silent is not waited for)."""
        end = time.monotonic() + DRAIN
        while not self._balanced(at) and time.monotonic() < end:
            self.port.pump(WAIT / 4)
            self.team.loop.run_until_idle()
            self.port.flush()

    def _paced(self, deadline: float) -> bool:
        """Wait for the wall clock to reach ``deadline``, handling what arrives meanwhile
        (a member that leaves is noticed at once, not after the wait); True if the wait
        was cut short by work."""
        port, loop = self.port, self.team.loop
        while (left := deadline - time.monotonic()) > 0:
            if port.pump(min(left, WAIT)) and loop.run_until_idle():
                port.flush()
                return True
        return False

    def close(self) -> None:
        _close(self.port, self.log)


def _close(port: Any, log: Any) -> None:
    """Close a process's port, then its log even if the port's close failed: the log
    holds what was acknowledged, and must reach the disk whatever happened to Zenoh."""
    try:
        port.close()
    finally:
        if log is not None:
            log.close()
