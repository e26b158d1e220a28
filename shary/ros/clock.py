"""The engine's clock on ROS time: ``use_sim_time`` honoured.

A robot in simulation (Gazebo, a replayed bag) publishes its time on ``/clock``, and its
nodes run with the ``use_sim_time`` parameter set: their clocks follow ``/clock``, and a
simulation slower than real time, or paused, slows or stops them.  shary's deadlines
(a scheme's ``after 10s``, a goal's ``exec`` deadline) must then be in that time too,
or a slow simulation would see every goal time out.

:class:`RosClock` is a :class:`~shary.kernel.loop.WallClock` whose time is the node's clock
(ROS time, which is ``/clock``'s when the node uses sim time), counted from the first
time it read (0 until ``/clock`` has said anything), and never going back (a simulation
restarted).  Stopping must not wait for a simulation that may be paused:
:meth:`RosClock.follow_wall` makes it run on real time from then on (the safe stop
calls it, and so does the first Ctrl-C).
"""

from __future__ import annotations

import time
from typing import Any

from shary.kernel.loop import WallClock


class RosClock(WallClock):
    """The engine's time from a ROS node's clock (see the module's docstring)."""

    def __init__(self, node: Any):
        self._clock = node.node.get_clock()
        self._origin_ns: int | None = None
        self._last = 0.0
        self._wall_since: float | None = None
        super().__init__()

    def now(self) -> float:
        if self._wall_since is not None:
            return self._last + time.monotonic() - self._wall_since
        ns = self._clock.now().nanoseconds
        if ns <= 0:  # no /clock yet
            return self._last
        if self._origin_ns is None:
            self._origin_ns = ns - int(self._last * 1e9)
        self._last = max(self._last, (ns - self._origin_ns) / 1e9)
        return self._last

    def follow_wall(self) -> None:
        """Run on real time from now on (a stop never waits for a paused simulation)."""
        if self._wall_since is None:
            self._last = self.now()
            self._wall_since = time.monotonic()
