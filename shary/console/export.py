"""``shary export LOG --mcap OUT``: a logged run as an MCAP file, for Foxglove and friends.

MCAP is the recording format Foxglove, ROS 2 (rosbag2) and many robotics
tools read.  The file is written with the ``mcap`` package's writer (chunked,
zstd-compressed, indexed); every channel carries JSON messages described by a
JSON Schema, so a viewer shows named fields without a ROS installation:

``/acts`` (acts performed and received), ``/actions`` (atomic tasks started
and ended), ``/facts`` (each perspective's additions and removals),
``/tree`` (task-tree nodes added, their states, cuts), ``/configurations``
(each task's active scheme states after every transition), ``/log`` (the
console's act/action lines as ``foxglove.Log``, for the Log panel),
``/snapshots`` (the run's PNG views as ``foxglove.CompressedImage``, for the
Image panel), ``/plan-tasks`` (a shared plan's task states, per view: the
robot's and each human's as the robot estimates it), ``/recognitions`` (the
recognized human actions) and ``/events`` (every event of the log, as it is).

Times are the run's engine seconds from zero (a viewer shows them as
1970-01-01 plus the run's time).  The configurations and lines come from the
same fold as the console's page (:class:`shary.console.view.View`), so the
file and the page agree.
"""

from __future__ import annotations

import argparse
import base64
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from shary.console.ports import run_file
from shary.console.replay import named_schemes
from shary.console.view import View
from shary.kernel.tasktree import replay_log
from shary.log.contextlog import LogEvent, stream_events
from shary.log.terminal import add_json_flag, emit_json
from shary.log.terminal import out as _out
from shary.plans.states import STATES as TASK_STATES
from shary.recognition.recognizer import STATES as RECOGNITION_STATES
from userfiles.outputs import open_output, output_file

_STRING = {"type": "string"}
_NUMBER = {"type": "number"}
_TIME = {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}}


def _obj(**fields: Any) -> dict[str, Any]:
    return {"type": "object", "properties": fields}


SCHEMAS: dict[str, tuple[str, dict[str, Any]]] = {
    "/acts": ("shary.Act", _obj(time=_NUMBER, agent=_STRING, act=_STRING, task=_STRING,
                                act_type=_STRING, direction={"enum": ["performed", "received"]})),
    "/actions": ("shary.Action", _obj(time=_NUMBER, agent=_STRING, atomic=_STRING,
                                      request=_STRING, task=_STRING, status=_STRING,
                                      reason=_STRING, args={"type": "object"})),
    "/facts": ("shary.FactChange", _obj(time=_NUMBER, perspective=_STRING, s=_STRING, p=_STRING,
                                        o=_STRING, change={"enum": ["added", "removed"]})),
    "/tree": ("shary.TreeChange", _obj(time=_NUMBER, change={"enum": ["node", "state", "cut"]},
                                       node=_STRING, parent=_STRING, kind=_STRING, name=_STRING,
                                       state=_STRING, nodes={"type": "array", "items": _STRING})),
    "/configurations": ("shary.Configuration", _obj(
        time=_NUMBER, task=_STRING, task_name=_STRING, agent=_STRING, scheme=_STRING,
        states={"type": "array", "items": _STRING})),
    "/log": ("foxglove.Log", _obj(timestamp=_TIME, level={"type": "integer"}, message=_STRING,
                                  name=_STRING, file=_STRING, line={"type": "integer"})),
    "/snapshots": ("foxglove.CompressedImage", _obj(
        timestamp=_TIME, frame_id=_STRING, format=_STRING,
        data={"type": "string", "contentEncoding": "base64"})),
    "/plan-tasks": ("shary.PlanTaskState", _obj(
        time=_NUMBER, task=_STRING, name=_STRING, view=_STRING,
        state={"enum": list(TASK_STATES)}, estimate={"type": "boolean"}, event=_STRING,
        reason=_STRING)),
    "/recognitions": ("shary.Recognition", _obj(
        time=_NUMBER, action=_STRING, action_class=_STRING, agent=_STRING,
        parameters={"type": "object", "additionalProperties": {"type": ["string", "null"]}},
        state={"enum": list(RECOGNITION_STATES)}, candidate=_STRING, cause=_STRING,
        fact=_STRING)),
    "/events": ("shary.Event", _obj(seq={"type": "integer"}, time=_NUMBER, kind=_STRING,
                                    task={"type": ["string", "null"]},
                                    agent={"type": ["string", "null"]}, data={"type": "object"})),
}
LOG_LEVELS = {"failed": 4, "operator": 3}
"""foxglove.Log levels of the console's lines (2, INFO, for the others)."""


def add_export(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="write a logged run as an MCAP file (Foxglove, rosbag2 "
                       "tools)")
    p.add_argument("log", type=Path, metavar="LOG", help="a run's log.sqlite")
    p.add_argument("--mcap", type=Path, metavar="OUT", required=True,
                   help="the MCAP file to write")
    add_json_flag(p, "the channels and their message counts")
    p.set_defaults(func=cmd_export)


def cmd_export(args: argparse.Namespace) -> int:
    counts = export_mcap(args.log, args.mcap)
    if args.json:
        emit_json({"out": str(args.mcap), "channels": counts})
    else:
        _out.print(f"wrote {args.mcap}: " + ", ".join(f"{name} {n}" for name, n in
                                                    counts.items()))
    return 0


def export_mcap(log: str | Path, out: str | Path) -> dict[str, int]:
    """Write the run logged in ``log`` to ``out`` (see the module's docstring); return the
    number of messages per channel.  A bad log is refused before anything is written."""
    from mcap.writer import CompressionType, Writer

    output_file(out, inputs=[log])
    replay_log(log)  # a tree the log cannot have grown is refused at its row, before writing
    folder = Path(log).resolve().parent
    counts = dict.fromkeys(SCHEMAS, 0)
    with stream_events(log) as events, open_output(out, binary=True) as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        writer.start(profile="", library="shary")
        channels = {}
        for topic, (name, schema) in SCHEMAS.items():
            schema_id = writer.register_schema(name=name, encoding="jsonschema",
                                               data=json.dumps(schema).encode())
            channels[topic] = writer.register_channel(topic=topic, message_encoding="json",
                                                      schema_id=schema_id)

        def put(topic: str, t: float, message: dict[str, Any]) -> None:
            ns = int(round(t * 1e9))
            writer.add_message(channels[topic], log_time=ns, publish_time=ns,
                               data=json.dumps(message, ensure_ascii=False).encode(),
                               sequence=counts[topic])
            counts[topic] += 1

        view = View(named_schemes())
        try:
            for e in events:
                put("/events", e.time, e.as_dict())
                _messages(e, folder, put)
                for change in view.apply(e):
                    _from_change(change, e, view, put)
        finally:
            writer.finish()  # an unfinished MCAP file cannot be read
    return counts


def _messages(e: LogEvent, folder: Path,
              put: Callable[[str, float, dict[str, Any]], None]) -> None:
    """The typed channels an event feeds, besides the view's."""
    d = e.data
    if e.kind in ("act", "act-received"):
        put("/acts", e.time, {"time": e.time, "agent": e.agent or "", "act": str(d.get("act")),
                              "task": e.task or "", "act_type": str(d.get("act_type") or ""),
                              "direction": "performed" if e.kind == "act" else "received"})
    elif e.kind in ("exec-request", "exec-result"):
        put("/actions", e.time, {
            "time": e.time, "agent": e.agent or "", "atomic": str(d.get("atomic", "")),
            "request": str(d.get("request")), "task": e.task or "",
            "status": "started" if e.kind == "exec-request" else str(d.get("status")),
            "reason": str(d.get("reason") or ""),
            "args": d.get("args") if isinstance(d.get("args"), dict) else {}})
    elif e.kind in ("fact-added", "fact-removed"):
        put("/facts", e.time, {"time": e.time, "perspective": str(d.get("perspective")),
                               "s": str(d.get("s")), "p": str(d.get("p")), "o": str(d.get("o")),
                               "change": e.kind[5:]})
    elif e.kind == "node":
        put("/tree", e.time, {"time": e.time, "change": "node", "node": e.task or "",
                              "parent": str(d.get("parent") or ""),
                              "kind": str(d.get("node_kind")), "name": str(d.get("name")),
                              "state": str(d.get("state", ""))})
    elif e.kind == "task-state":
        put("/tree", e.time, {"time": e.time, "change": "state", "node": e.task or "",
                              "name": str(d.get("name")), "state": str(d.get("state"))})
    elif e.kind == "node-removed":
        put("/tree", e.time, {"time": e.time, "change": "cut", "node": e.task or "",
                              "nodes": [str(n) for n in d.get("nodes") or ()]})
    elif e.kind == "plan-task" and d.get("state") in TASK_STATES:
        put("/plan-tasks", e.time, {"time": e.time, "task": e.task or "",
                                    "name": str(d.get("name") or ""), "view": e.agent or "",
                                    "state": d["state"], "estimate": bool(d.get("estimate")),
                                    "event": str(d.get("event") or ""),
                                    "reason": str(d.get("reason") or "")})
    elif e.kind == "recognition" and d.get("state") in RECOGNITION_STATES:
        params = d.get("params") if isinstance(d.get("params"), dict) else {}
        put("/recognitions", e.time, {
            "time": e.time, "action": str(d.get("action")),
            "action_class": str(d.get("action_class") or ""), "agent": e.agent or "",
            "parameters": {str(k): None if v is None else str(v) for k, v in params.items()},
            "state": d["state"], "candidate": str(d.get("candidate") or ""),
            "cause": str(d.get("cause") or ""), "fact": str(d.get("fact") or "")})
    elif e.kind == "snapshot":
        image = run_file(folder, d.get("file"))
        if image is not None:
            data = base64.b64encode(image.read_bytes()).decode("ascii")
            put("/snapshots", e.time, {"timestamp": _stamp(e.time), "frame_id": "camera",
                                       "format": "png", "data": data})


def _from_change(change: list[Any], e: LogEvent, view: View,
                 put: Callable[[str, float, dict[str, Any]], None]) -> None:
    if change[0] == "config":
        task = view.tasks[change[1]]
        put("/configurations", e.time, {"time": e.time, "task": change[1],
                                        "task_name": str(task["name"]), "agent": task["agent"],
                                        "scheme": str(task["scheme"]), "states": change[2]})
    elif change[0] == "line":
        _, t, who, kind, text = change
        put("/log", t, {"timestamp": _stamp(t), "level": LOG_LEVELS.get(kind, 2),
                        "message": text, "name": who or "shary", "file": kind, "line": 0})


def _stamp(t: float) -> dict[str, int]:
    ns = int(round(t * 1e9))
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}
