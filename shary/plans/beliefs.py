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
"""

from __future__ import annotations

from typing import Any

__all__ = ["HumanBeliefs"]


class HumanBeliefs:
    """The humans' estimated beliefs about one plan, and the informs that fix them."""

    def __init__(self, follower: Any):
        self.follower = follower
        self.sup = follower.sup
        self.unseen: dict[str, list[int]] = {h: [] for h in follower.humans}
        """Per human, the robot's tasks they missed, oldest first."""
        self._speaking: set[str] = set()
        self._subscriptions = [self.sup.facts.subscribe(self._looks, subject=h)
                               for h in follower.humans]

    def stop(self) -> None:
        for subscription in self._subscriptions:
            self.sup.facts.unsubscribe(subscription)
        self._subscriptions = []

    @property
    def speaking(self) -> bool:
        """Whether an inform is under way (waiting for attention, or said)."""
        return bool(self._speaking)

    def watching(self, human: str, task: int) -> bool:
        """Whether ``human`` looks at the robot or at something the task is about."""
        seen = {str(o) for o in self.sup.facts.objects(human, "looksAt")}
        about = {self.sup.robot, *map(str, self.follower.params.get(task, ()))}
        return bool(seen & about)

    def robot_did(self, task: int) -> None:
        """The robot achieved ``task``: in each human's view, seen or missed."""
        states = self.follower.states
        robot = self.follower.robot
        model = robot.model_for(self.follower.plan.primitive[task].name, robot.models.robot)
        for human in self.follower.humans:
            if model is not None and model.executor is None:  # a wait: nothing to miss
                states.send(task, "achieved", [human])
            elif self.watching(human, task):
                states.send(task, "achieved", [human])
            else:
                states.send(task, "achieved-unseen", [human])
                self.unseen[human].append(task)
                self.sup.record("belief", task=states.fact_name(task), agent=human,
                                state="NOT_SEEN", why="looked away")

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
        from shary.dialogue.attention import tell

        pending = self.unseen.get(human)
        if not pending or human in self._speaking:
            return
        task = pending[0]
        if attentive and not self.watching(human, task):
            return  # they looked elsewhere: wait for their attention on it
        follower = self.follower
        name = follower.plan.primitive[task].name
        values = [follower.sup.robot, *map(str, follower.objects_of(task))]
        try:
            text = self.sup.speech.say({"act": "inform-done",
                                        "about": f"{name}({', '.join(values)})", "to": human},
                                       self.sup.robot)
        except (ValueError, KeyError) as err:
            text = f"I did {name}."
            self.sup.record("inform", agent=human, task=follower.states.fact_name(task),
                            error=str(err))
        self._speaking.add(human)
        self.sup.record("inform", task=follower.states.fact_name(task), agent=human, text=text)

        def said(run: Any) -> None:
            self._speaking.discard(human)
            if run.outcome != "done":  # not heard: it stays NOT_SEEN, said when they look back
                if follower.finished is not None:  # ... if they ever do: say why it stays
                    self.sup.record("belief", task=follower.states.fact_name(task),
                                    agent=human, state="NOT_SEEN", why="untold",
                                    reason=f"{human} did not attend after the plan ended")
                return
            if task in pending:
                pending.remove(task)
            follower.states.send(task, "seen", [human], reason="informed")
            if pending:
                self._inform(human, False)

        tell(self.sup, human, text, on_finish=said)
