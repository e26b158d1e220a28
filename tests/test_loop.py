"""The event loop and clocks: FIFO order, timers in order, idle hooks, real time."""

from __future__ import annotations

from shary.kernel.loop import STEADY_GC_THRESHOLDS, EventLoop, WallClock
from shary.statechart.clock import SimulatedClock


def test_ready_work_runs_in_fifo_order_after_the_current_callback():
    loop = EventLoop()
    seen = []

    def first():
        seen.append("first")
        loop.call_soon(seen.append, "third")

    loop.call_soon(first)
    loop.call_soon(seen.append, "second")
    loop.run_until_idle()
    assert seen == ["first", "second", "third"]


def test_timers_fire_in_due_order_and_the_loop_idles_between_them():
    loop = EventLoop()
    seen = []

    def at(name):
        seen.append((loop.now(), name))
        loop.call_soon(seen.append, (loop.now(), name + "-after"))

    loop.call_later(2, at, "b")
    loop.call_later(1, at, "a")
    cancelled = loop.call_later(1.5, at, "never")
    cancelled.cancel()
    loop.advance(3)
    assert seen == [(1, "a"), (1, "a-after"), (2, "b"), (2, "b-after")]
    assert loop.now() == 3


def test_idle_hooks_run_after_work_only():
    loop = EventLoop()
    flushes = []
    loop.idle_hooks.append(lambda: flushes.append(loop.now()))
    loop.run_until_idle()
    loop.call_soon(lambda: None)
    loop.run_until_idle()
    assert flushes == [0]


def test_many_cancelled_timers_do_not_pile_up():
    clock = SimulatedClock()
    for _ in range(10_000):
        clock.call_later(30, lambda: None).cancel()
    assert len(clock._heap) < 600 and clock.next_due() is None


def test_wall_clock_runs_in_real_time():
    loop = EventLoop(WallClock())
    seen = []
    loop.call_later(0.02, seen.append, "tick")
    loop.run_for(0.1)
    assert seen == ["tick"] and loop.now() >= 0.1



def test_timers_cancelled_by_a_firing_timer_are_dropped_mid_advance():
    """A callback that cancels most pending timers makes the clock rebuild its heap while
    it is firing: the timers left still fire, in order, and the cancelled ones never."""
    clock = SimulatedClock()
    fired = []
    later = [clock.call_later(2 + i / 1000, fired.append, i) for i in range(1000)]

    def cancel_most():
        fired.append("cancel")
        for timer in later[:900]:
            timer.cancel()

    clock.call_later(1, cancel_most)
    clock.call_later(1, fired.append, "same time, set after")
    assert clock.advance(10) == 102
    assert fired == ["cancel", "same time, set after", *range(900, 1000)]
    assert clock.next_due() is None


def test_settle_freezes_the_loaded_world_once():
    import gc

    before = gc.get_threshold()
    loop = EventLoop()
    try:
        loop.settle()
        frozen = gc.get_freeze_count()
        assert frozen > 0 and gc.get_threshold() == STEADY_GC_THRESHOLDS
        loop.settle()  # once only: a second call freezes nothing more
        assert gc.get_freeze_count() == frozen
    finally:
        gc.unfreeze()
        gc.set_threshold(*before)


def test_run_for_sleeps_in_its_waiter_whose_work_runs_before_the_timers_then_due():
    """A middleware plugged in as the loop's waiter (ROS 2: the node) runs its callbacks
    while the loop waits; what they put on the loop runs before the timers due by then,
    and work given from another thread wakes the waiter."""
    import time

    loop = EventLoop(WallClock())
    seen: list[str] = []

    class Waiter:
        def __init__(self) -> None:
            self.timeouts: list[float] = []
            self.woken = 0

        def wait(self, timeout: float) -> None:
            self.timeouts.append(timeout)
            time.sleep(timeout)
            loop.call_soon(seen.append, "waiter's work")

        def wake(self) -> None:
            self.woken += 1

    waiter = loop.waiter = Waiter()
    loop.call_later(0.05, seen.append, "timer")
    loop.run_for(0.1)
    assert seen[:2] == ["waiter's work", "timer"]
    assert waiter.timeouts[0] <= 0.05  # up to the timer, not the whole run
    loop.call_soon_threadsafe(seen.append, "given")
    assert waiter.woken == 1
