"""The executor port: how atomic tasks reach the world.

``shary`` never moves a motor.  Atomic tasks (move the arm, speak, wait for
the human to take) are handed to executors registered by name: the PyBullet
world of ``sim/`` fills this port, a real robot would fill it with ROS 2
actions, and tests fill it with small scripted fakes.

An executor receives a :class:`Request` and a :class:`Reporter`; it must
report exactly one outcome per request — done, failed (with a reason) or
cancelled — and stop at once when cancelled.  Reports are queued on the
supervisor's event loop, so an executor may report from inside ``start``.

A request *begins* when the world's executor gets it: at once, or, for a part of
the body several ask for (the voice, an arm), when the body's arbiter serves it
(:mod:`shary.kernel.arbiter`).  The reporter is told (:meth:`Reporter.begun`), so that
what watches until a step starts (a recipe monitor's ``until:``) watches while the
request waits: an inform's sentence that waits for the voice is still not said to
someone who looks away meanwhile.
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
    priority: int = 2
    """Who asks, for a part of the body several ask for at once (:mod:`shary.kernel.arbiter`):
    1 a plan watching, 2 a task's step (the default), 3 a robot action's own look."""


@dataclass(frozen=True)
class Outcome:
    """What became of a request: ``done``, ``failed`` or ``cancelled``."""

    request: Request
    status: str
    reason: str = ""
    result: dict[str, Any] = field(default_factory=dict)


class Reporter:
    """Passed to executors; queues outcomes on the supervisor's loop, and tells at once
    when a request begins (``begun``)."""

    _begun: Callable[[Request], None] | None = None

    def __init__(self, deliver: Callable[[Outcome], None],
                 call_soon: Callable[..., None],
                 begun: Callable[[Request], None] | None = None):
        self._deliver = deliver
        self._call_soon = call_soon
        self._begun = begun

    def begun(self, request: Request) -> None:
        """``request`` reaches the world's executor now (told before it starts there)."""
        if self._begun is not None:
            self._begun(request)

    def done(self, request: Request, **result: Any) -> None:
        self._call_soon(self._deliver, Outcome(request, "done", "", result))

    def failed(self, request: Request, reason: str) -> None:
        self._call_soon(self._deliver, Outcome(request, "failed", reason))

    def cancelled(self, request: Request, reason: str = "cancelled") -> None:
        self._call_soon(self._deliver, Outcome(request, "cancelled", reason))


class Executor(Protocol):
    """What the world implements for each atomic task it can perform.

    A request begins as the executor gets it, unless the executor may hold it first
    (the body's arbiter's port): such an executor has a true ``tells_begun`` attribute
    and calls ``reporter.begun`` itself."""

    def start(self, request: Request, reporter: Reporter) -> None: ...

    def cancel(self, request: Request) -> None: ...


class ExecutorRegistry:
    """Executors by atomic task name."""

    def __init__(self, executors: dict[str, Executor] | None = None):
        self._executors: dict[str, Executor] = dict(executors or {})
        self.arbiter: Any = None
        """The body's arbiter (:class:`shary.kernel.arbiter.BodyArbiter`), which the supervisor
        puts in front of the executors that move the head or an arm."""

    def register(self, atomic: str, executor: Executor) -> None:
        self._executors[atomic] = executor

    def get(self, atomic: str) -> Executor | None:
        found = self._executors.get(atomic)
        if found is None or self.arbiter is None:
            return found
        return self.arbiter.port(atomic, found)

    def names(self) -> list[str]:
        return sorted(self._executors)

    def dispatch(self, request: Request, reporter: Reporter, record: Callable[..., Any], *,
                 args: dict[str, Any] | None = None, problem: str | None = None,
                 **extra: Any) -> None:
        """Log ``request`` as an ``exec-request`` row, then start it on its executor.

        It fails at once (through ``reporter``, so asynchronously like any outcome)
        with ``problem`` if one is given, or when no executor is registered.  Every
        path that sends an atomic task to the world goes through here, so the log
        reads the same whoever asked: a scheme's act, a plan manager, a teleoperator.
        ``args`` is what the row shows (the request's own by default); ``extra``
        adds fields to the row (``by=`` for a teleoperator).
        """
        record("exec-request", task=request.node, agent=request.agent, atomic=request.atomic,
               request=request.id, args=request.args if args is None else args, **extra)
        executor = self.get(request.atomic)
        if problem is not None:
            reporter.failed(request, problem)
        elif executor is None:
            reporter.failed(request, f"no executor is registered for {request.atomic!r}")
        else:
            if not getattr(executor, "tells_begun", False):  # the world's own: begins now
                reporter.begun(request)
            executor.start(request, reporter)


def record_outcome(record: Callable[..., Any], outcome: Outcome) -> None:
    """Log an outcome as the ``exec-result`` row that answers its ``exec-request``."""
    request = outcome.request
    record("exec-result", task=request.node, agent=request.agent, request=request.id,
           status=outcome.status, reason=outcome.reason or None)
