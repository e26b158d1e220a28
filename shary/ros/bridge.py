"""A supervisor on a ROS 2 robot: every port filled from one binding, on one node.

:class:`RosSupervision` puts together what the other modules of
:mod:`shary.ros` do, for a :class:`~shary.supervisor.Supervisor` whose loop
runs on a wall clock: the binding's executors in its executor registry, the
binding's fact and speech topics into its facts and dialogue, its state for
ROS tools (:mod:`~shary.ros.views`), and ``~/run_task`` and ``~/person_act``
(:mod:`~shary.ros.server`).  The views and the task server hear the
supervisor's events through :class:`Fanout`, the log the supervisor is given.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from shary.ros.binding import Binding
from shary.ros.executors import RosExecutors
from shary.ros.node import RosNode
from shary.ros.perception import RosPerception
from shary.ros.server import RosTaskServer
from shary.ros.views import RosViews

Listener = Callable[[float, str, "str | None", "str | None", dict[str, Any]], Any]


class Fanout:
    """A context log that also tells each event to listeners (ROS views, the task
    server); ``log`` (a :class:`~shary.log.ContextLog`, or None) keeps them."""

    def __init__(self, log: Any = None) -> None:
        self.log = log
        self.listeners: list[Listener] = []
        if hasattr(log, "path"):
            self.path = log.path

    def record(self, t: float, kind: str, *, task: str | None = None,
               agent: str | None = None, **data: Any) -> Any:
        row = self.log.record(t, kind, task=task, agent=agent, **data) if self.log else None
        for listener in self.listeners:
            listener(t, kind, task, agent, data)
        return row

    def flush(self) -> None:
        if self.log is not None:
            self.log.flush()


class RosSupervision:
    """A supervisor's ports on a robot's ROS 2 interfaces (see the module's docstring)."""

    def __init__(self, sup: Any, binding: Binding, node: RosNode, *, fanout: Fanout):
        from shary.console.replay import named_schemes

        self.sup, self.binding, self.node = sup, binding, node
        node.attach(sup.loop)
        self.executors = RosExecutors(node, binding, sup.loop, record=sup.record,
                                      fact=self.fact)
        self.executors.register(sup.executors)
        self.perception = RosPerception(node, binding, sup.facts, sup.loop,
                                        act=sup.receive_act, hear=sup.dialogue.hear,
                                        record=sup.record)
        self.views = RosViews(node, sup.loop, named_schemes(), robot=sup.robot)
        self.server = RosTaskServer(node, sup)
        fanout.listeners += [self.views.listener, self.server.listener]

    def fact(self, subject: str, predicate: str) -> Any:
        """The robot's belief of ``subject``'s ``predicate`` (a goal's ``{fact:…}``)."""
        found = self.sup.facts.objects(subject, predicate)
        return found[0] if found else None
