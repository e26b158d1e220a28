"""The ``keys-matter`` invariant: every key a campaign draws changes the run it is drawn for.

A campaign's story says what the people did ("alice mounts in 20-22s", "looks
at phone for 5s when pick starts"); its tables are only worth what that story
is.  A key the simulation ignores, or one drawn equal to what the person does
unasked, makes a run that does not test what it says, and no invariant on the
engine can see it: it is a fault of the generator (:mod:`sim.fuzz.behaviours`),
found here.

For each key drawn (:attr:`~sim.fuzz.behaviours.Variation.keys`) the run is
made again with the same seed and that key taken away
(:meth:`~sim.fuzz.behaviours.Variation.without`), and compared with the run as
drawn: its logged rows one by one, then what the world makes true at its end.
Runs are deterministic for a seed, so the first row that differs shows the key
mattered, and the run without it stops there (:class:`Follower`, attached where
the console attaches): a key costs the simulation up to the moment it takes
effect, not a whole run.  A key whose run comes out the same, row for row, is a
violation.

A key's moment may not come in a run: the answer to a second ASK-TASK where
the robot asked once, a distraction when the robot starts a hand-over it never
starts, a weld quality for a seam never welded.  Each key says when its moment
comes (its *cue*, :attr:`~sim.fuzz.behaviours.Drawn.cue`), read from the run's
rows by :func:`reached`; a key not reached is counted (the campaign's report
says how many) but not run again, and not a violation: the people did
something else first.  A cue the generator gives wrongly cannot hide a key that
never matters, since every kind of key is reached in some run of a campaign,
and :func:`reached` is tested against runs where it is (tests/test_fuzz.py).
"""

from __future__ import annotations

from typing import Any

from .behaviours import Variation
from .drawn import Drawn

__all__ = ["BLINK", "TIE", "Follower", "keys_matter", "reached", "same_without"]

BLINK = 0.35
"""Seconds within which a fact dropped and seen again is a blink of the perception."""
TIE = 0.2
"""Seconds by which a moment must pass a deadline to count: two things due at one
instant (a take and a turn of the head) may come in either order."""


class _Diverged(Exception):
    """The run without a key has logged a row the run with it did not."""


class Follower:
    """Follows a run against the rows of another run of the same scenario and seed, and
    stops it at the first row that differs (the console's attachment interface:
    ``attach``, ``observe``, ``between``, :mod:`shary.console.live`)."""

    def __init__(self, rows: list[Any]):
        self.rows = rows
        self.seen = 0
        self.differs = False

    def attach(self, supervisor: Any) -> None:
        """Nothing to steer: a follower only reads."""

    def observe(self, t: float, kind: str, task: str | None, agent: str | None,
                data: dict[str, Any]) -> None:
        if not self.differs and (self.seen >= len(self.rows)
                                 or tuple(self.rows[self.seen]) != (t, kind, task, agent, data)):
            self.differs = True
        self.seen += 1

    def between(self, now: float) -> None:
        if self.differs:
            raise _Diverged


def _holds(data: dict[str, Any], wanted: dict[str, Any]) -> bool:
    """Whether ``data`` has every item of ``wanted`` (dictionaries compared item by item)."""
    for name, value in wanted.items():
        have = data.get(name)
        if isinstance(value, dict):
            if not isinstance(have, dict) or not _holds(have, value):
                return False
        elif have != value:
            return False
    return True


def reached(cue: tuple[Any, ...], rows: list[Any]) -> bool:
    """Whether the moment of a key with ``cue`` came in the run of ``rows``:

    ``()``
        from the start (noise, where a person looks, a bystander);
    ``("at", SECONDS)``
        the run went on past that time;
    ``("asked", ACT, PERSON, K)``
        the robot said ACT to the end K times in tasks with PERSON in a role (a question
        cut short, the person turning away, is not heard: it is asked again);
    ``("agreed", ACT, PERSON)``
        PERSON said yes (H-AGREE) in a task where the robot began ACT;
    ``("answered", ACT, PERSON, K, REPLY)``
        the robot said ACT to PERSON to the end K times and then heard their REPLY
        (a late answer to a question given up is not heard);
    ``("starts", ATOMIC, PERSON)``
        the robot started ATOMIC with PERSON among its arguments;
    ``("offered", PERSON, SECONDS, UNTIL)``
        the robot held something out to PERSON while it saw them look at it for SECONDS
        (a person takes only what they see held out, and takes time to), before UNTIL
        (when they walk out; None: they stay);
    ``("blink", PREDICATE)``
        a fact of PREDICATE blinked in the robot's belief: dropped, and back within
        :data:`BLINK` (a flicker the perception's hold did not filter out; a person's
        own look-away lasts longer, sim/fuzz/behaviours.py's ``GLANCE``);
    ``("exec", ATOMIC)``
        the robot started ATOMIC;
    ``("row", KIND, AGENT, DATA)``, ``("row", KIND, AGENT, DATA, (MEMBER, SECONDS))``
        a row of KIND (by AGENT, unless None) whose data has DATA's items (and MEMBER
        not killed within SECONDS of it: a person killed before they reply, or while
        they mount a panel, does neither);
    ``("decided", PERSON, K)``, ``("acted", PERSON)``, ``("undecided", PERSON)``
        in a shared plan, K decisions of PERSON's were taken, PERSON began an action,
        a decision of PERSON's waited for an action that did not begin in time;
    ``("done", LABEL)``
        a plan task whose label begins with LABEL was executed;
    ``("due-for", LABEL, SECONDS, PERSON)``
        a task of the robot's whose label begins with LABEL stayed due or under way for
        SECONDS (a partner acting before it looks at what is due after their delay),
        PERSON not yet walking out;
    ``("away", I, MOMENTS, PERSON, ROBOT)``
        the I-th of PERSON's look-aways came while ROBOT saw them look at it, and not
        while another of theirs lasted (a look-away at a look-away is nothing new);
        MOMENTS are all their look-aways, each (when, seconds): when is a time, or the
        label with which a task of the robot's begins, the first such task not taken by
        an earlier one (as sim/stack/partner.py takes them).
    """
    if not cue:
        return True
    what, *args = cue
    if what == "at":
        return bool(rows) and rows[-1][0] > args[0]
    if what == "asked":
        return len(_said(rows, args[0], args[1])) >= args[2]
    if what == "answered":
        act, person, k, reply = args
        said = _said(rows, act, person)
        return len(said) >= k and any(
            r[1] == "act-received" and r[3] == person and r[4].get("act") == reply
            and r[0] >= said[k - 1] for r in rows)
    if what == "agreed":
        act, person = args[0], args[1]
        reply = "H-AGREE"
        tasks = {r[2] for r in rows if r[1] == "task-start"
                 and person in (r[4].get("roles") or {}).values()}
        asking = {r[2] for r in rows if r[1] == "act" and r[4].get("act") == act
                  and r[2] in tasks}
        return any(r[1] == "act-received" and r[3] == person
                   and r[4].get("act") == reply and r[2] in asking for r in rows)
    if what in ("starts", "exec"):
        return any(r[1] == "exec-request" and r[4].get("atomic") == args[0]
                   and (what == "exec" or args[1] in r[4].get("args", {}).values())
                   or (r[1] == "robot-action" and r[4].get("action") == args[0]
                       and what == "exec") for r in rows)
    if what == "offered":
        return _offered_seen(rows, *args)
    if what == "blink":
        dropped: dict[tuple[Any, ...], float] = {}
        for t, kind, _, _, data in rows:
            if kind in ("fact-added", "fact-removed") and data.get("p") == args[0] \
                    and data.get("perspective") == "robot":
                fact = (data.get("s"), data.get("o"))
                if kind == "fact-removed":
                    dropped[fact] = t
                elif fact in dropped and t - dropped.pop(fact) <= BLINK:
                    return True
        return False
    if what == "row":
        kind, agent, data = args[:3]
        killed = None
        if len(args) > 3:
            member, within = args[3]
            killed = next((r[0] - within for r in rows
                           if r[1] == "agent-killed" and r[3] == member), None)
        return any(r[1] == kind and (agent is None or r[3] == agent) and _holds(r[4], data)
                   and (killed is None or r[0] < killed) for r in rows)
    if what == "decided":
        return sum(r[1] == "plan-decision" and r[3] == args[0] for r in rows) >= args[1]
    if what == "acted":
        return any(r[1] == "person-action" and r[3] == args[0] for r in rows)
    if what == "undecided":
        return any(r[1] == "plan-match" and r[3] == args[0]
                   and str(r[4].get("why", "")).startswith("no action started") for r in rows)
    if what == "due-for":
        return _due_for(rows, *args)
    if what == "away":
        return _away_seen(rows, *args)
    return any(r[1] == "plan-task" and r[4].get("state") == "EXECUTED"
               and str(r[4].get("name", "")).startswith(args[0]) for r in rows)


def _said(rows: list[Any], act: str, person: str) -> list[float]:
    """When the robot finished saying ``act`` to the end in a task with ``person`` in a
    role: its sentence (the first after the act began, the robot's last act) done."""
    tasks = set()
    last: tuple[str, Any] | None = None  # the robot's last act and its task
    saying: dict[str, bool] = {}  # speak request -> it says ``act`` to them
    said: list[float] = []
    for t, kind, task, _, data in rows:
        if kind == "task-start" and person in (data.get("roles") or {}).values():
            tasks.add(task)
        elif kind == "act":
            last = (str(data.get("act")), task)
        elif kind == "exec-request" and data.get("atomic") == "speak" and last is not None:
            saying[str(data.get("request"))] = last[0] == act and last[1] in tasks
            last = None  # one sentence an act
        elif kind == "exec-result" and saying.pop(str(data.get("request")), False) \
                and data.get("status") == "done":
            said.append(t)
    return said


class _Gaze:
    """Where the robot sees a person look, read row by row: the target of their newest
    ``looksAt`` fact still held (a fact is dropped only some time after it stops, so
    for a while the old target and the new one are both held), None when none is (a
    look away at nothing)."""

    def __init__(self, person: str):
        self.person = person
        self.held: dict[str, int] = {}  # target -> the row that added it
        self.rows = 0

    def see(self, row: Any) -> None:
        self.rows += 1
        _, kind, _, _, data = row
        if kind in ("fact-added", "fact-removed") and data.get("s") == self.person \
                and data.get("p") == "looksAt" and data.get("perspective") == "robot":
            if kind == "fact-added":
                self.held[str(data.get("o"))] = self.rows
            else:
                self.held.pop(str(data.get("o")), None)

    @property
    def target(self) -> str | None:
        return max(self.held, key=self.held.__getitem__) if self.held else None


def _offered_seen(rows: list[Any], person: str, seconds: float, until: float | None
                  ) -> bool:
    if until is not None:
        rows = [r for r in rows if r[0] < until]
        if not rows:
            return False
    gaze = _Gaze(person)
    giving: dict[str, str] = {}  # request -> robot, while a give to the person runs
    since: float | None = None  # since when a robot giving to them is looked at
    for row in rows:
        t, kind, _, agent, data = row
        gaze.see(row)
        if kind == "exec-request" and data.get("atomic") == "give" \
                and person in data.get("args", {}).values():
            giving[data["request"]] = str(agent)
        elif kind == "exec-result":
            giving.pop(data.get("request"), None)
        if gaze.target in giving.values():
            since = t if since is None else since
        elif since is not None:
            if t - since > seconds + TIE:
                return True
            since = None
    return since is not None and rows[-1][0] - since > seconds + TIE


def _due_for(rows: list[Any], label: str, seconds: float, person: str) -> bool:
    out = next((r[0] for r in rows if r[1] == "person-action" and r[3] == person
                and r[4].get("args", {}).get("to") == "door"), None)
    if out is not None:
        rows = [r for r in rows if r[0] < out]
        if not rows:
            return False
    due: dict[str, float] = {}  # task -> since when it is due (or under way)
    for t, kind, task, _, data in rows:
        if kind != "plan-task" or not str(data.get("name", "")).startswith(label):
            continue
        if data.get("state") == "TODO":
            due.setdefault(str(task), t)
        elif data.get("state") != "ONGOING" and str(task) in due \
                and t - due.pop(str(task)) >= seconds:
            return True
    return any(rows[-1][0] - since >= seconds for since in due.values())


def _away_seen(rows: list[Any], index: int, moments: tuple[tuple[Any, float], ...],
               person: str, robot: str) -> bool:
    """Whether the ``index``-th look-away of ``person`` came while ``robot`` saw them look
    at it and no other of theirs was under way (see :func:`reached`)."""
    waiting = {i: m for i, (m, _) in enumerate(moments) if isinstance(m, str)}
    came: dict[int, tuple[int, float]] = {  # look-away -> the row and time it came
        i: (-1, float(m)) for i, (m, _) in enumerate(moments) if not isinstance(m, str)}
    for n, (t, kind, _, agent, data) in enumerate(rows):
        if kind == "plan-task" and agent == robot and data.get("state") == "ONGOING":
            name = str(data.get("name", ""))
            first = next((i for i, m in waiting.items() if name.startswith(m)), None)
            if first is not None:
                came[first] = (n, t)
                del waiting[first]
    if index not in came or not rows:
        return False
    at, when = came[index]
    if at < 0:  # at a time: the row before which it came
        if rows[-1][0] <= when:
            return False
        at = next(n for n, r in enumerate(rows) if r[0] >= when)
    if any(when_k <= when < when_k + moments[k][1]
           for k, (n_k, when_k) in came.items() if k != index and (when_k, n_k) < (when, at)):
        return False  # already looking away: this one turns nobody's head
    gaze = _Gaze(person)
    for row in rows[:at]:
        gaze.see(row)
    return gaze.target == robot


def same_without(variation: Variation, key: Drawn, rows: list[Any],
                 truth: frozenset[Any]) -> bool:
    """Whether the run of ``variation`` without ``key`` is the same as the one with it
    (whose logged ``rows`` and end ``truth`` are given)."""
    follower = Follower(rows)
    try:
        result = variation.without(key).run(console=follower)
    except _Diverged:
        return False
    return (not follower.differs and follower.seen == len(rows)
            and result.truth == truth)


def keys_matter(variation: Variation, rows: list[Any], truth: frozenset[Any]
                ) -> tuple[str | None, int]:
    """The first drawn key of ``variation`` whose moment came and whose run is the same
    without it, in one line (None when there is none), and how many keys were not
    reached (see the module's docstring)."""
    unreached = 0
    for key in variation.keys:
        if not reached(key.cue, rows):
            unreached += 1
        elif same_without(variation, key, rows, truth):
            return (f"drawn '{key.says}' changed nothing: the run without it is the same",
                    unreached)
    return None, unreached
