"""A supervisor on a ROS 2 robot: every port filled from one binding, on one node.

:class:`RosSupervision` puts together what the other modules of
:mod:`shary.ros` do, for a :class:`~shary.kernel.supervisor.Supervisor` whose loop
runs on a wall clock: the binding's executors in its executor registry, the
binding's fact and speech topics into its facts and dialogue, the liveliness of
the robot's nodes (a goal of a node that is gone fails at once), its state for
ROS tools (:mod:`~shary.ros.views`), and ``~/run_task`` and ``~/person_act``
(:mod:`~shary.ros.server`).  The views and the task server hear the
supervisor's events through :class:`~shary.log.told.Told`, the log the supervisor is given.
Closing the node stops the supervisor safely first (:mod:`~shary.ros.stop`): no robot goal
is left running and every ``~/run_task`` goal is answered.
"""

from __future__ import annotations

from typing import Any

from shary.log.told import Told
from shary.ros.binding import Binding
from shary.ros.executors import RosExecutors
from shary.ros.liveliness import Liveliness
from shary.ros.node import RosNode
from shary.ros.perception import RosPerception
from shary.ros.qos import QosWatch
from shary.ros.server import RosTaskServer
from shary.ros.stop import StopReport, safe_stop
from shary.ros.views import RosViews


class RosSupervision:
    """A supervisor's ports on a robot's ROS 2 interfaces (see the module's docstring)."""

    def __init__(self, sup: Any, binding: Binding, node: RosNode, *, fanout: Told):
        from shary.console.replay import named_schemes

        self.sup, self.binding, self.node = sup, binding, node
        node.attach(sup.loop)
        self.executors = RosExecutors(node, binding, sup.loop, record=sup.record,
                                      fact=self.fact)
        self.executors.register(sup.executors)
        self.liveliness = Liveliness(node, binding, executors=self.executors,
                                     record=sup.record)
        self.qos = QosWatch(node, sup.loop, sup.record)
        """Publishers the perception's subscriptions cannot hear (:mod:`~shary.ros.qos`)."""
        self.perception = RosPerception(node, binding, sup.facts, sup.loop,
                                        act=sup.receive_act, hear=sup.dialogue.hear,
                                        record=sup.record, qos=self.qos)
        self.views = RosViews(node, sup.loop, named_schemes(), robot=sup.robot,
                              frames=binding.frames)
        self.server = RosTaskServer(node, sup)
        self.server.unsettled = self.executors.unsettled
        fanout.listeners += [self.views.listener, self.server.listener]
        self.stopped: StopReport | None = None
        """What the safe stop did, once it has run."""
        self.stop_reason = "the node is shutting down"
        """The reason the stop gives when the node closes (the command sets the signal)."""
        node.before_close.append(lambda: self.stop(self.stop_reason))

    def stop(self, reason: str) -> StopReport:
        """Stop safely (:mod:`shary.ros.stop`): tasks cancelled, robot goals cancelled and
        their servers' answers awaited, ``~/run_task`` goals answered; once (the node's
        closing runs it if nobody did before)."""
        if self.stopped is None:
            self.stopped = safe_stop(self.sup, self.executors, self.server, self.sup.loop,
                                     reason)
        return self.stopped

    def fact(self, subject: str, predicate: str) -> Any:
        """The robot's belief of ``subject``'s ``predicate`` (a goal's ``{fact:…}``)."""
        found = self.sup.facts.objects(subject, predicate)
        return found[0] if found else None
