"""One owner for the robot's head, arms and voice: requests arbitrated by priority.

Looking is a resource.  The plan manager watches the object of the partner's
next action (:mod:`shary.plans.robot`), a robot action first looks at what it
acts on (:mod:`shary.recognition.execution`), a task looks at the person it
speaks to (the ``inform`` scheme's recipes), and all of them send ``look-at``
requests through the executor port.  Served side by side, two head motions
fight over the same joints and neither ends; served one after the other
without memory, the last one wins for good and the plan's watch is lost (the
robot keeps looking at the person it spoke to and never perceives her place).

:class:`BodyArbiter` sits between :class:`~shary.kernel.executors.ExecutorRegistry`
and the world's executors for the atomic tasks that move the head or an arm, or speak:

* **the head** serves one *aim* at a time, the one of highest priority
  (:attr:`~shary.kernel.executors.Request.priority`: 1 a plan watching, 2 a task's
  step, 3 a robot action's own look) and, among equals, the newest.  An aim
  is *held* as long as whoever asked for it is alive: the node's parent in the
  task tree (the act x task that looks then speaks, the robot action) or the
  node itself when it has no parent.  A request below a held aim waits and is
  served (its result sent) when that aim ends; a request that is superseded
  while the head moves for it is told ``cancelled`` (unless the newer looks at the
  same target: the head goes on, and the newer is served once it is there, so two
  tasks turning to one person never take the head from each other); when a held
  aim ends,
  the head goes back to the best aim still held (the previous aim restored);
* **an arm** runs one motion at a time: a second request waits until the
  first has ended, and is told ``cancelled`` if it is cancelled meanwhile;
* **the voice** says one sentence at a time, in the same way: two tasks that speak
  at once (a person's request answered while an inform is said, a goodbye while a
  give-up's reason is said) would talk over each other, so the later sentence waits
  until the earlier one has been said.

Every decision is a ``body`` row of the context log (``part``, ``action``:
serve, wait, supersede, restore, release; ``target``, ``priority``,
``owner``), so that where the head looked, and why, can be read after a run.
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from shary.kernel.executors import Outcome, Reporter, Request
from shary.kernel.tasktree import ACT as ACT_NODE
from shary.kernel.tasktree import FINISHED

__all__ = ["ACT", "ARM_TASKS", "HEAD_TASKS", "TASK", "VOICE_TASKS", "WATCH", "BodyArbiter"]

WATCH, TASK, ACT = 1, 2, 3
"""Request priorities: a plan watching, a task's step (look at the person spoken to), a
robot action's own look (held while the action runs: the robot sees what it moves, and
perceives the effect it then reports)."""
HEAD_TASKS = frozenset({"look-at"})
ARM_TASKS = frozenset({"move-arm", "pick", "place", "dump", "give", "put-back"})
"""The core library's atomic tasks that move the arm (recipes/core.yaml)."""
VOICE_TASKS = frozenset({"speak"})
SERIAL_PARTS = {**dict.fromkeys(ARM_TASKS, "arm"), **dict.fromkeys(VOICE_TASKS, "voice")}
"""The parts that serve one request at a time, first come first served, by atomic task."""


@dataclass
class _Aim:
    request: Request
    reporter: Reporter | None  # None: a restore of the arbiter's own, nobody waits
    owner: str | None  # the node whose life holds the aim; None: held until reached
    seq: int
    waiting: bool = True  # the requester has not had its result yet
    logged: bool = False  # its wait is in the log

    @property
    def key(self) -> tuple[int, int]:
        return (self.request.priority, self.seq)


class BodyArbiter:
    """Arbitrates the head, the arms and the voice (see the module's documentation).

    ``tree`` is the supervisor's task tree (whose nodes own the aims), ``loop``
    its event loop and ``record`` its log.
    """

    def __init__(self, tree: Any, loop: Any, record: Callable[..., Any]):
        self.tree = tree
        self.loop = loop
        self.record = record
        self._seq = itertools.count(1)
        self._aims: dict[str, _Aim] = {}  # owner (or request id) -> its latest aim
        # Kept beside the aims so that serving costs the same however many are held (a
        # supervisor with thousands of tasks, benchmarks/kernel.py): the aims by key in a
        # heap (stale entries skipped), the aims that may have ended since the last serve,
        # the waiting aims whose wait is not logged yet, and each request's aim's key.
        self._heap: list[tuple[int, int, int, str, _Aim]] = []
        self._pushes = itertools.count()
        self._suspects: dict[str, None] = {}
        self._unlogged: dict[str, _Aim] = {}
        self._keys: dict[str, str] = {}
        self._moving: _Aim | None = None  # the aim the head moves for
        self._reached: _Aim | None = None  # the aim the head last reached
        self._told: set[str] = set()  # requests already answered (superseded)
        self._head: Any = None
        self._serial = {part: _Serial(part, record, loop) for part in set(SERIAL_PARTS.values())}
        self._ports: dict[int, _Port] = {}
        self._reporter = Reporter(self._head_outcome, loop.call_soon)
        tree.watchers.append(self._node_changed)

    def port(self, atomic: str, inner: Any) -> Any:
        """The executor the registry hands out for ``atomic`` (``inner`` behind it)."""
        if atomic not in HEAD_TASKS and atomic not in SERIAL_PARTS:
            return inner
        found = self._ports.get(id(inner))
        if found is None:
            found = self._ports[id(inner)] = _Port(self, inner)
        return found

    # -- the head -----------------------------------------------------------------------

    def _owner(self, request: Request) -> str | None:
        """A task's step is held by its act x task (it looks, then speaks); a plan's
        node or a robot action by the node itself; a node outside the tree until the
        head has turned."""
        if request.node not in self.tree:
            return None
        parent = self.tree.parent(request.node)
        if parent is not None and self.tree.node(parent).get("kind") == ACT_NODE:
            return parent
        return request.node

    def _alive(self, aim: _Aim) -> bool:
        if aim.owner is None:
            return aim.waiting
        return aim.owner in self.tree and self.tree.state(aim.owner) not in FINISHED

    def look(self, request: Request, reporter: Reporter, inner: Any) -> None:
        self._head = inner
        owner = self._owner(request)
        key = owner if owner is not None else request.id
        old = self._aims.pop(key, None)
        if old is not None and old.waiting:
            self._drop(old, "superseded by a newer request of the same task")
        self._hold(key, _Aim(request, reporter, owner, next(self._seq)))
        self._serve()

    def _hold(self, key: str, aim: _Aim) -> None:
        self._aims[key] = aim
        heapq.heappush(self._heap, (-aim.request.priority, -aim.seq, -next(self._pushes),
                                    key, aim))
        self._keys[aim.request.id] = key
        if aim.waiting:
            self._unlogged[key] = aim
        if not self._alive(aim):
            self._suspects[key] = None

    def _find(self, request: Request) -> tuple[str | None, _Aim | None]:
        """The key and aim of ``request``, if it is still held."""
        key = self._keys.get(request.id)
        aim = self._aims.get(key) if key is not None else None
        if aim is None or aim.request is not request:
            self._keys.pop(request.id, None)
            return None, None
        return key, aim

    def _log(self, action: str, aim: _Aim, **extra: Any) -> None:
        self.record("body", task=aim.request.node, agent=aim.request.agent, part="head",
                    action=action, target=str(aim.request.args.get("target")),
                    priority=aim.request.priority, owner=aim.owner, **extra)

    def _best(self) -> _Aim | None:
        suspects, self._suspects = self._suspects, {}
        for key in suspects:
            aim = self._aims.get(key)
            if aim is None or self._alive(aim):
                continue
            del self._aims[key]
            if aim.owner is not None:
                self._log("release", aim)
            if aim.waiting:
                self._drop(aim, "its task ended before the head was free")
        heap = self._heap
        while heap and self._aims.get(heap[0][3]) is not heap[0][4]:
            heapq.heappop(heap)
        return heap[0][4] if heap else None

    def _serve(self) -> None:
        best = self._best()
        if best is None:
            return
        for key, aim in list(self._unlogged.items()):
            if self._aims.get(key) is not aim or not aim.waiting or aim.logged:
                del self._unlogged[key]
            elif aim is not best and aim.key < best.key:
                del self._unlogged[key]
                aim.logged = True
                self._log("wait", aim, behind=best.owner)
        if best is self._moving:
            return
        if self._moving is not None and self._moving.waiting and \
                self._moving.request.args.get("target") == best.request.args.get("target"):
            return  # the head goes there already: the newer is served once it is there
        if self._moving is not None:
            moving = self._moving
            self._moving = None
            self._log("supersede", moving, by=str(best.request.args.get("target")))
            self._told.add(moving.request.id)  # what the executor reports is not news
            if moving.waiting and moving.reporter is not None:
                moving.waiting = False
                self._suspects[self._keys.get(moving.request.id, "")] = None
                moving.reporter.cancelled(moving.request, "superseded: the head was needed "
                                          f"for {best.request.args.get('target')}")
            self._head.cancel(moving.request)
            self._reached = None
        if best is self._reached:
            return  # the head is there already
        if not best.waiting:  # a held aim the head left: go back to it
            request = best.request
            restore = Request(f"{request.id}+", request.atomic, request.args, request.agent,
                              request.node, request.priority)
            best = _Aim(restore, None, best.owner, best.seq, False)
            self._hold(best.owner if best.owner is not None else restore.id, best)
            self._log("restore", best)
        else:
            self._log("serve", best)
        self._moving, self._reached = best, None
        self._head.start(best.request, self._reporter)

    def _head_outcome(self, outcome: Outcome) -> None:
        request = outcome.request
        if self._moving is not None and self._moving.request is request:
            self._moving = None
        if request.id in self._told:
            self._told.discard(request.id)
            return
        key, aim = self._find(request)
        if aim is None or key is None:
            return
        if outcome.status == "done":
            self._reached = aim
        if aim.waiting and aim.reporter is not None:
            _report(aim.reporter, outcome)
        aim.waiting = False
        self._suspects[key] = None
        if outcome.status != "done" or aim.owner is None:
            del self._aims[key]  # it could not look there, or nothing holds it: no way back
        self.loop.call_soon(self._serve)

    def _drop(self, aim: _Aim, reason: str) -> None:
        if aim.reporter is not None and aim.waiting:
            aim.waiting = False
            self._told.add(aim.request.id)
            aim.reporter.cancelled(aim.request, reason)
        if self._moving is aim:
            self._moving = None
            self._head.cancel(aim.request)
        else:
            self._told.discard(aim.request.id)

    def cancel_look(self, request: Request) -> None:
        key, aim = self._find(request)
        if aim is not None and key is not None:
            del self._aims[key]
            self._drop(aim, "cancelled")
            self.loop.call_soon(self._serve)

    def _node_changed(self, node: str, state: str) -> None:
        if state in FINISHED and node in self._aims:
            self._suspects[node] = None
            self.loop.call_soon(self._serve)

    # -- the arms and the voice ------------------------------------------------------

    def serial(self, atomic: str) -> _Serial:
        """The part that serves ``atomic``'s requests one at a time (an arm, the voice)."""
        return self._serial[SERIAL_PARTS[atomic]]


class _Serial:
    """A part that serves one request at a time: a second waits until the first has
    ended, and is told ``cancelled`` if it is cancelled meanwhile."""

    def __init__(self, part: str, record: Callable[..., Any], loop: Any):
        self.part = part
        self.record = record
        self.loop = loop
        self.queue: dict[str, tuple[Request, Any]] = {}
        """Requests waiting (and their executor), by request id, oldest first: a dict, so
        that a cancel or the next start costs the same however many wait (a supervisor
        with thousands of tasks, benchmarks/kernel.py)."""
        self.busy: Request | None = None
        """The request the part serves: begun, or served and about to begin."""
        self.begun = False
        self.requesters: dict[str, Reporter] = {}
        self.reporter = Reporter(self._outcome, loop.call_soon)

    def start(self, request: Request, reporter: Reporter, inner: Any) -> None:
        self.requesters[request.id] = reporter
        if self.busy is None:
            self.busy, self.begun = request, False
            self._begin(request, inner)
        else:
            self.record("body", task=request.node, agent=request.agent, part=self.part,
                        action="wait", atomic=request.atomic, behind=self.busy.id)
            self.queue[request.id] = (request, inner)

    def _begin(self, request: Request, inner: Any) -> None:
        if self.busy is not request or self.begun:
            return  # cancelled after it was served, before it began
        self.begun = True
        self.requesters[request.id].begun(request)
        inner.start(request, self.reporter)

    def _outcome(self, outcome: Outcome) -> None:
        if self.busy is not None and self.busy.id == outcome.request.id:
            self.busy = None
        reporter = self.requesters.pop(outcome.request.id, None)
        if reporter is not None:
            _report(reporter, outcome)
        self._next()

    def _next(self) -> None:
        if self.busy is not None or not self.queue:
            return
        request, inner = self.queue.pop(next(iter(self.queue)))
        self.record("body", task=request.node, agent=request.agent, part=self.part,
                    action="serve", atomic=request.atomic)
        self.busy, self.begun = request, False
        # it begins once the outcome just reported is delivered: the log says the
        # earlier sentence ended before the next one begins
        self.loop.call_soon(self._begin, request, inner)

    def cancel(self, request: Request, inner: Any) -> None:
        if request.id in self.queue or (self.busy is request and not self.begun):
            self.queue.pop(request.id, None)
            if self.busy is request:
                self.busy = None
            self.requesters.pop(request.id).cancelled(
                request, f"cancelled before the {self.part} was free")
            self._next()
            return
        inner.cancel(request)


def _report(reporter: Reporter, outcome: Outcome) -> None:
    if outcome.status == "done":
        reporter.done(outcome.request, **outcome.result)
    elif outcome.status == "failed":
        reporter.failed(outcome.request, outcome.reason)
    else:
        reporter.cancelled(outcome.request, outcome.reason)


class _Port:
    """What the registry hands out in place of an executor that moves the head or an arm,
    or speaks."""

    tells_begun = True
    """A request may wait here: the port tells its reporter when it begins."""

    def __init__(self, arbiter: BodyArbiter, inner: Any):
        self.arbiter = arbiter
        self.inner = inner

    def start(self, request: Request, reporter: Reporter) -> None:
        if request.atomic in HEAD_TASKS:
            reporter.begun(request)  # a look is one aim among others from its request on
            self.arbiter.look(request, reporter, self.inner)
        else:
            self.arbiter.serial(request.atomic).start(request, reporter, self.inner)

    def cancel(self, request: Request) -> None:
        if request.atomic in HEAD_TASKS:
            self.arbiter.cancel_look(request)
        else:
            self.arbiter.serial(request.atomic).cancel(request, self.inner)

