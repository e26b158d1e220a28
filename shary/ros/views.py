"""shary's state for ROS tools: a latched snapshot, the active states, diagnostics, markers.

:class:`RosViews` listens to the context log's events (as the console does),
folds them with the console's :class:`~shary.console.view.View`, and
publishes:

``~/snapshot``       ``std_msgs/String``, latched (TRANSIENT_LOCAL, depth 1), at most
                     every ``period`` seconds after a change: the JSON of the task runs
                     (scheme, configuration, outcome), the task tree, the agenda and the
                     open questions (modelled on py_trees_ros ``~/snapshots``);
``~/active_state``   ``std_msgs/String``: ``TASK NODE: STATE, STATE`` each time a
                     task's configuration changes (Foxglove's State Transitions
                     panel plots it);
``/diagnostics``     ``diagnostic_msgs/DiagnosticArray`` once a second (rqt_robot_monitor
                     and Foxglove mark a silent status stale) and after a change: a
                     status ``shary`` for the node, then one per task run, ``shary/TASK
                     NODE``; OK while it runs, WARN when waiting or suspended, ERROR when
                     it ended otherwise than done;
``~/markers``        ``visualization_msgs/MarkerArray`` once a second and after a change:
                     a text above the robot (what it does) and above each person a task
                     waits for (an answer, or their attention: WAIT-ATTENTION), in the
                     frames the binding names (``frames:``), stamped, with a lifetime of
                     a few periods (markers of a shary that is gone fade), and deleted
                     (``DELETE``) as soon as what they show is over.

Everything is bounded however long shary runs: the snapshot and the diagnostics carry
the tasks running and the last :data:`KEEP_ENDED` ended (the view forgets older ones,
with their nodes and goals, and all but the last :data:`KEEP_ITEMS` ended acts and
actions).  Stamps come from the node's clock, which follows
``/clock`` when the node's ``use_sim_time`` is set.
"""

from __future__ import annotations

import json
from collections import deque
from typing import Any

from shary.log.contextlog import LogEvent
from shary.ros.node import RosNode

DONE_OUTCOMES = {"done", "success", "succeeded", "achieved", "ended"}
"""Task outcomes that are not a failure, for the diagnostics' level."""
KEEP_ENDED = 10
"""Ended tasks (and agenda goals) the views keep showing, the newest."""
KEEP_ITEMS = 200
"""Ended timeline items (acts, actions) the folded view keeps, the newest: the view is
the console's, which keeps a whole run's; a node may run for months."""
BEAT = 1.0
"""Seconds between two publications of the diagnostics and the markers."""
MARKER_LIFETIME = 3.0
"""Seconds a marker stays in RViz without being published again."""
WAITING_ACTS = {"WAIT-ATTENTION"}
"""Acts during which the robot waits for a person's attention (shown above them)."""
GOAL_OVER = {"done", "failed", "cancelled", "dropped", "refused"}


class RosViews:
    """Publishes a supervisor's state for ROS tools (see the module's docstring)."""

    def __init__(self, node: RosNode, loop: Any, schemes: Any, *, robot: str,
                 period: float = 0.1, frames: dict[str, str] | None = None):
        from diagnostic_msgs.msg import DiagnosticArray
        from std_msgs.msg import String
        from visualization_msgs.msg import MarkerArray

        from shary.console.view import View

        self.node, self.loop, self.robot = node, loop, robot
        self.frames = {"robot": "base_link", "person": "person_{agent}", **(frames or {})}
        """The robot's frame and a person's (``{agent}``: the person's name)."""
        self.period = period
        self.view = View(schemes)
        self._seq = 0
        self._scheduled = False
        self._doing = ""
        self._ended: deque[str] = deque()
        self._shown: set[tuple[str, int]] = set()
        """The markers (namespace, id) last published, to delete those that are over."""
        self.snapshot_pub = node.publisher(String, "~/snapshot", latched=True)
        self.active_pub = node.publisher(String, "~/active_state")
        self.diagnostics_pub = node.publisher(DiagnosticArray, "/diagnostics")
        self.markers_pub = node.publisher(MarkerArray, "~/markers")
        loop.call_later(BEAT, self._beat)

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
        elif kind == "task-end" and task in self.view.tasks:
            self._ended.append(task)
            while len(self._ended) > KEEP_ENDED:
                self._forget(self._ended.popleft())
        if len(self.view.items) > 2 * KEEP_ITEMS:  # now and then: amortized
            ended = [key for key, item in self.view.items.items() if item[5] is not None]
            for key in ended[:-KEEP_ITEMS]:
                del self.view.items[key]
        for change in changes:
            if change[0] == "config":
                run = self.view.tasks.get(change[1], {})
                text = f"{run.get('name', '?')} {change[1]}: {', '.join(change[2]) or '-'}"
                self.active_pub.publish(String(data=text))
        if not self._scheduled and any(change[0] != "time" for change in changes):
            self._scheduled = True
            self.loop.call_later(self.period, self.publish)

    def _forget(self, task: str) -> None:
        """Drop an ended task from the view: its run, its nodes, and agenda goals over
        beyond the newest :data:`KEEP_ENDED`."""
        view = self.view
        view.tasks.pop(task, None)
        view.questions.pop(task, None)
        doomed = {task}
        for node_id, node in list(view.nodes.items()):  # parents come before children
            if node_id in doomed or node[1] in doomed:
                doomed.add(node_id)
                del view.nodes[node_id]
        over = [key for key, goal in view.goals.items() if str(goal[-1]) in GOAL_OVER]
        for key in over[:-KEEP_ENDED]:
            del view.goals[key]

    def _beat(self) -> None:
        """Once a second: the diagnostics and the markers, changed or not."""
        self.diagnostics_pub.publish(self.diagnostics())
        self.markers_pub.publish(self.markers())
        self.loop.call_later(BEAT, self._beat)

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
        array.header.stamp = self.node.node.get_clock().now().to_msg()
        running = 0
        for node, run in self.view.tasks.items():
            config = list(run["config"])
            if run["outcome"] is not None:
                level = 0 if run["outcome"] in DONE_OUTCOMES else 2
                message = f"ended: {run['outcome']}"
            else:
                running += 1
                level = 1 if any("suspend" in s or "wait" in s.lower() for s in config) else 0
                message = ", ".join(config) or "starting"
            array.status.append(DiagnosticStatus(
                level=bytes([level]), name=f"shary/{run['name']} {node}", message=message,
                hardware_id=self.robot,
                values=[KeyValue(key=k, value=str(v)) for k, v in (
                    ("task", run["name"]), ("agent", run["agent"]), ("scheme", run["scheme"]),
                    ("outcome", run["outcome"] or ""))]))
        array.status.insert(0, DiagnosticStatus(
            level=bytes([0]), name="shary", hardware_id=self.robot,
            message=f"{running} task(s) running; doing: {self._doing or 'nothing'}"))
        return array

    def markers(self) -> Any:
        from rclpy.duration import Duration
        from visualization_msgs.msg import Marker, MarkerArray

        array = MarkerArray()
        stamp = self.node.node.get_clock().now().to_msg()
        texts = [("shary/robot", 0, self.frames["robot"],
                  f"{self.robot}: {self._doing or 'idle'}")]
        for node, people, text in self._waits():
            for i, person in enumerate(people):
                texts.append((f"shary/{node}", i, self.frames["person"].replace(
                    "{agent}", person), text.replace("{agent}", person)))
        shown = set()
        for ns, index, frame, text in texts:
            marker = Marker(type=Marker.TEXT_VIEW_FACING, action=Marker.ADD, id=index,
                            text=text, ns=ns)
            marker.header.frame_id = frame
            marker.header.stamp = stamp
            marker.lifetime = Duration(seconds=MARKER_LIFETIME).to_msg()
            marker.pose.position.z = 1.6
            marker.pose.orientation.w = 1.0
            marker.scale.z = 0.15
            marker.color.r = marker.color.g = marker.color.b = marker.color.a = 1.0
            array.markers.append(marker)
            shown.add((ns, index))
        for ns, index in sorted(self._shown - shown):  # what they showed is over
            gone = Marker(action=Marker.DELETE, ns=ns, id=index)
            gone.header.stamp = stamp
            array.markers.append(gone)
        self._shown = shown
        return array

    def _waits(self) -> list[tuple[str, list[str], str]]:
        """Each running task that waits for people: its node, the people, the text
        (``{agent}``: each one): an answer to its question, or their attention."""
        found = []
        for node, question in self.view.questions.items():
            if len(question) > 3 and question[3]:
                found.append((node, list(question[3]), "waiting for {agent}"))
        for node, run in self.view.tasks.items():
            scheme = self.view.schemes(run["scheme"]) if run["outcome"] is None else None
            if scheme is None or node in self.view.questions:
                continue
            acts = {scheme.states[s].act for s in run["config"] if s in scheme.states}
            if acts & WAITING_ACTS:
                people = [who for role, who in run["roles"].items()
                          if scheme.roles.get(role) == "human"]
                found.append((node, people, "waiting for {agent}'s attention"))
        return found


def _args(args: Any) -> str:
    if isinstance(args, dict):
        return " ".join(str(v) for v in args.values())
    return ""
