"""What must hold at the end of every run, whatever the people did: the campaign's judge.

Each invariant reads one run (:class:`Run`: its context-log rows, what the world
makes true at the end, the scenario) and says whether it held, and if not,
what it saw, in one line.  A run's **verdict** is the outcome the supervisor
reached: the shared plan's last ``shared-plan`` row (``achieved``, ``failed``)
for the stack family, every goal's ``goal-over`` for the living room and the
dialogue family (all ``done``: achieved; a conversation in which nothing the
robot could take on was asked, "I found no such thing", is achieved), the team
goal's ``goal-over`` for the seam-welding site.

The invariants:

``verdict``
    The run ends before its timeout with a verdict; a failure states its
    reason (the plan's ``reason``, or something the robot says after its last
    act; a team task ``task-given-up`` with its reason).  A goal the person
    declined (``H-DISAGREE``) ends ``done`` in the task tree, as SHARY's
    END-TASK does, but it is not achieved: it counts as failed, its reason
    what the robot says ("I will not give you the yellow bottle.") or, when it
    says nothing (she no longer looks), her no.
``no-ongoing``
    Nothing is left under way: no plan task ONGOING in any view, every task
    started ended (the interaction ``session`` aside: it lasts as long as the
    people are there; and a killed member's own tasks, which end with its
    process), no team task still running.
``facts``
    The world agrees with the verdict: an achieved stack stands (both red
    cubes on the placements, the stick across them, a blue cube, the green
    cube, the other blue cube), a given object is in the person's hand, a
    cleaned-up one in the trash, mounted panels on the frame and welded seams
    beaded (at least unsure, 0.4: a person may vouch for such a bead); and a
    failed verdict is not one whose effects are all there (sound beads, 0.8),
    unless a task the site cannot show (an inspection) was left undone.
``told-unseen``
    Nothing is told to a person who is not looking: each robot sentence said
    in a task with people in its roles (the partner of a give, the helper of
    an ask-help, the person an inform is for; the task whose act said it,
    :func:`~sim.fuzz.conversations.said_in`) is said while one of them is
    perceived looking at the robot
    (``looksAt`` rows); a task of the robot alone (a clean-up's "I have
    cleared the yellow bottle away.") tells no one in particular.  Except a
    call for attention ("Excuse me, Alice."), the stated reason of a verdict
    already reached (a GIVE-UP, a failed plan's ANNOUNCE) and the goodbye to a
    person walking out (FAREWELL), which are said whoever listens.  The
    seam-welding site's people are reached through their proxies (a remote IVA
    has no gaze): not checked there.
``not-seen``
    Every task NOT_SEEN in a person's view becomes EXECUTED in it later (the
    robot told them), or the plan failed, or the plan ended and the robot's inform
    to them after its end gave up (a ``belief`` row ``why=untold``: they did not
    attend, e.g. they had left) (stack only).

The invariants that see conversations (``order``, ``belief``,
``no-call-while-looking``, ``after-farewell``, ``reason-heard``, ``one-voice``) read the same
rows; they are in :mod:`sim.fuzz.conversations`, and :data:`INVARIANTS` lists
them all.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from ..weld.executors import BAD, SOUND
from .conversations import (
    ATTENTION_CALL,
    CONVERSING,
    after_farewell,
    belief,
    no_call_while_looking,
    one_voice,
    order,
    reason_heard,
    said_in,
)

__all__ = ["INVARIANTS", "Invariant", "Run", "verdict"]

Row = tuple[float, str, "str | None", "str | None", dict[str, Any]]

CLOSING_ACTS = frozenset({"GIVE-UP", "FAREWELL", "ANNOUNCE"})
"""Acts whose sentence closes something whoever listens: the stated reason of a task
given up or of a failed plan (ANNOUNCE), the goodbye as a person walks out
(shary/dialogue/sessions.py: leaving closes the session)."""


@dataclass
class Run:
    """One finished run of a campaign, as the invariants read it."""

    family: str
    rows: list[Row]
    truth: frozenset[tuple[str, str, str]]
    end: float
    timeout: float
    robot: str
    people: tuple[str, ...]
    scenario: Any

    def of(self, *kinds: str) -> Iterable[Row]:
        return (r for r in self.rows if r[1] in kinds)


@dataclass(frozen=True)
class Invariant:
    name: str
    says: str
    check: Callable[[Run], str | None] | None
    """The violation seen, in one line, or None when the invariant held; None for one
    the campaign judges itself, running again (``keys-matter``, :mod:`sim.fuzz.keys`)."""
    families: tuple[str, ...] = ("stack", "living-room", "weld", "dialogue")


# -------------------------------------------------------------------------- verdicts

def verdict(run: Run) -> tuple[str | None, str]:
    """The run's outcome (achieved, failed, or None when none was reached) and the
    reason stated for a failure ('' when none was)."""
    if run.family == "stack":
        return _plan_verdict(run)
    if run.family == "weld":
        return _team_verdict(run)
    return _goals_verdict(run)


def _plan_verdict(run: Run) -> tuple[str | None, str]:
    state, reason, at = None, "", 0.0
    for t, _, _, _, data in run.of("shared-plan"):
        if data.get("state") in ("achieved", "failed"):
            state, reason, at = data["state"], str(data.get("reason") or ""), t
    if state == "failed" and not reason:
        reason = next((d["text"] for t, _, _, a, d in run.of("speech")
                       if a == run.robot and t >= at - 1e-9), "")
    return state, reason


def _goals_verdict(run: Run) -> tuple[str | None, str]:
    goals = {d["goal"]: d for _, _, _, _, d in run.of("goal-added")}
    over = {d["goal"]: (t, task, d["outcome"], str(d.get("reason") or ""))
            for t, _, task, _, d in run.of("goal-over")}
    if not goals and run.family == "dialogue":
        return "achieved", ""  # nothing was asked that the robot could take on
    if not goals or set(goals) - set(over):
        return None, ""
    declined = {task: f"{who} said no" for _, _, task, who, d in run.of("act-received")
                if d.get("act") == "H-DISAGREE"}
    cancelled = {d.get("name"): f"{who} cancelled it" for _, _, _, who, d
                 in run.of("act-received") if d.get("act") == "CANCEL"}
    names = {d["goal"]: d["name"] for _, _, _, _, d in run.of("goal-over")}
    failed = [(t, task, logged or cancelled.get(names.get(goal), ""))
              for goal, (t, task, outcome, logged) in over.items()
              if outcome != "done" or task in declined]
    if not failed:
        return "achieved", ""
    reasons = []
    for end, node, logged in failed:
        acts = [t for t, _, task, a, d in run.of("act") if task == node and a == run.robot]
        since = acts[-1] if acts else end
        said = next((d["text"] for t, _, _, a, d in run.of("speech")
                     if a == run.robot and since - 1e-9 <= t <= end + 1e-9), "")
        reasons.append(logged or said or declined.get(node, ""))
    return "failed", " / ".join(reasons) if all(reasons) else ""


def _team_verdict(run: Run) -> tuple[str | None, str]:
    over = [d for _, _, _, _, d in run.of("goal-over")
            if "tasks" in d]  # the team's goal (a robot's own agenda logs its goals too)
    if not over:
        return None, ""
    if over[-1]["outcome"] == "done":
        return "achieved", ""
    given_up = [f"{task}: {d.get('reason', '')}" for _, _, task, _, d in run.of("task-given-up")
                if d.get("reason")]
    if over[-1].get("reason"):  # the watchdog's: nothing a task said
        given_up.append(str(over[-1]["reason"]))
    return "failed", "; ".join(given_up)


# ------------------------------------------------------------------------ invariants

def _ends_with_verdict(run: Run) -> str | None:
    if run.end >= run.timeout - 1e-9:
        state, _ = verdict(run)
        return f"still going at the timeout ({run.timeout:g}s), verdict {state or 'none'}"
    state, reason = verdict(run)
    if state is None:
        return f"ended at {run.end:.1f}s without a verdict"
    if state == "failed" and not reason:
        return "failed without a stated reason"
    return None


def _nothing_ongoing(run: Run) -> str | None:
    left = []
    states: dict[tuple[str | None, str | None], tuple[str, str]] = {}
    for _, _, task, agent, data in run.of("plan-task"):
        states[(agent, task)] = (data.get("state", ""), data.get("name", ""))
    left += [f"{name} ONGOING in {agent}'s view" for (agent, _), (state, name)
             in states.items() if state == "ONGOING"]
    killed = {agent for _, _, _, agent, _ in run.of("agent-killed")}
    # a killed member's own tasks end with its process: nobody is left to end them (the
    # team task it held was taken back, ``agent-lost``)
    started = {task: d["name"] for _, _, task, agent, d in run.of("task-start")
               if d.get("name") != "session" and agent not in killed}
    for _, _, task, _, _ in run.of("task-end"):
        started.pop(task, None)
    left += [f"task {name} ({node}) never ended" for node, name in started.items()]
    team: dict[str, str] = {}
    for _, kind, task, _, _ in run.of("task-running", "task-done", "task-failed",
                                      "task-given-up", "task-retry", "task-unassigned",
                                      "respawn", "agent-lost"):
        if task is not None:
            team[task] = kind
    left += [f"team task {task} left running" for task, kind in team.items()
             if kind == "task-running"]
    return "; ".join(left[:3]) + (f" (+{len(left) - 3})" if len(left) > 3 else "") \
        if left else None


def stack_built(truth: frozenset[tuple[str, str, str]]) -> bool:
    """Whether the StackBuildingTask's stack stands: each red cube on its own placement,
    the stick across both, then a blue cube, the green cube and the other blue cube."""
    on = {(s, o) for s, p, o in truth if p == "isOn"}
    reds = ("red_cube_1", "red_cube_2")
    bases = {o for r in reds for s, o in on if s == r and o.startswith("placement_")}
    if len(bases) != 2 or not all(("stick", r) in on for r in reds):
        return False
    blues = ("blue_cube_1", "blue_cube_2")
    return any((b, "stick") in on and ("green_cube", b) in on and (other, "green_cube") in on
               for b, other in (blues, blues[::-1]))


def _effects(run: Run, strict: bool = False) -> list[str]:
    """What the world should show if the verdict is 'achieved', each missing one named;
    ``strict``: a weld counts only if sound (a bead K-10 is unsure of may be vouched for
    by a person, so it does not contradict 'achieved', nor prove 'failed' wrong)."""
    truth = run.truth
    if run.family == "stack":
        return [] if stack_built(truth) else ["the stack does not stand"]
    missing = []
    if run.family == "weld":
        for name, task in run.scenario.team.tasks.items():
            panel, seam = task.args.get("panel"), task.args.get("seam")
            if task.skill == "mount-panel" and (panel, "mounted", "true") not in truth:
                missing.append(f"{panel} is not mounted ({name})")
            quality = next((float(o) for s, p, o in truth if s == seam and p == "quality"),
                           0.0)
            if task.skill == "weld-seam" and quality < (SOUND if strict else BAD):
                missing.append(f"{seam} is not welded soundly ({name}: bead "
                               f"{quality:g})" if quality else f"{seam} is not welded ({name})")
        return missing
    for _, _, _, _, d in run.of("goal-added"):
        args = d.get("args") or {}
        if d["name"] == "give-object" and \
                (args["partner"], "isHolding", args["object"]) not in truth:
            missing.append(f"{args['partner']} does not hold the {args['object']}")
        if d["name"] == "clean-up" and (args["object"], "isIn", "trash") not in truth:
            missing.append(f"the {args['object']} is not in the trash")
    return missing


def _facts_agree(run: Run) -> str | None:
    state, _ = verdict(run)
    if state is None:
        return None  # no verdict: the verdict invariant says so
    missing = _effects(run)
    if state == "achieved" and missing:
        return "achieved, but " + "; ".join(missing)
    if state == "failed" and not _effects(run, strict=True) and not _unseen_undone(run) \
            and not _failed_unshown(run):
        return "failed, but everything it was to do is done"
    return None


SHOWN = ("give-object", "clean-up")
"""The goals whose outcome the living room shows (a hand holding, a bin holding)."""


def _failed_unshown(run: Run) -> list[int]:
    """The failed goals whose failure the world cannot contradict: an inform or another
    goal it shows nothing of, or one whose effect another goal brought about (she said
    no to the bottle, then asked for it herself)."""
    if run.family not in ("living-room", "dialogue"):
        return []
    goals = {d["goal"]: (d["name"], tuple(sorted((d.get("args") or {}).items())))
             for _, _, _, _, d in run.of("goal-added")}
    declined = {task for _, _, task, _, d in run.of("act-received")
                if d.get("act") == "H-DISAGREE"}
    done = {goals.get(d["goal"]) for _, _, task, _, d in run.of("goal-over")
            if d["outcome"] == "done" and task not in declined}
    return [d["goal"] for _, _, task, _, d in run.of("goal-over")
            if (d["outcome"] != "done" or task in declined)
            and (goals.get(d["goal"], ("",))[0] not in SHOWN or goals.get(d["goal"]) in done)]


PHYSICAL = ("mount-panel", "weld-seam")
"""The weld team's skills whose work the site shows (an inspection leaves no trace)."""


def _unseen_undone(run: Run) -> list[str]:
    """The weld team's tasks left undone whose work the world cannot show (an inspection
    nobody was left to make): a failure over them is not contradicted by the site."""
    if run.family != "weld":
        return []
    last: dict[str, str] = {}
    for _, kind, task, _, _ in run.of("task-done", "task-ready", "task-given-up"):
        if task is not None:
            last[task] = kind
    return [name for name, task in run.scenario.team.tasks.items()
            if task.skill not in PHYSICAL and last.get(name) != "task-done"]


def _told_unseen(run: Run) -> str | None:
    looks: set[tuple[str, str]] = set()
    roles: dict[str | None, list[str]] = {}
    act, speaking, plan_over = "", None, False
    saying = said_in(run)
    for t, kind, task, agent, data in run.rows:
        if kind in ("fact-added", "fact-removed") and data.get("p") == "looksAt" \
                and data.get("s") in run.people:
            (looks.add if kind == "fact-added" else looks.discard)((data["s"], data["o"]))
        elif kind == "task-start":
            roles[task] = [str(v) for v in (data.get("roles") or {}).values()
                           if v in run.people]
        elif kind == "act" and agent == run.robot:
            act, speaking = data.get("act", ""), task
        elif kind == "shared-plan" and data.get("state") == "failed":
            plan_over = True
        elif kind == "speech" and agent == run.robot:
            text = str(data.get("text", ""))
            said, by = saying.get(str(data.get("request")), (speaking, act))
            told = roles.get(said, [])
            if not told or text.startswith(ATTENTION_CALL) or by in CLOSING_ACTS \
                    or plan_over:
                continue
            if not any((p, run.robot) in looks for p in told):
                where = ", ".join(f"{p} looks at {o}" for p, o in sorted(looks)
                                  if p in told) or f"{' and '.join(told)} not looking"
                return f"said {text!r} at {t:.1f}s while {where}"
    return None


def _not_seen_told(run: Run) -> str | None:
    pending: dict[tuple[str | None, str | None], tuple[float, str]] = {}
    failed = any(d.get("state") == "failed" for _, _, _, _, d in run.of("shared-plan"))
    untold = {agent for _, _, _, agent, d in run.of("belief") if d.get("why") == "untold"}
    for t, _, task, agent, data in run.of("plan-task"):
        if agent == run.robot or agent in untold:
            continue
        if data.get("state") == "NOT_SEEN":
            pending.setdefault((agent, task), (t, data.get("name", "")))
        elif data.get("state") == "EXECUTED":
            pending.pop((agent, task), None)
    if pending and not failed:
        (agent, _), (t, name) = next(iter(pending.items()))
        more = f" (+{len(pending) - 1})" if len(pending) > 1 else ""
        return f"{name} NOT_SEEN by {agent} since {t:.1f}s, never told{more}"
    return None


INVARIANTS = (
    Invariant("verdict", "ends before its timeout with a verdict (a failure with its reason)",
              _ends_with_verdict),
    Invariant("no-ongoing", "no task left ONGOING or running at the end", _nothing_ongoing),
    Invariant("facts", "the world's facts agree with the verdict", _facts_agree),
    Invariant("told-unseen", "nothing told to a person who is not looking", _told_unseen,
              ("stack", "living-room", "dialogue")),
    Invariant("not-seen", "every NOT_SEEN is told, or the plan ended and telling failed",
              _not_seen_told, ("stack",)),
    # the conversations (sim/fuzz/conversations.py)
    Invariant("order", "past events are told in the order they happened", order,
              CONVERSING),
    Invariant("belief", "what was told is EXECUTED in the listener's view", belief,
              ("stack",)),
    Invariant("no-call-while-looking", "nobody is called while looking at the robot",
              no_call_while_looking, CONVERSING),
    Invariant("after-farewell", "nothing said to, nor goal kept for, someone who left",
              after_farewell, CONVERSING),
    Invariant("reason-heard", "a failure's reason is said to someone there, or logged "
              "unheard", reason_heard, CONVERSING),
    Invariant("one-voice", "the robot says one sentence at a time", one_voice, CONVERSING),
    # the generator's: every key drawn changes the run (sim/fuzz/keys.py)
    Invariant("keys-matter", "every key drawn changes the run it is drawn for", None),
)
