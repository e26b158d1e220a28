"""The story of a team run on the seam-welding site, as ``shary run weld-…`` prints it.

A newcomer should follow the team without opening the log: who the Task
Manager gives each task to (and why), who refuses, the robots' atomic tasks,
K-10's question with its picture, who answers and what, the weld that is
respawned, EVA1's request for light, the breakpoint, the association and the
release, and IVA taking control and handing back.  Lines go to a
:class:`sim.narration.Report` with its kinds (``act``, ``action``,
``failed``, ``speech``, ``person``), so :class:`sim.narration.ConsoleReport`
shows them as it shows the living room's story.
"""

from __future__ import annotations

from typing import Any

from ..narration import Report, action_text


class TeamStory:
    """Turns the team's context-log events into lines of the story."""

    def __init__(self, report: Report):
        self.report = report

    def event(self, t: float, kind: str, agent: str | None, data: dict[str, Any],
              task: str | None = None) -> None:
        """One event of the context log; most are not told."""
        say = self.report
        who = agent or "team"
        if kind == "delegation" and agent:
            ranking = data.get("ranking") or []
            others = ", ".join(f"{r.get('agent')} {r.get('score')}" for r in ranking[1:])
            say(t, "RM", "act", f"{data.get('need')} {task} → {agent}"
                + (f" (score {ranking[0].get('score')}; then {others})" if others else ""))
        elif kind == "task-running":
            say(t, who, "act", f"starts {task}")
        elif kind == "task-done":
            say(t, who, "act", f"done: {task}")
        elif kind == "task-failed":
            say(t, who, "failed", f"{task} failed: {data.get('reason', '')}")
        elif kind == "task-given-up":
            say(t, "TM", "failed", f"gives up {task} after {data.get('attempts')} attempts")
        elif kind == "agent-killed":
            say(t, who, "failed", "killed: its process is gone")
        elif kind == "put-down":
            say(t, who, "failed", f"puts {data.get('panel')} down: {data.get('why')}")
        elif kind == "agent-lost":
            say(t, "TM", "failed", f"takes {task} back from {who} (lost)")
        elif kind == "watchdog":
            say(t, "TM", "failed", f"watchdog ({data.get('why')}): {data.get('action')}")
        elif kind == "respawn":
            say(t, "TM", "failed", f"respawns {task} (after {data.get('by')}: "
                f"{data.get('reason', '')})")
        elif kind == "message" and data.get("status") == "refused" \
                and data.get("type") == "progress":
            say(t, who, "person", f"refuses {task}"
                + (f": {data['reason']}" if data.get("reason") else ""))
        elif kind == "exec-request":
            by = f" (driven by {data['by']})" if data.get("by") else ""
            args = dict(data.get("args") or {})
            text = (f"{data.get('atomic')} “{args['words']}” as {args.get('speaker')} sees it"
                    if "words" in args else action_text(str(data.get("atomic")), args))
            say(t, who, "action", text + by)
        elif kind == "exec-result" and data.get("status") == "failed":
            say(t, who, "failed", str(data.get("reason", "")))
        elif kind == "question":
            attached = data.get("data") or {}
            image = f"  [image {attached['image']}]" if attached.get("image") else ""
            to = f"({data['to']}) " if data.get("to") else ""
            say(t, who, "speech", f"{to}{data.get('text')}{image}")
        elif kind == "message" and data.get("type") == "question" and who == "interaction":
            say(t, "IM", "act", f"routes “{data.get('text')}” to {data.get('to')}")
        elif kind == "answer":
            if data.get("expired"):
                say(t, "IM", "failed", f"nobody answered in time; taken as "
                    f"{data.get('value')!r}")
            else:
                say(t, who, "speech", f"{data.get('value')}")
        elif kind == "help-request":
            args = data.get("args") or {}
            say(t, who, "speech", str(args.get("words") or data.get("skill")))
        elif kind == "spatial":
            say(t, "SRA", "action", str(data["says"]) if data.get("says")
                else f"cannot tell for {who}: the reference is ambiguous")
        elif kind == "breakpoint":
            say(t, who, "act", f"breakpoint before {data.get('before')}: suspends {task}")
        elif kind == "associate":
            say(t, who, "act", f"associates with {data.get('requester')}")
        elif kind == "release":
            say(t, who, "act", f"released by {data.get('by')}; resumes {task or 'its work'}")
        elif kind == "control":
            mode = data.get("mode")
            say(t, str(data.get("by")), "person",
                f"takes control of {who}" if mode == "user" else f"hands {who} back")
        elif kind == "goal-over" and "tasks" in data:
            say(t, "TM", "act", f"goal {data.get('outcome')}: {data.get('done')} of "
                f"{data.get('tasks')} tasks done"
                + (f" ({data['reason']})" if data.get("reason") else ""))

