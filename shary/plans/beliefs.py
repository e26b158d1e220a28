"""Theory of mind: what the robot estimates a human believes about the plan.

JAHRVIS's Human Plan Manager keeps, for each human, an estimate of their
mental state about the shared plan (Section VI-C.2).  Here that estimate is
the human's *view* of each task (:mod:`shary.plans.states`), kept as
``taskState`` facts in the human's perspective of the fact base.  A robot
action done while the human was not looking at the robot or at what it acted
on (``looksAt`` facts from perception) becomes NOT_SEEN in that view; the
robot then informs them with a generated sentence ("I placed the green cube
on the blue cube") when they look back, or before their own next action needs
it, and the task becomes EXECUTED in their view.  The inform is an ``inform``
task (:mod:`shary.dialogue.attention`): the robot speaks only once the human
attends to it, calls them by name if they do not, and gives up without
speaking if they still do not (the task stays NOT_SEEN, told at their next
glance).

One estimate lasts as long as the follower, across replans: what a person
missed is bound to the task it is about (:class:`Missed`: the plan's task
states, the task, the sentence made when it happened), not to a position in a
plan that a replan renumbers, and what they missed is told oldest first, in
the order it happened, whichever plan it was in.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["HumanBeliefs", "Missed"]


@dataclass(frozen=True)
class Missed:
    """A robot's task a person did not see, bound to the plan it was done in."""

    states: Any
    """The :class:`~shary.plans.states.TaskStates` of that plan (told: NOT_SEEN -> EXECUTED)."""
    task: int
    about: frozenset[str]
    """What looking at means seeing it: the robot and the task's objects."""
    text: str
    """What the robot says of it ("I placed the green cube on the blue cube.")."""

    @property
    def fact(self) -> str:
        return self.states.fact_name(self.task)


class HumanBeliefs:
    """The humans' estimated beliefs about a shared plan, and the informs that fix them."""

    def __init__(self, follower: Any):
        self.follower = follower
        self.sup = follower.sup
        self.unseen: dict[str, list[Missed]] = {h: [] for h in follower.humans}
        """Per human, the robot's tasks they missed, oldest first (any plan)."""
        self._speaking: set[str] = set()
        self._subscriptions = [self.sup.facts.subscribe(self._looks, subject=h)
                               for h in follower.humans]

    @property
    def speaking(self) -> bool:
        """Whether an inform is under way (waiting for attention, or said)."""
        return bool(self._speaking)

    def watching(self, human: str, task: int) -> bool:
        """Whether ``human`` looks at the robot or at something the task is about."""
        return self._sees(human, self._about(task))

    def _about(self, task: int) -> frozenset[str]:
        return frozenset({self.sup.robot, *map(str, self.follower.params.get(task, ()))})

    def _sees(self, human: str, about: frozenset[str]) -> bool:
        return bool({str(o) for o in self.sup.facts.objects(human, "looksAt")} & about)

    def robot_did(self, task: int) -> None:
        """The robot achieved ``task``: in each human's view, seen or missed."""
        follower = self.follower
        states = follower.states
        robot = follower.robot
        model = robot.model_for(follower.plan.primitive[task].name, robot.models.robot)
        for human in follower.humans:
            if model is not None and model.executor is None:  # a wait: nothing to miss
                states.send(task, "achieved", [human])
            elif self.watching(human, task):
                states.send(task, "achieved", [human])
            else:
                states.send(task, "achieved-unseen", [human])
                self.unseen[human].append(Missed(states, task, self._about(task),
                                                 self._sentence(task, human)))
                self.sup.record("belief", task=states.fact_name(task), agent=human,
                                state="NOT_SEEN", why="looked away")

    def _sentence(self, task: int, human: str) -> str:
        """What the robot will say of ``task`` to ``human`` (made now: a replan may come
        before it is said, and the plan's task numbers with it)."""
        follower = self.follower
        name = follower.plan.primitive[task].name
        values = [follower.sup.robot, *map(str, follower.objects_of(task))]
        try:
            return self.sup.speech.say({"act": "inform-done",
                                        "about": f"{name}({', '.join(values)})", "to": human},
                                       self.sup.robot)
        except (ValueError, KeyError) as err:
            self.sup.record("inform", agent=human, task=follower.states.fact_name(task),
                            error=str(err))
            return f"I did {name}."

    def needs(self, human: str) -> None:
        """``human``'s own action is next, or the plan is over: what they missed they
        should know now (said once they attend, as JAHRVIS's Communication Manager
        perceives the human before speaking)."""
        self._inform(human, attentive=False)

    def _looks(self, event: Any) -> None:
        if str(event.predicate).rsplit("#", 1)[-1] != "looksAt" or event.kind != "added":
            return
        human = self.sup.facts.name(event.subject)
        if self.unseen.get(human):
            self.sup.loop.call_soon(self._inform, human, True)

    def _inform(self, human: str, attentive: bool) -> None:
        """Tell ``human`` the oldest task they missed, one sentence at a time.  On a
        glance (``attentive``) only if they look at the robot or the task; otherwise
        through an ``inform`` task (:func:`shary.dialogue.attention.tell`), which waits
        for their attention, calls them by name, or gives up without speaking."""
        from shary.dialogue.attention import departed, tell

        pending = self.unseen.get(human)
        if not pending or human in self._speaking:
            return
        missed = pending[0]
        if attentive and not self._sees(human, missed.about):
            return  # they looked elsewhere: wait for their attention on it
        follower = self.follower
        self._speaking.add(human)
        self.sup.record("inform", task=missed.fact, agent=human, text=missed.text)

        def said(run: Any) -> None:
            self._speaking.discard(human)
            if run.outcome != "done" and self._sees(human, missed.about) \
                    and not departed(self.sup, human):
                self._inform(human, True)  # they looked back as it gave up: tell them now
                return
            if run.outcome != "done":  # not heard: it stays NOT_SEEN, said when they look back
                if follower.finished is not None:  # ... if they ever do: say why it stays
                    self.sup.record("belief", task=missed.fact, agent=human,
                                    state="NOT_SEEN", why="untold",
                                    reason=f"{human} did not attend after the plan ended")
                return
            if missed in pending:
                pending.remove(missed)
            missed.states.send(missed.task, "seen", [human], reason="informed")
            if pending:
                self._inform(human, False)

        tell(self.sup, human, missed.text, on_finish=said)
