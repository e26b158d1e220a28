"""The engine's clock: time and timers, with no threads.

Every timeout of a scheme (``after 10s``) and every delayed send is a timer on
a :class:`Clock`.  Headless runs and tests use :class:`SimulatedClock`, which
only moves when whoever drives the world calls :meth:`SimulatedClock.advance`,
as fast as the CPU allows and in a deterministic order (due time, then the
order timers were set).

The heap holds ``(due, seq, timer)`` tuples: tuples compare in C, where a
:class:`Timer` with ``__lt__`` cost a Python call (and two tuples) per
comparison, and a supervisor with thousands of pending timeouts compares a lot
(every push, every pop, and every rebuild that drops the cancelled ones).
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable
from typing import Any, Protocol


class Timer:
    """A pending call; cancelling it only marks it (it is dropped when due)."""

    __slots__ = ("due", "seq", "callback", "args", "cancelled", "clock")

    def __init__(self, due: float, seq: int, callback: Callable[..., Any], args: tuple,
                 clock: SimulatedClock | None = None):
        self.due = due
        self.seq = seq
        self.callback = callback
        self.args = args
        self.cancelled = False
        self.clock = clock

    def cancel(self) -> None:
        if not self.cancelled:
            self.cancelled = True
            if self.clock is not None:
                self.clock._forget(self)


class Clock(Protocol):
    """What the engine needs of a clock."""

    def now(self) -> float: ...

    def call_later(self, delay: float, callback: Callable[..., Any], *args: Any) -> Timer: ...


class SimulatedClock:
    """A clock that advances only when told to, firing due timers in order."""

    def __init__(self, start: float = 0.0):
        self._now = start
        self._heap: list[tuple[float, int, Timer]] = []
        self._seq = itertools.count()
        self._cancelled = 0

    def now(self) -> float:
        return self._now

    def call_later(self, delay: float, callback: Callable[..., Any], *args: Any) -> Timer:
        due = self._now + delay if delay > 0.0 else self._now
        seq = next(self._seq)
        timer = Timer(due, seq, callback, args, self)
        heapq.heappush(self._heap, (due, seq, timer))
        return timer

    def _forget(self, timer: Timer) -> None:
        """Count a cancelled timer; rebuild the heap when they are most of it.

        Cancelled timers are dropped lazily when due, but a clock that does
        not move (or timeouts far away, cancelled again and again) would let
        them pile up.
        """
        self._cancelled += 1
        if self._cancelled > 256 and self._cancelled * 2 > len(self._heap):
            heap = self._heap  # in place: advance_to holds it while callbacks cancel
            heap[:] = [entry for entry in heap if not entry[2].cancelled]
            heapq.heapify(heap)
            self._cancelled = 0

    def next_due(self) -> float | None:
        """When the next live timer is due, or None when none is pending."""
        heap = self._heap
        while heap and heap[0][2].cancelled:
            heapq.heappop(heap)
            self._cancelled -= 1
        return heap[0][0] if heap else None

    def advance(self, seconds: float) -> int:
        """Move time forward by ``seconds``, firing every timer due meanwhile; return how many."""
        return self.advance_to(self._now + seconds)

    def advance_to(self, when: float) -> int:
        """Move time forward to ``when``, firing every timer due by then; return how many."""
        fired = 0
        heap = self._heap
        while heap and heap[0][0] <= when:
            timer = heapq.heappop(heap)[2]
            if timer.cancelled:
                self._cancelled -= 1
                continue
            self._now = max(self._now, timer.due)
            timer.callback(*timer.args)
            fired += 1
        self._now = max(self._now, when)
        return fired
