"""The invariants that see conversations: what the robot says, to whom, and in which order.

The invariants of :mod:`sim.fuzz.invariants` judge outcomes (a verdict, the
world, nothing left under way); these judge the dialogue that led there, from
the same context-log rows (:class:`~sim.fuzz.invariants.Run`).  Where a person
looks is the robot's perception (``looksAt`` rows of its perspective); who a
sentence is said to is the people in the roles of the task whose act said it
(:func:`said_in`, as ``told-unseen`` reads it); a person is *gone* from the robot's goodbye
(the ``FAREWELL`` act of their session) until a session with them opens again.

``order``
    Sentences about past events are said in the order the events happened: the
    robot's informs of what a person missed (``inform`` rows, each bound to the
    task it is about) are said in the order those tasks were achieved.
``belief``
    An inform about a task that ends told leaves that task EXECUTED in the
    listener's view; and a plan achieved leaves no task NOT_SEEN in the view of
    a partner who looked at the robot after they missed it and is still there
    at the end (they were there to be told).
``no-call-while-looking``
    No call for attention ("Excuse me, Alice.") while the person called is
    perceived looking at the robot.
``after-farewell``
    Nothing is said to a person after their goodbye (their session's
    FAREWELL), and no goal with them outlives it by more than
    :data:`GRACE` seconds.
``reason-heard``
    A failure's reason is said while the person is there, or logged as
    ``unheard`` when they are not: each ``plan-end`` sentence is said (before
    they leave) or logged unheard, and each goal with a person that ends failed
    or cancelled (not on their own CANCEL: the reason is theirs) has the robot
    speaking to them at its end, or an ``unheard`` row for them.
``one-voice``
    The robot says one sentence at a time: no sentence begins while another is
    being said (from its ``speech`` row until its ``speak`` request ends, said or
    cancelled).
"""

from __future__ import annotations

from collections.abc import Iterator
from itertools import pairwise
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .invariants import Row, Run

__all__ = ["ATTENTION_CALL", "CONVERSING", "GRACE", "after_farewell", "belief",
           "no_call_while_looking", "one_voice", "order", "reason_heard", "said_in"]

ATTENTION_CALL = "Excuse me"
"""How a call for attention begins (shary/dialogue/attention.py): said to be looked at."""

GRACE = 1.0
"""How long a goal with a person may outlive their goodbye (it ends at once: a margin
for the loop's turn)."""
CONVERSING = ("stack", "living-room", "dialogue")
"""The families whose people the robot talks to face to face (the weld site's people
are reached through their proxies)."""


def said_in(run: Run) -> dict[str, tuple[str | None, str]]:
    """Each robot ``speak`` request -> the task it is said in and the act that says it,
    read from the task tree's ``node`` rows: a sentence that waits for the voice is said
    after other tasks have acted, so the robot's last act is not always its own."""
    parents: dict[str | None, str | None] = {}
    acts: dict[str | None, str] = {}
    found: dict[str, tuple[str | None, str]] = {}
    for _, kind, task, _, data in run.rows:
        if kind == "node":
            parents[task] = data.get("parent")
            if data.get("node_kind") == "act":
                acts[task] = str(data.get("act", ""))
        elif kind == "exec-request" and data.get("atomic") == "speak":
            act = parents.get(task)
            if act in acts:
                found[str(data.get("request"))] = (parents.get(act), acts[act])
    return found


def _speaking(run: Run) -> Iterator[tuple[Row, list[str], set[tuple[str, str]], str]]:
    """Each robot speech row, with the people it is said to, who looks at what then (in
    the robot's perception) and the name of the task it is said in."""
    looks: set[tuple[str, str]] = set()
    roles: dict[str | None, list[str]] = {}
    names: dict[str | None, str] = {}
    speaking = None
    saying = said_in(run)
    for row in run.rows:
        _, kind, task, agent, data = row
        if kind in ("fact-added", "fact-removed") and data.get("p") == "looksAt" \
                and data.get("s") in run.people \
                and data.get("perspective", "robot") == "robot":
            (looks.add if kind == "fact-added" else looks.discard)((data["s"], data["o"]))
        elif kind == "task-start":
            roles[task] = [str(v) for v in (data.get("roles") or {}).values()
                           if v in run.people]
            names[task] = str(data.get("name", ""))
        elif kind == "act" and agent == run.robot:
            speaking = task
        elif kind == "speech" and agent == run.robot:
            task = saying.get(str(data.get("request")), (speaking, ""))[0]
            yield row, roles.get(task, []), set(looks), names.get(task, "")


def no_call_while_looking(run: Run) -> str | None:
    for (t, _, _, _, data), told, looks, _ in _speaking(run):
        text = str(data.get("text", ""))
        looking = [p for p in told if (p, run.robot) in looks]
        if text.startswith(ATTENTION_CALL) and looking:
            return f"said {text!r} at {t:.1f}s while {looking[0]} looks at {run.robot}"
    return None


def _farewells(run: Run) -> list[tuple[float, str, float | None]]:
    """Each goodbye: (when, to whom, when a session with them opened again or None)."""
    partners: dict[str | None, str] = {}
    out: list[tuple[float, str, float | None]] = []
    for t, kind, task, agent, data in run.rows:
        if kind == "task-start" and data.get("name") == "session":
            partners[task] = str((data.get("roles") or {}).get("partner"))
        elif kind == "act" and data.get("act") == "FAREWELL" and task in partners:
            out.append((t, partners[task], None))
        elif kind == "session-open":
            out = [(at, who, t if who == agent and back is None else back)
                   for at, who, back in out]
    return out


def _gone(farewells: list[tuple[float, str, float | None]], person: str, t: float) -> bool:
    return any(who == person and at <= t and (back is None or t < back)
               for at, who, back in farewells)


def _goal_people(run: Run) -> dict[int, tuple[str, set[str], float]]:
    """Goal id -> its task name, the people among its arguments, when it was added."""
    return {d["goal"]: (str(d.get("name")), {str(v) for v in (d.get("args") or {}).values()
                                            if v in run.people}, t)
            for t, _, _, _, d in run.of("goal-added")}


def after_farewell(run: Run) -> str | None:
    farewells = _farewells(run)
    if not farewells:
        return None
    for (t, _, _, _, data), told, _, name in _speaking(run):
        gone = [p for p in told if _gone(farewells, p, t)]
        if gone and name != "session":
            return f"said {data.get('text')!r} at {t:.1f}s to {gone[0]}, who had left"
    over = {d["goal"]: t for t, _, _, _, d in run.of("goal-over")}
    for goal, (name, people, added) in _goal_people(run).items():
        end = over.get(goal, run.end)
        for at, who, _ in farewells:  # a goal they ask for once back is a new one
            if who in people and added <= at and end > at + GRACE:
                return (f"goal {goal} ({name}) with {who} lasted until {end:.1f}s, "
                        f"after their goodbye at {at:.1f}s")
    return None


def reason_heard(run: Run) -> str | None:
    farewells = _farewells(run)
    said = [(t, str(d.get("text", ""))) for t, _, _, a, d in run.of("speech")
            if a == run.robot]
    unheard = [(t, agent, str(d.get("text", ""))) for t, _, _, agent, d in run.of("unheard")]
    for t, _, _, person, data in run.of("plan-end"):
        text = str(data.get("text", ""))
        spoken = [at for at, words in said if words == text and at >= t - 1e-9]
        logged = any(who == person and words == text and at >= t - 1e-9
                     for at, who, words in unheard)
        if spoken and _gone(farewells, str(person), spoken[0]):
            return f"said {text!r} at {spoken[0]:.1f}s to {person}, who had left"
        if not spoken and not logged:
            return f"the plan's reason {text!r} ({t:.1f}s) neither said nor logged unheard"
    people = _goal_people(run)
    acts = [(t, task) for t, _, task, a, _ in run.of("act") if a == run.robot]
    cancels = [(t, who) for t, _, _, who, d in run.of("act-received")
               if d.get("act") == "CANCEL"]
    for t, _, task, _, data in run.of("goal-over"):
        name, with_, added = people.get(data.get("goal"), ("", set(), 0.0))
        if data.get("outcome") == "done" or not with_ or any(
                who in with_ and added <= at <= t + 1e-9 for at, who in cancels):
            continue  # nobody to tell, or they cancelled it: the reason is theirs
        since = max((at for at, node in acts if node == task and at <= t + 1e-9), default=t)
        spoken = any(since - 1e-9 <= at <= t + 1e-9 and not any(
            _gone(farewells, p, at) for p in with_) for at, _ in said)
        logged = any(who in with_ and abs(at - t) < 1e-6 for at, who, _ in unheard)
        if not spoken and not logged:
            return (f"goal {data.get('goal')} ({name}) ended {data.get('outcome')} at "
                    f"{t:.1f}s, its reason neither said to {' and '.join(sorted(with_))} "
                    f"nor logged unheard")
    return None


def _informs(run: Run) -> list[dict[str, Any]]:
    """The robot's informs of what a person missed: the task each is about, to whom, the
    inform task that says it (the next ``inform`` task started for them), its end."""
    out: list[dict[str, Any]] = []
    waiting: list[dict[str, Any]] = []
    ends: dict[str | None, str] = {}
    for t, kind, task, agent, data in run.rows:
        if kind == "inform" and "text" in data and "error" not in data:
            entry = {"t": t, "task": task, "to": agent, "text": data["text"], "node": None}
            out.append(entry)
            waiting.append(entry)
        elif kind == "task-start" and data.get("name") == "inform":
            partner = (data.get("roles") or {}).get("partner")
            match = next((e for e in waiting if e["to"] == partner), None)
            if match is not None:
                match["node"] = task
                waiting.remove(match)
        elif kind == "task-end":
            ends[task] = str(data.get("state", data.get("outcome", "")))
    for entry in out:
        entry["end"] = ends.get(entry["node"])
    return out


def _achieved_at(run: Run) -> dict[str | None, float]:
    """Plan task (its fact name) -> when it became EXECUTED in the robot's view."""
    return {task: t for t, _, task, agent, d in run.of("plan-task")
            if agent == run.robot and d.get("state") == "EXECUTED"}


def order(run: Run) -> str | None:
    achieved = _achieved_at(run)
    said = [(t, str(d.get("text", ""))) for t, _, _, a, d in run.of("speech")
            if a == run.robot]
    used: set[int] = set()
    heard: dict[str | None, list[tuple[float, float, str]]] = {}
    for entry in _informs(run):
        if entry["end"] != "told" or entry["task"] not in achieved:
            continue
        index = next((i for i, (t, text) in enumerate(said)
                      if i not in used and text == entry["text"] and t >= entry["t"] - 1e-9),
                     None)
        if index is not None:
            used.add(index)
            heard.setdefault(entry["to"], []).append(
                (said[index][0], achieved[entry["task"]], entry["text"]))
    for person, sentences in heard.items():
        sentences.sort()
        for (t1, e1, s1), (t2, e2, s2) in zip(sentences, sentences[1:], strict=False):
            if e2 < e1 - 1e-9:
                return (f"told {person} {s2!r} ({e2:.1f}s) at {t2:.1f}s after {s1!r} "
                        f"({e1:.1f}s) at {t1:.1f}s")
    return None


def belief(run: Run) -> str | None:
    views: dict[tuple[str | None, str | None], list[tuple[float, str]]] = {}
    for t, _, task, agent, d in run.of("plan-task"):
        views.setdefault((agent, task), []).append((t, str(d.get("state", ""))))
    for entry in _informs(run):
        if entry["end"] == "told" and not any(
                state in ("EXECUTED", "FAILED") and t >= entry["t"] - 1e-9
                for t, state in views.get((entry["to"], entry["task"]), [])):
            return (f"told {entry['to']} {entry['text']!r}, but {entry['task']} is not "
                    f"EXECUTED in their view")
    achieved = any(d.get("state") == "achieved" for _, _, _, _, d in run.of("shared-plan"))
    if not achieved:
        return None
    looked: dict[str, list[float]] = {}
    for t, _, _, _, d in run.of("fact-added"):
        if d.get("p") == "looksAt" and d.get("o") == run.robot and d.get("s") in run.people \
                and d.get("perspective", "robot") == "robot":
            looked.setdefault(str(d["s"]), []).append(t)
    farewells = _farewells(run)
    for (person, task), states in views.items():
        if person == run.robot or not states or states[-1][1] != "NOT_SEEN" \
                or _gone(farewells, str(person), run.end):
            continue
        since = states[-1][0]
        if any(t > since for t in looked.get(str(person), [])):
            return (f"{task} ended NOT_SEEN in {person}'s view although they looked at "
                    f"{run.robot} after missing it")
    return None


def one_voice(run: Run) -> str | None:
    sentences: list[tuple[float, str, str]] = []  # (began, request, text)
    ended: dict[str, float] = {}
    for t, kind, _, agent, data in run.rows:
        if kind == "speech" and agent == run.robot and data.get("request") is not None:
            sentences.append((t, str(data["request"]), str(data.get("text", ""))))
        elif kind in ("exec-result", "exec-cancel") and data.get("request") is not None:
            ended.setdefault(str(data["request"]), t)
    # in the order they began: a sentence begun over an earlier one means the one right
    # after that earlier one was too
    for (began, request, text), (then, _, said) in pairwise(sentences):
        end = ended.get(request, run.end)
        if then < end:
            return (f"began {said!r} at {then:.1f}s while still saying {text!r} "
                    f"(from {began:.1f}s to {end:.1f}s)")
    return None
