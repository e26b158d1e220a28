"""A scenario's shared plan in a simulated run: the stack table, the follower, the partner.

:class:`StackSession` is what :mod:`sim.run` adds to a run whose scenario has a
``shared-plan:`` section: the stack table's objects and a-priori facts, the
executors and perception that know stacking, and, once recognition has
started, the plan follower (:class:`shary.plans.execution.PlanFollower`) with
its replan port and the partner who follows the plan as their profile says.
"""

from __future__ import annotations

from typing import Any

from shary.plans.execution import PlanFollower

from . import table
from .partner import StackPartner
from .planning import Replanner, StackFiles, first_plan
from .world import StackExecutors, StackPerception

__all__ = ["StackSession"]



class StackSession:
    """The shared plan of one run (see the module's documentation)."""

    executors_class = StackExecutors
    perception_class = StackPerception

    def __init__(self, spec: dict[str, Any], robot: str):
        self.spec = spec
        self.robot = robot
        self.partner_name = str(spec["partner"])
        self.names = {"robot": robot, "human": self.partner_name}
        self.follower: PlanFollower | None = None
        self.partner: StackPartner | None = None
        self.files = StackFiles.read(str(spec["problem"]))

    @staticmethod
    def objects() -> dict[str, dict[str, Any]]:
        return table.objects()

    @staticmethod
    def a_priori(facts: Any) -> None:
        table.a_priori(facts)

    def start(self, sup: Any, person: Any, decision_wait: float = 6.0) -> None:
        """Plan, and follow the plan with ``person`` (recognition must be running)."""
        self.follow(sup, decision_wait)
        self.join(person, self.follower)
        self.follower.start()

    def follow(self, sup: Any, decision_wait: float = 6.0) -> PlanFollower:
        """The supervisor's side: the first plan and its follower (not started yet)."""
        self.follower = PlanFollower(
            sup, first_plan(self.files, self.names), humans=[self.partner_name],
            replan=Replanner(sup.facts, self.files, self.names,
                             lambda kind, **row: sup.record(kind, agent=sup.robot, **row)),
            decision_wait=decision_wait, name="StackBuildingTask")
        return self.follower

    def join(self, person: Any, follower: Any) -> StackPartner:
        """The partner's side: ``person`` follows ``follower``'s plan (the follower itself,
        or what a world on ROS 2 hears of it) as their profile says, looking at the robot."""
        self.partner = StackPartner(person, follower, self.spec.get("profile") or {})
        person.look("robot")
        return self.partner

    @property
    def busy(self) -> bool:
        follower = self.follower
        return follower is not None and (follower.finished is None or follower.beliefs.speaking)

    def settle(self) -> None:
        """Called when the run is otherwise quiet: once the plan is over and no inform is
        under way, the partner's own later behaviour (a look back after the robot gave up
        telling her what she missed, or after the timeout) is dropped, so the run ends
        with its verdict instead of waiting for it."""
        if not self.busy and self.partner is not None:
            self.partner.stop()
