"""One event loop, one clock, no threads.

Everything the supervisor does runs as a callback of this loop: executor
reports, fact events, timers, scheme steps.  Work scheduled with
:meth:`EventLoop.call_soon` runs in FIFO order once the current callback has
returned, which gives run-to-completion at the level of the whole supervisor
and a deterministic order for a given seed.

With a :class:`~shary.statechart.clock.SimulatedClock` (headless runs, tests), whoever
drives the world calls :meth:`EventLoop.advance`; with a :class:`WallClock`
(a real robot), :meth:`EventLoop.run_for` sleeps until the next timer in its
*waiter*: by default a :class:`threading.Event` that other threads set, or a
middleware's own wait, so that its callbacks run on the loop's thread (ROS 2:
:class:`shary.ros.node.RosNode` waits in rcl's wait set, and the loop never
imports rclpy).
"""

from __future__ import annotations

import gc
import random
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any, Protocol

from shary.statechart.clock import Clock, SimulatedClock, Timer

MAX_CALLBACKS_PER_DRAIN = 1_000_000
"""Callbacks run without time passing before the loop declares a livelock."""

STEADY_GC_THRESHOLDS = (2000, 100, 10)
"""The cyclic collector's thresholds once a supervisor is settled (CPython's are
(700, 10, 10)).  Each change a supervisor handles leaves a few dozen objects that live
until a later change ends them (a suspended act, its monitor and timer); the collector
scans each survivor in every generation it reaches, and the middle generation's scans
are cache misses over the whole world.  Collecting it ten times less often lets most
survivors die before it looks at them: 15 % of the kernel benchmark's time went to the
collector, 10-11 % with these (docs/benchmarks.md)."""


class WallClock(SimulatedClock):
    """Real time (monotonic seconds since creation), with the same timer heap."""

    def __init__(self) -> None:
        super().__init__()
        self._origin = time.monotonic()

    def now(self) -> float:
        return time.monotonic() - self._origin

    def call_later(self, delay: float, callback: Callable[..., Any], *args: Any) -> Timer:
        self._now = self.now()
        return super().call_later(delay, callback, *args)


class Waiter(Protocol):
    """Where :meth:`EventLoop.run_for` sleeps between timers."""

    def wait(self, timeout: float) -> None:
        """Sleep up to ``timeout`` seconds, less if woken or if work came (work of the
        waiter's own, run on this thread, puts its events with :meth:`EventLoop.call_soon`)."""

    def wake(self) -> None:
        """From any thread: end the current or the next :meth:`wait` now."""


class EventWaiter:
    """The default waiter: a :class:`threading.Event` (a lock acquired with the timeout:
    no polling), set by :meth:`EventLoop.call_soon_threadsafe`."""

    def __init__(self) -> None:
        self._event = threading.Event()

    def wait(self, timeout: float) -> None:
        self._event.wait(timeout)
        # cleared before the loop takes what other threads gave: a wake after this has
        # its work taken now, or wakes the next wait
        self._event.clear()

    def wake(self) -> None:
        self._event.set()


class EventLoop:
    """The supervisor's single-threaded loop: a clock, a FIFO of ready work, a seeded RNG."""

    def __init__(self, clock: Clock | None = None, seed: int = 0):
        self.clock = clock if clock is not None else SimulatedClock()
        self.seed = seed
        self.random = random.Random(seed)
        self._ready: deque[tuple[Callable[..., Any], tuple]] = deque()
        self._soon = self.call_soon  # one bound method for every timer, not one each
        self._settled = False
        self._from_threads: deque[tuple[Callable[..., Any], tuple]] = deque()
        self.waiter: Waiter = EventWaiter()
        """Where :meth:`run_for` sleeps (replaced by a middleware that runs its callbacks
        on this thread: :meth:`shary.ros.node.RosNode.attach`)."""
        self.idle_hooks: list[Callable[[], Any]] = []
        """Called each time the loop becomes idle after work (the context log's flush)."""

    def now(self) -> float:
        return self.clock.now()

    def settle(self) -> None:
        """The world is loaded; what follows is the long run.  Freeze what exists now out
        of the cyclic collector's sight (``gc.freeze()``: it would rescan every live task
        at each full collection) and collect less often (:data:`STEADY_GC_THRESHOLDS`).

        Process-wide, as garbage collection is, so never implicit: the program that owns
        the process calls it once (a robot's main, after loading the world and before
        :meth:`run_for`); a short headless run or a test need not.  Cyclic garbage among
        the frozen objects is never collected: settle after set-up, not between runs."""
        if self._settled:
            return
        self._settled = True
        gc.collect()
        gc.freeze()
        gc.set_threshold(*STEADY_GC_THRESHOLDS)

    def call_soon(self, callback: Callable[..., Any], *args: Any) -> None:
        """Run ``callback(*args)`` after the current callback, in FIFO order."""
        self._ready.append((callback, args))

    def call_later(self, delay: float, callback: Callable[..., Any], *args: Any) -> Timer:
        """Run ``callback(*args)`` ``delay`` seconds from now (cancel with ``.cancel()``)."""
        return self.clock.call_later(delay, self._soon, callback, *args)

    def call_soon_threadsafe(self, callback: Callable[..., Any], *args: Any,
                             wake: bool = True) -> None:
        """From another thread (a console's, a signal handler): run ``callback(*args)`` on
        this loop soon, waking it if it sleeps in :meth:`run_for`
        (with ``wake=False``, the next time it wakes or goes round: news that can wait,
        spared a thread switch).  Such callbacks run in the order they were given, before
        the timers due at the same time.  The only entry that is safe from another thread."""
        self._from_threads.append((callback, args))
        if wake:
            self.waiter.wake()

    def wake(self) -> None:
        """From another thread: wake the loop if it sleeps (to run what was given quietly)."""
        self.waiter.wake()

    def _take_from_threads(self) -> None:
        taken, ready = self._from_threads, self._ready
        while taken:
            ready.append(taken.popleft())

    def run_until_idle(self) -> int:
        """Run ready callbacks until none is left; return how many ran."""
        ran = 0
        ready = self._ready
        if self._from_threads:
            self._take_from_threads()
        while ready:
            callback, args = ready.popleft()
            callback(*args)
            ran += 1
            if ran > MAX_CALLBACKS_PER_DRAIN:
                raise RuntimeError("the event loop never became idle (a livelock?)")
        if ran:
            for hook in self.idle_hooks:
                hook()
        return ran

    def advance(self, seconds: float) -> None:
        """Simulated time: move on ``seconds``, firing timers in order, idle after each."""
        assert isinstance(self.clock, SimulatedClock)
        self.run_until_idle()
        target = self.clock.now() + seconds
        while True:
            due = self.clock.next_due()
            if due is None or due > target:
                break
            self.clock.advance_to(due)
            self.run_until_idle()
        self.clock.advance_to(target)
        self.run_until_idle()

    def run_for(self, seconds: float) -> None:
        """Real time: run for ``seconds``, sleeping between timers in the :attr:`waiter`
        (woken early by :meth:`call_soon_threadsafe`, or by the waiter's own work)."""
        end = self.clock.now() + seconds
        self.run_until_idle()
        while self.clock.now() < end:
            due = self.clock.next_due() if isinstance(self.clock, SimulatedClock) else None
            wake = end if due is None else min(due, end)
            if not self._from_threads:
                self.waiter.wait(max(0.0, wake - self.clock.now()))
            if self._from_threads:  # before the timers now due: a goal's answer that came
                self._take_from_threads()  # before its deadline counts (the waiter's own
                # work is already on the ready queue, before them too)
            if isinstance(self.clock, SimulatedClock):
                self.clock.advance_to(self.clock.now())
            self.run_until_idle()
