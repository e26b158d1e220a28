"""Interaction sessions: greeting, tasks, idle, farewell; no task with a stranger.

A session with a person is a ``session`` task (``schemes/session.yaml``) run
in the background (:attr:`shary.kernel.supervisor.Supervisor.background`: it lasts
as long as the interaction, and is not work left to do).  :class:`Sessions`
opens and closes them from the robot's perception:

- **the will to interact** opens one: the person comes near the robot
  (``PERSON isNear ROBOT``) and looks at it (``PERSON looksAt ROBOT``), the
  two added in either order within :attr:`Sessions.within` seconds (the
  chronicle :func:`will_to_interact`, a partially ordered conjunction,
  recognized by a :class:`~shary.kernel.agenda.ChronicleRecognizer` of its own);
  the robot greets them;
- **leaving** closes it: the robot perceives the person no more (no fact of
  where they are, ``isAt``, nor of where they look, ``looksAt``) for
  :attr:`Sessions.leave_after` seconds; the robot says goodbye.  Looking away,
  on the phone, is not leaving: the person is still there.  From the goodbye
  on, nothing waits for them and nothing is said to them (:meth:`Sessions.gone`):
  the goals with them end at once, cancelled with that reason (an ``unheard``
  row: there is nobody to tell it to), the tasks that would speak to them
  (an ``inform``) hear ``left``, and a joint subtask with them (their help
  asked for) is cancelled: the task that needed it fails over it, without them;
- :meth:`Sessions.start` opens, without a greeting, a session with every
  person already attending to the robot when the robot starts (a scenario
  begins with the interaction going on, as SHARY's do).

The agenda runs a goal that involves a person (one of its arguments, or who
asked for it) only inside a session with that person (:meth:`Sessions.admits`,
one of the agenda's gates); a goal of the robot alone (exploring a place) is
not an interaction and is not held.  A goal held for someone who does not
come to interact within :attr:`Sessions.wait_for` seconds is cancelled, the
reason in its ``goal-over`` row ("alice did not come to interact within
60 s"): the robot does not wait for ever for a person who is not there.  A
session is ``busy`` while a task with its person runs and ``idle`` otherwise
(its first act starting; the agenda's listeners told when the goal is over).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from shary.dialogue.attention import ATTENDS, LEFT, attending
from shary.dialogue.steps import say
from shary.dialogue.verbalize import proper
from shary.kernel.agenda import ChronicleRecognizer
from shary.kernel.recipes import (
    Chronicle,
    ChronicleAll,
    ChronicleEvent,
    Pattern,
    Recipe,
    Step,
    Term,
)

if TYPE_CHECKING:
    from shary.kernel.agenda import Goal
    from shary.kernel.supervisor import Supervisor, TaskRun

SESSION_TASK = "session"
NEAR = "isNear"
AT = "isAt"


def will_to_interact(robot: str, within: float) -> Chronicle:
    """The chronicle of the will to interact: a person comes near ``robot`` and looks at
    it, in either order, within ``within`` seconds (a partially ordered conjunction)."""
    def added(predicate: str) -> ChronicleEvent:
        return ChronicleEvent("added", Pattern(Term("param", "person"),
                                               Term("const", predicate),
                                               Term("const", robot)))

    return Chronicle("will-to-interact", (ChronicleAll((added(NEAR), added(ATTENDS)),
                                                      within),),
                     SESSION_TASK, {"partner": Term("param", "person")},
                     doc="a person comes near the robot and looks at it, in either order")


class Sessions:
    """Opens and closes interaction sessions (see the module's docstring)."""

    def __init__(self, sup: Supervisor, *, within: float = 10.0, leave_after: float = 2.0,
                 wait_for: float = 60.0, perspective: str = "robot"):
        self.sup = sup
        self.within = within
        self.leave_after = leave_after
        self.wait_for = wait_for
        """How long a goal waits for its people to come to interact before it is dropped."""
        self._held: dict[int, Any] = {}
        """Goal id -> the timer that drops it if its people never come (while held)."""
        self.perspective = perspective
        self.open: dict[str, TaskRun] = {}
        """Person -> their session's task run, while it is open (farewell included)."""
        self._leaving: dict[str, Any] = {}
        self._gone: set[str] = set()
        """People who left (their session closed by leaving) and have not come back."""
        self.subscriptions = [
            sup.facts.subscribe(self._on_fact, predicate=p, perspective=perspective)
            for p in (ATTENDS, AT)]
        self.chronicle = will_to_interact(sup.robot, within)
        self.recognizer: ChronicleRecognizer | None = None
        sup.agenda.admits.append(self.admits)
        sup.agenda.listeners.append(self._goal_over)
        sup.act_listeners.append(self._act)
        sup.dialogue.sessions = self

    def close(self) -> None:
        """Stop watching (sessions that are open stay open)."""
        for subscription in self.subscriptions:
            self.sup.facts.unsubscribe(subscription)
        if self.recognizer is not None:
            self.recognizer.close()
        for timer in [*self._leaving.values(), *self._held.values()]:
            timer.cancel()
        self._leaving.clear()
        self._held.clear()

    # -- who is a person ----------------------------------------------------------------

    def is_person(self, thing: Any) -> bool:
        """Whether the robot believes ``thing`` is a person (text, a number: no)."""
        try:
            return self.sup.facts.holds(str(thing), "type", "Human", self.perspective)
        except ValueError:  # not a name at all (the words of an inform task)
            return False

    def people(self) -> list[str]:
        return sorted(str(s) for s, p, o in self.sup.facts.triples(self.perspective)
                      if str(p) == "type" and str(o) == "Human")

    # -- opening and closing ------------------------------------------------------------

    def start(self) -> None:
        """Open, silently, a session with every person attending to the robot now, and
        watch for the will to interact from now on."""
        if self.recognizer is None:
            self.recognizer = ChronicleRecognizer(
                self.sup, self.perspective, {self.chronicle.name: self.chronicle},
                self._willing)
        for person in self.people():
            if person not in self.open and attending(self.sup.facts, person, self.sup.robot,
                                                     self.perspective):
                self.begin(person, greet=False)

    def begin(self, person: str, greet: bool = True) -> TaskRun:
        """Open a session with ``person`` (greeting them unless told not to)."""
        greeting = f"Hello, {proper(person)}." if greet else ""
        self._gone.discard(person)
        self.sup.record("session-open", agent=person, greeted=greet)
        run = self.sup.start_task(SESSION_TASK, {"partner": person, "greeting": greeting},
                                  background=True, on_finish=lambda r: self._over(person, r))
        run.deliver("arrived" if greet else "engaged")
        self.open[person] = run
        self.sup.agenda.reconsider()
        return run

    def _over(self, person: str, run: TaskRun) -> None:
        if self.open.get(person) is run:
            del self.open[person]
        self.sup.record("session-close", agent=person)

    def tracked(self, person: str) -> bool:
        """Whether the robot perceives the person: where they are, or where they look."""
        facts = self.sup.facts
        return bool(facts.objects(person, AT, self.perspective)
                    or facts.objects(person, ATTENDS, self.perspective))

    def _on_fact(self, event: Any) -> None:
        person = str(event.subject)
        session = self.open.get(person)
        if session is not None and self.is_person(person):
            self._watch_leaving(person, session)

    def _willing(self, chronicle: Chronicle, args: dict[str, Any]) -> None:
        """The will to interact was recognized: open a session, with a greeting."""
        person, facts, robot = str(args["partner"]), self.sup.facts, self.sup.robot
        still = (facts.holds(person, NEAR, robot, self.perspective)
                 and facts.holds(person, ATTENDS, robot, self.perspective))
        if still and self.is_person(person) and person not in self.open:
            self.begin(person)

    def _watch_leaving(self, person: str, session: TaskRun) -> None:
        timer = self._leaving.pop(person, None)
        if timer is not None:
            timer.cancel()
        if not self.tracked(person):
            self._leaving[person] = self.sup.loop.call_later(self.leave_after, self._left,
                                                             person, session)

    @property
    def timing(self) -> bool:
        """Whether someone's leaving is being timed (a farewell may be due): a run that
        ends when nothing is left to do waits for it."""
        return bool(self._leaving)

    def _left(self, person: str, session: TaskRun) -> None:
        self._leaving.pop(person, None)
        if self.open.get(person) is session and not session.ended \
                and not self.tracked(person):
            self.sup.record("chronicle", chronicle="leaving", bindings={"person": person})
            self._gone.add(person)
            session.deliver(LEFT)
            self._release(person)

    def gone(self, person: str) -> bool:
        """Whether ``person`` left (the robot said goodbye) and has not come back."""
        return person in self._gone

    def _release(self, person: str) -> None:
        """``person`` left: the goals with them end now, and the tasks that would still
        speak to them hear it (an inform ends untold)."""
        from shary.kernel.agenda import OVER

        reason = f"{person} left"
        for goal in [g for g in self.sup.agenda.goals
                     if g.state not in OVER and person in self.involved(g)]:
            self.sup.record("unheard", agent=person, text=reason, why=reason)
            self.sup.agenda.cancel(goal, reason)
        for run in self.sup.tasks_with(person):
            if run.expects(LEFT):
                run.deliver(LEFT)
            elif run.parent is not None and run.node in self.sup.runs:
                # a joint subtask with them (asking their help): it fails now, and the
                # task that needed it decides what comes next, without them
                self.sup.cancel_task(run.node, reason)

    # -- the agenda ------------------------------------------------------------------------

    def involved(self, goal: Goal) -> set[str]:
        """The people a goal is with: its arguments that are people, and who asked."""
        people = {str(v) for v in goal.args.values() if self.is_person(v)}
        if goal.initiator is not None:
            people.add(goal.initiator)
        return people

    def is_open(self, person: str) -> bool:
        """Whether a session with ``person`` is open and past its greeting."""
        run = self.open.get(person)
        return run is not None and not run.ended and run.instance is not None \
            and run.instance.is_active("open")

    def admits(self, goal: Goal) -> bool:
        """The agenda's gate: every person of the goal is in an open session (a goal
        held starts the wait after which it is dropped, :attr:`wait_for`)."""
        if all(self.is_open(p) for p in self.involved(goal)):
            return True
        if goal.id not in self._held:
            self._held[goal.id] = self.sup.loop.call_later(self.wait_for, self._not_come, goal)
        return False

    def _not_come(self, goal: Goal) -> None:
        from shary.kernel.agenda import PENDING

        self._held.pop(goal.id, None)
        absent = sorted(p for p in self.involved(goal) if not self.is_open(p))
        if goal.state == PENDING and absent:
            reason = (f"{' and '.join(absent)} did not come to interact within "
                      f"{self.wait_for:g} s")
            for person in absent:  # never in a session: nobody there to say it to
                self.sup.record("unheard", agent=person, text=reason, why=reason)
            self.sup.agenda.cancel(goal, reason)

    def _act(self, run: TaskRun, state: Any, agent: str) -> None:
        if run.type.name == SESSION_TASK:
            if state.act == "INTERACT":
                self.sup.agenda.reconsider()  # greeted: what waited for the session may go
            return
        goal = self.sup.agenda.active
        # a goal's task begins (its first act, as the agenda starts it): its sessions are busy
        if goal is not None and run.parent is None and goal.task == run.type.name \
                and goal.run in (None, run) and not run.acts:
            self._tell(goal, "task-started")

    def _goal_over(self, goal: Goal) -> None:
        self._tell(goal, "task-over")

    def _tell(self, goal: Goal, event: str) -> None:
        for person in self.involved(goal):
            session = self.open.get(person)
            if session is not None and session.expects(event):
                session.deliver(event)


# -- the session's recipes ----------------------------------------------------------------

def farewell(run: TaskRun, recipe: Recipe) -> list[Step]:
    """FAREWELL: say goodbye to the partner by name."""
    return [say("goodbye", f"Goodbye, {proper(str(run.env['partner']))}.")]
