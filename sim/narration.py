"""The story of a run, as ``shary run`` prints it while a scenario runs.

A newcomer reading the console should be able to follow the run without
opening the log: the acts the robot enters, what each agent does, what is
said, why a step failed and the new plan made from there, what the people do
on their own, and where the partner's attention goes (looked away, looked
back).  The :class:`Narrator` turns the run's events into such lines; a
``Report`` shows them: :class:`ConsoleReport` prints them aligned in columns,
coloured per agent and styled per kind of line.

A line has a *kind*, so that whoever shows it can style it:

``act``        an act starts (``[ASK-TASK] give-object``)
``action``     the robot starts an atomic task (``navigate coffee-area``)
``failed``     a step failed, with its reason
``speech``     something said aloud (in quotes) or a person's gesture (in parentheses)
``person``     a person's own action (``pick yellow-bottle``)
``attention``  a person looked away from the robot or back at it
``plan``       a plan (or a new plan after a failure): one line per agent's stream
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

KINDS = ("act", "action", "failed", "speech", "person", "attention", "plan")


class Report(Protocol):
    """Where the story goes: one call per line."""

    def __call__(self, t: float, who: str, kind: str, text: str) -> Any: ...


_PREPOSITIONS = ("to", "on", "into", "from")


def action_text(atomic: str, args: dict[str, Any]) -> str:
    """An atomic task as a short phrase: ``give yellow-bottle to alice``."""
    words = [atomic]
    for key, value in args.items():
        words += [key, str(value)] if key in _PREPOSITIONS else [str(value)]
    return " ".join(words)


class Narrator:
    """Tells the events of a run that a newcomer needs to follow it.

    ``last_plan()`` gives the plan (a :class:`planner.Plan`) behind the latest
    ``plan`` event, whose agents' streams are shown; ``robot`` and ``people``
    say whose attention is worth telling (a person's, towards the robot).
    """

    def __init__(self, report: Report, robot: str, people: set[str],
                 last_plan: Callable[[], Any] = lambda: None):
        self.report = report
        self.robot = robot
        self.people = people
        self.last_plan = last_plan
        self._replan: str | None = None
        self._attending: dict[str, bool] = {}
        self._looking_at: dict[str, str] = {}

    def event(self, t: float, kind: str, agent: str | None, data: dict[str, Any]) -> None:
        """One event of the context log (see :mod:`shary.log.contextlog`); most are not told."""
        if kind == "replan":
            self._replan = str(data.get("reason", ""))
        elif kind == "plan":
            self._plan(t, list(data.get("steps", ())))
        elif kind == "act-received" and agent and data.get("initiated") and data.get("name"):
            # a person starts or stops a task (their other acts enter a task's state)
            self.report(t, agent, "act", f"[{data.get('act')}] {data['name']}")
        elif kind == "person-action" and agent:
            self.report(t, agent, "person", action_text(str(data.get("atomic")),
                                                        dict(data.get("args") or {})))
        elif kind == "recognition" and data.get("state") == "achieved":
            params = data.get("params") if isinstance(data.get("params"), dict) else {}
            self.report(t, self.robot, "recognized", f"recognized: {agent or 'nobody'} "
                        + " ".join([str(data.get("action")),
                                    *(str(v) for v in params.values() if v is not None)]))
        elif kind in ("fact-added", "fact-removed") and data.get("p") == "looksAt" \
                and data.get("perspective", "robot") == "robot":
            self._attention(t, kind == "fact-added", str(data.get("s")), str(data.get("o")))

    def _plan(self, t: float, steps: list[str]) -> None:
        reason, self._replan = self._replan, None
        plan = self.last_plan()
        streams = plan.streams if plan is not None else {}
        count = sum(len(s) for s in streams.values()) or len(steps)
        head = f"new plan, {count} {'action' if count == 1 else 'actions'}" if reason is not None \
            else f"plan, {count} {'action' if count == 1 else 'actions'}"
        because = reason.split(": ")[0] if reason else ""
        self.report(t, self.robot, "plan", head + (f", since {because}" if because else ""))
        if not streams:
            self.report(t, self.robot, "plan", "  " + " → ".join(steps))
        for agent, actions in streams.items():
            self.report(t, agent, "plan", "  " + " → ".join(
                f"{a.name}({', '.join(str(x) for x in a.args if str(x) != agent)})"
                for a in actions))

    def _attention(self, t: float, added: bool, who: str, target: str) -> None:
        if who not in self.people:
            return
        if target != self.robot:
            if added:
                self._looking_at[who] = target
            return
        before = self._attending.get(who)
        self._attending[who] = added
        if added and before is None:
            self.report(t, who, "attention", f"looks at {self.robot}")
        elif added and before is False:
            self.report(t, who, "attention", f"looks back at {self.robot}")
        elif not added and before:
            where = self._looking_at.get(who)
            self.report(t, who, "attention", f"looks away from {self.robot}"
                        + (f" (at the {where})" if where else ""))


_AGENT_COLOURS = ("cyan", "magenta", "green", "yellow", "blue", "bright_red")
_STYLES = {"act": "bold", "failed": "red", "attention": "italic", "plan": "dim",
           "person": "", "action": "", "speech": "", "recognized": "italic"}
_MARKS = {"act": "▶", "action": "·", "failed": "✗", "speech": "“", "person": "·",
          "attention": "◉", "plan": "≡", "recognized": "✓"}


class ConsoleReport:
    """Prints the story aligned: time, agent (one colour each), a mark per kind, the text.

    ``console`` is a :class:`rich.console.Console`; text is escaped, never
    read as markup.
    """

    def __init__(self, console: Any):
        self.console = console
        self.colours: dict[str, str] = {}

    def __call__(self, t: float, who: str, kind: str, text: str) -> None:
        from rich.markup import escape

        colour = self.colours.setdefault(who, _AGENT_COLOURS[len(self.colours)
                                                             % len(_AGENT_COLOURS)])
        if kind == "speech" and not text.startswith("("):
            text = f"“{text}”"
        mark = " " if kind == "speech" else _MARKS.get(kind, " ")
        style = _STYLES.get(kind, "")
        body = f"[{style}]{escape(text)}[/{style}]" if style else escape(text)
        self.console.print(f"[dim]{t:7.1f}s[/dim]  [{colour}]{escape(who):<8}[/{colour}] "
                           f"[{colour}]{mark}[/{colour}] {body}")
