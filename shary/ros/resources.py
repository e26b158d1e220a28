"""One goal at a time per part of the robot, and per action server.

A real robot's action servers are mostly single-goal: Nav2's ``navigate_to_pose``
takes a new goal by aborting the one it runs, so two tasks that each send the
base a goal leave the base with one of them and shary not knowing which.
:class:`Resources` sits in front of the servers (:class:`~shary.ros.executors.RosExecutors`
asks it before a goal is sent): each goal *uses* the parts of the robot its task's
binding names (``resources:``, by default ``base`` for navigate, ``arm`` for the arm's
tasks, ``head`` for look-at, ``voice`` for speak) and, for an action, its server.
A goal whose parts are free is sent at once; otherwise, with the rules of the body's
arbiter of a simulated robot (:mod:`shary.kernel.arbiter`):

* a goal of higher priority (:attr:`~shary.kernel.executors.Request.priority`) than every goal
  holding the parts it needs *preempts* them: each is told ``cancelled`` (reason
  ``preempted``) and cancelled at its server, and the new goal is sent once the
  server has answered (its result came, or the ``cancel`` deadline passed): never two
  goals on one single-goal server;
* any other goal *waits* (higher priority first, then first come) and is sent when the
  parts are free; cancelled meanwhile, it is told ``cancelled`` and never sent.

A part is held until its goal is over at the server: the result came, or a cancel went
unanswered past its deadline.  Every decision is a ``ros-resource`` row of the context
log (``action``: wait, preempt, serve; the parts; who holds them).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any


class Resources:
    """Who holds each part of the robot, and which goals wait (see the module's docstring).

    A goal is anything with a ``request`` (:class:`~shary.kernel.executors.Request`) and a
    ``needs`` tuple of parts; ``start(goal)`` sends it, ``preempt(goal, reason)``
    cancels one that holds a part a goal of higher priority needs."""

    def __init__(self, start: Callable[[Any], Any], preempt: Callable[[Any, str], Any],
                 record: Callable[..., Any]):
        self.start = start
        self.preempt = preempt
        self.record = record
        self.holders: dict[str, Any] = {}
        """Part -> the goal that holds it."""
        self._waiting: dict[int, Any] = {}
        """Goals waiting for parts, by order of arrival."""
        self._seq = itertools.count()
        self._order: dict[int, int] = {}

    def admit(self, goal: Any) -> None:
        """Send ``goal`` now if its parts are free; else make it wait, preempting the
        holders when it outranks them all."""
        busy = self._blocking(goal)
        if not busy:
            self._hold(goal)
            self.start(goal)
            return
        seq = next(self._seq)
        self._waiting[seq] = goal
        self._order[id(goal)] = seq
        priority = goal.request.priority
        held = sorted({part for part in goal.needs if part in self.holders})
        if all(priority > other.request.priority for other in busy):
            self._row(goal, "preempt", held, busy)
            for other in busy:
                self.preempt(other, f"preempted: {', '.join(held)} needed by "
                             f"{goal.request.atomic} of {goal.request.node} (priority "
                             f"{priority} over {other.request.priority})")
        else:
            self._row(goal, "wait", held, busy)

    def withdraw(self, goal: Any) -> bool:
        """Take ``goal`` out of the wait (cancelled before it was sent); whether it
        waited."""
        seq = self._order.pop(id(goal), None)
        if seq is None:
            return False
        del self._waiting[seq]
        return True

    def release(self, goal: Any) -> None:
        """``goal`` is over at its server: its parts go to the goals that wait, best
        first."""
        freed = [part for part, holder in self.holders.items() if holder is goal]
        for part in freed:
            del self.holders[part]
        if freed:
            self._serve()

    def waiting(self) -> list[Any]:
        """The goals that wait, in order of arrival."""
        return list(self._waiting.values())

    def _serve(self) -> None:
        for seq, goal in sorted(self._waiting.items(),
                                key=lambda item: (-item[1].request.priority, item[0])):
            if seq in self._waiting and not self._blocking(goal):
                del self._waiting[seq]
                self._order.pop(id(goal), None)
                self._hold(goal)
                self._row(goal, "serve", list(goal.needs), [])
                self.start(goal)

    def _blocking(self, goal: Any) -> list[Any]:
        found: dict[int, Any] = {}
        for part in goal.needs:
            holder = self.holders.get(part)
            if holder is not None and holder is not goal:
                found[id(holder)] = holder
        return list(found.values())

    def _hold(self, goal: Any) -> None:
        for part in goal.needs:
            self.holders[part] = goal

    def _row(self, goal: Any, action: str, parts: list[str], holders: list[Any]) -> None:
        request = goal.request
        self.record("ros-resource", task=request.node, agent=request.agent,
                    request=request.id, atomic=request.atomic, action=action, parts=parts,
                    priority=request.priority,
                    holders=[h.request.id for h in holders] or None)
