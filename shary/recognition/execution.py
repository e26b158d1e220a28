"""Executing the robot's actions from their models: look, act, retry, then escalate (Listing 1).

JAHRVIS's Action Execution Manager runs a robot action in three Jason plans:
turn the head to what the action is about and call the motion planner and
controller; on failure, try again; once ``max_attempts`` tries have failed,
signal the failure to the task level (``.fail_goal(executeAction, …)``).
:class:`RobotActions` does the same through the engine's executor port: the
model's ``look-at`` role is looked at (the ``look-at`` atomic task, when an
executor performs it), the model's executor runs with its arguments taken
from the roles, a failure is retried until ``max_attempts`` tries have
failed, and then the caller (the plan, the task) is told ``failed`` with the
last reason.  Every request, retry and outcome is logged like the atomic
tasks recipes run (``exec-request``/``exec-result``), plus a
``robot-action`` row per state of the action.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from shary.kernel.arbiter import ACT
from shary.kernel.executors import Outcome, Reporter, Request, record_outcome
from shary.recognition.models import ActionModels, RobotActionModel

__all__ = ["ActionResult", "RobotActions"]


@dataclass(frozen=True)
class ActionResult:
    """How a robot action ended: ``done`` or ``failed`` (after its attempts) or ``cancelled``."""

    action: str
    status: str
    attempts: int
    reason: str = ""


class RobotActions:
    """Performs robot actions by name with their roles bound (see the module's documentation).

    ``sup`` is the supervisor (its executors, loop, log and robot's name).
    """

    def __init__(self, sup: Any, models: ActionModels):
        self.sup = sup
        self.models = models
        self._reporter = Reporter(self._outcome, sup.loop.call_soon)
        self._pending: dict[str, _Running] = {}
        self._ids = itertools.count(1)

    def perform(self, action: str, params: dict[str, Any], node: str,
                done: Callable[[ActionResult], Any]) -> None:
        """Start ``action`` (a robot model's name) with ``params`` (role -> entity); ``done``
        is called once, on the loop, with how it ended.  Raises KeyError for an action
        no model describes and ValueError for missing roles: those are the caller's
        mistakes, not the world's."""
        model = self.models.robot[action]
        missing = [role for role, _ in model.params if role not in params]
        if missing:
            raise ValueError(f"{action} needs {', '.join(missing)}")
        running = _Running(model, dict(params), node, done)
        self.sup.record("robot-action", task=node, agent=self.sup.robot, action=action,
                        state="started", params={k: str(v) for k, v in params.items()})
        if model.look_at is not None and self.sup.executors.get("look-at") is not None:
            self._request(running, "look-at", {"target": params[model.look_at]}, looking=True)
        else:
            self._attempt(running)

    def cancel(self, node: str) -> None:
        """Cancel the action running for ``node`` (its current request is cancelled)."""
        for running in list(self._pending.values()):
            if running.node == node:
                running.cancelled = True
                executor = self.sup.executors.get(running.request.atomic)
                if executor is not None:
                    executor.cancel(running.request)

    # -- inside -----------------------------------------------------------------------------------

    def _attempt(self, running: _Running) -> None:
        model = running.model
        running.attempts += 1
        if model.executor is None:  # nothing to move: done once the head has turned
            self._finish(running, "done")
            return
        args = {argument: running.params[role] for argument, role in model.args.items()}
        self._request(running, model.executor, args, looking=False)

    def _request(self, running: _Running, atomic: str, args: dict[str, Any], *,
                 looking: bool) -> None:
        request = Request(f"a{next(self._ids)}", atomic, args, self.sup.robot, running.node,
                          ACT)
        running.request, running.looking = request, looking
        self._pending[request.id] = running
        self.sup.executors.dispatch(request, self._reporter, self.sup.record,
                                    args={k: str(v) for k, v in args.items()})

    def _outcome(self, outcome: Outcome) -> None:
        record_outcome(self.sup.record, outcome)
        running = self._pending.pop(outcome.request.id, None)
        if running is None:
            return
        if running.cancelled:
            self._finish(running, "cancelled", outcome.reason or "cancelled")
        elif running.looking:
            self._attempt(running)  # looked, could not, or the head was needed: act all the same
        elif outcome.status == "cancelled":
            self._finish(running, "cancelled", outcome.reason or "cancelled")
        elif outcome.status == "done":
            self._finish(running, "done")
        elif running.attempts < running.model.max_attempts:
            self.sup.record("robot-action", task=running.node, agent=self.sup.robot,
                            action=running.model.name, state="retry",
                            attempt=running.attempts + 1, reason=outcome.reason)
            self._attempt(running)
        else:
            self._finish(running, "failed", f"max_attempts ({running.model.max_attempts}) "
                         f"reached: {outcome.reason}")

    def _finish(self, running: _Running, status: str, reason: str = "") -> None:
        self.sup.record("robot-action", task=running.node, agent=self.sup.robot,
                        action=running.model.name, state=status, attempts=running.attempts,
                        reason=reason or None)
        result = ActionResult(running.model.name, status, running.attempts, reason)
        self.sup.loop.call_soon(running.done, result)


@dataclass
class _Running:
    model: RobotActionModel
    params: dict[str, Any]
    node: str
    done: Callable[[ActionResult], Any]
    attempts: int = 0
    request: Request | None = None
    looking: bool = False
    cancelled: bool = False
