"""shary's state for ROS tools: a latched snapshot, the active states, diagnostics, markers.

:class:`RosViews` listens to the context log's events (as the console does),
folds them with the console's :class:`~shary.console.view.View`, and
publishes, each at most every ``period`` seconds and only after a change:

``~/snapshot``       ``std_msgs/String``, latched (TRANSIENT_LOCAL, depth 1): the
                     JSON of the task runs (scheme, configuration, outcome), the
                     task tree, the agenda and the open questions (modelled on
                     py_trees_ros ``~/snapshots``: publish on change, a late
                     subscriber gets the latest);
``~/active_state``   ``std_msgs/String``: ``TASK NODE: STATE, STATE`` each time a
                     task's configuration changes (Foxglove's State Transitions
                     panel plots it);
``/diagnostics``     ``diagnostic_msgs/DiagnosticArray``: one status per task run,
                     ``shary/TASK NODE``; OK while it runs, WARN when suspended,
                     ERROR when it ended otherwise than done (rqt_robot_monitor,
                     Foxglove's Diagnostics panels);
``~/markers``        ``visualization_msgs/MarkerArray``: a text above the robot
                     (what it is doing) and above each person it waits for.
"""

from __future__ import annotations

import json
from typing import Any

from shary.log.contextlog import LogEvent
from shary.ros.node import RosNode

DONE_OUTCOMES = {"done", "success", "succeeded", "achieved", "ended"}
"""Task outcomes that are not a failure, for the diagnostics' level."""


class RosViews:
    """Publishes a supervisor's state for ROS tools (see the module's docstring)."""

    def __init__(self, node: RosNode, loop: Any, schemes: Any, *, robot: str,
                 period: float = 0.1, frame: str = "base_link"):
        from diagnostic_msgs.msg import DiagnosticArray
        from std_msgs.msg import String
        from visualization_msgs.msg import MarkerArray

        from shary.console.view import View

        self.node, self.loop, self.robot, self.frame = node, loop, robot, frame
        self.period = period
        self.view = View(schemes)
        self._seq = 0
        self._dirty = False
        self._scheduled = False
        self._doing = ""
        self.snapshot_pub = node.publisher(String, "~/snapshot", latched=True)
        self.active_pub = node.publisher(String, "~/active_state")
        self.diagnostics_pub = node.publisher(DiagnosticArray, "/diagnostics")
        self.markers_pub = node.publisher(MarkerArray, "~/markers")

    def listener(self, time: float, kind: str, task: str | None, agent: str | None,
                 data: dict[str, Any]) -> None:
        """Told every logged event (see :class:`shary.log.told.Told`'s listeners)."""
        from std_msgs.msg import String

        self._seq += 1
        changes = self.view.apply(LogEvent(self._seq, time, kind, task, agent, data))
        if kind == "exec-request" and agent == self.robot:
            self._doing = f"{data.get('atomic')} {_args(data.get('args'))}".strip()
        elif kind == "exec-result" and agent == self.robot:
            self._doing = ""
        for change in changes:
            if change[0] == "config":
                run = self.view.tasks.get(change[1], {})
                text = f"{run.get('name', '?')} {change[1]}: {', '.join(change[2]) or '-'}"
                self.active_pub.publish(String(data=text))
        if not self._scheduled and any(change[0] != "time" for change in changes):
            self._scheduled = True
            self.loop.call_later(self.period, self.publish)

    def publish(self) -> None:
        """Publish the snapshot, the diagnostics and the markers now."""
        from std_msgs.msg import String

        self._scheduled = False
        self.snapshot_pub.publish(String(data=json.dumps(self.snapshot())))
        self.diagnostics_pub.publish(self.diagnostics())
        self.markers_pub.publish(self.markers())

    def snapshot(self) -> dict[str, Any]:
        """The state as JSON-able data (what ``~/snapshot`` carries)."""
        view = self.view
        return {
            "time": view.time,
            "tasks": {node: {"name": t["name"], "agent": t["agent"], "scheme": t["scheme"],
                             "configuration": list(t["config"]), "outcome": t["outcome"]}
                      for node, t in view.tasks.items()},
            "tree": [dict(zip(("id", "parent", "kind", "name", "state"), n, strict=False))
                     for n in view.nodes.values()],
            "agenda": [dict(zip(("id", "name", "args", "priority", "state"), g, strict=False))
                       for g in view.goals.values()],
            "questions": {node: q[2:4] for node, q in view.questions.items()},
            "doing": self._doing,
        }

    def diagnostics(self) -> Any:
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

        array = DiagnosticArray()
        for node, run in self.view.tasks.items():
            config = list(run["config"])
            if run["outcome"] is not None:
                level = 0 if run["outcome"] in DONE_OUTCOMES else 2
                message = f"ended: {run['outcome']}"
            else:
                level = 1 if any("suspend" in s or "wait" in s.lower() for s in config) else 0
                message = ", ".join(config) or "starting"
            array.status.append(DiagnosticStatus(
                level=bytes([level]), name=f"shary/{run['name']} {node}", message=message,
                hardware_id=self.robot,
                values=[KeyValue(key=k, value=str(v)) for k, v in (
                    ("task", run["name"]), ("agent", run["agent"]), ("scheme", run["scheme"]),
                    ("outcome", run["outcome"] or ""))]))
        return array

    def markers(self) -> Any:
        from visualization_msgs.msg import Marker, MarkerArray

        array = MarkerArray()
        texts = [(self.frame, f"{self.robot}: {self._doing or 'idle'}")]
        for question in self.view.questions.values():
            for person in question[3] if len(question) > 3 else ():
                texts.append((f"person_{person}", f"waiting for {person}"))
        for i, (frame, text) in enumerate(texts):
            marker = Marker(type=Marker.TEXT_VIEW_FACING, action=Marker.ADD, id=i, text=text,
                            ns="shary")
            marker.header.frame_id = frame
            marker.pose.position.z = 1.6
            marker.pose.orientation.w = 1.0
            marker.scale.z = 0.15
            marker.color.r = marker.color.g = marker.color.b = marker.color.a = 1.0
            array.markers.append(marker)
        return array


def _args(args: Any) -> str:
    if isinstance(args, dict):
        return " ".join(str(v) for v in args.values())
    return ""
