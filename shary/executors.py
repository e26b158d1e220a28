"""The executor port: how atomic tasks reach the world.

``shary`` never moves a motor.  Atomic tasks (move the arm, speak, wait for
the human to take) are handed to executors registered by name: the PyBullet
world of ``sim/`` fills this port, a real robot would fill it with ROS 2
actions, and tests fill it with small scripted fakes.

An executor receives a :class:`Request` and a :class:`Reporter`; it must
report exactly one outcome per request — done, failed (with a reason) or
cancelled — and stop at once when cancelled.  Reports are queued on the
supervisor's event loop, so an executor may report from inside ``start``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol


@dataclass(frozen=True)
class Request:
    """One atomic task to perform."""

    id: str
    atomic: str
    args: dict[str, Any]
    agent: str
    node: str


@dataclass(frozen=True)
class Outcome:
    """What became of a request: ``done``, ``failed`` or ``cancelled``."""

    request: Request
    status: str
    reason: str = ""
    result: dict[str, Any] = field(default_factory=dict)


class Reporter:
    """Passed to executors; queues outcomes on the supervisor's loop."""

    def __init__(self, deliver: Callable[[Outcome], None],
                 call_soon: Callable[..., None]):
        self._deliver = deliver
        self._call_soon = call_soon

    def done(self, request: Request, **result: Any) -> None:
        self._call_soon(self._deliver, Outcome(request, "done", "", result))

    def failed(self, request: Request, reason: str) -> None:
        self._call_soon(self._deliver, Outcome(request, "failed", reason))

    def cancelled(self, request: Request, reason: str = "cancelled") -> None:
        self._call_soon(self._deliver, Outcome(request, "cancelled", reason))


class Executor(Protocol):
    """What the world implements for each atomic task it can perform."""

    def start(self, request: Request, reporter: Reporter) -> None: ...

    def cancel(self, request: Request) -> None: ...


class ExecutorRegistry:
    """Executors by atomic task name."""

    def __init__(self, executors: dict[str, Executor] | None = None):
        self._executors: dict[str, Executor] = dict(executors or {})

    def register(self, atomic: str, executor: Executor) -> None:
        self._executors[atomic] = executor

    def get(self, atomic: str) -> Executor | None:
        return self._executors.get(atomic)

    def names(self) -> list[str]:
        return sorted(self._executors)
