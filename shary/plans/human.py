"""The Human Plan Manager: what the human does, matched against the plan.

JAHRVIS's HPM (Section VI-C.2) receives the recognized human actions
(:mod:`shary.recognition`: possibly started, progressing, achieved) and decides
what each one means for the plan:

* it is the human's task due now (or one option of their decision: the
  branch it starts is followed, the others become UNPLANNED): started makes
  it ONGOING, achieved EXECUTED;
* it is a task further on in the plan, the human's or the robot's ("I placed
  the cube you were going to place"): an unexpected but **useful** action,
  accepted: that task is EXECUTED, with the tasks before it that only
  prepared it (same objects), and the robot does not do it again;
* it repeats what is already done, or nobody caused it: nothing;
* it matches nothing the plan expects: a **harmful** action, the plan is
  replanned from what is now true.

A human's wait (``WaitForCube``) is no movement and no effect: when nothing
of theirs starts within ``decision_wait`` seconds of it being due, it is
taken as done (the leave-it-to-the-robot branch of a decision).

A human's task that becomes NOT_STARTING (due too long) or NOT_FINISHED
(started, never ended) climbs :mod:`shary.plans.recovery`'s ladder: look at
what the robot cannot see, ask them ("Please pick the stick.", "Are you going
to place the stick?") through an ``inform`` task, which waits for their
attention (if they never attend, they left, and the plan fails: its partner
is not there to do their part), take it over, replan.  A task under way
whose objects are out of the camera's view is looked at before its effect is
needed.
"""

from __future__ import annotations

from typing import Any

__all__ = ["HumanPlanManager"]


class HumanPlanManager:
    """Matches recognitions to one plan (see the module's documentation)."""

    def __init__(self, follower: Any, decision_wait: float = 6.0):
        self.follower = follower
        self.sup = follower.sup
        self.ontology = follower.robot.ontology
        self.decision_wait = decision_wait
        self._timer: Any = None

    def listen(self) -> None:
        if self.sup.recognizer is not None:
            self.sup.recognizer.listeners.append(self.recognized)

    def stop(self) -> None:
        if self.sup.recognizer is not None and self.recognized in self.sup.recognizer.listeners:
            self.sup.recognizer.listeners.remove(self.recognized)
        if self._timer is not None:
            self._timer.cancel()

    # -- due tasks ----------------------------------------------------------------------

    def due(self, tasks: list[Any]) -> None:
        """The human's tasks (one, or a decision's options) are due now."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        waits = [t for t in tasks if self._is_wait(t.name)]
        if waits:
            self._timer = self.sup.loop.call_later(self.decision_wait, self._waited, waits[0].id)

    def _waited(self, task: int) -> None:
        self._timer = None
        follower = self.follower
        if task in follower.current:
            self.sup.record("plan-match", task=follower.states.fact_name(task),
                            agent=follower.plan.primitive[task].agent, match="waits",
                            why=f"no action started within {self.decision_wait:g}s")
            follower.human_did(task)

    def _is_wait(self, name: str) -> bool:
        cls = self.ontology.action_class(name)
        wait = self.ontology.action_class("wait")
        return cls is not None and wait is not None and self.ontology.is_a(cls, wait)

    def ask(self, task: int, act: str = "request") -> None:
        """Ask the human for their task: ``request`` one not started ("Please pick the
        stick."), ``ask-going`` one not finished ("Are you going to place the stick?");
        see the module, and :mod:`shary.plans.recovery` for when."""
        from shary.dialogue.attention import tell

        follower = self.follower
        spec = follower.plan.primitive[task]
        human = str(follower.agents.get(task, spec.agent))
        values = [human, *map(str, follower.objects_of(task))]
        try:
            text = self.sup.speech.say({"act": act, "about":
                                        f"{spec.name}({', '.join(values)})", "to": human},
                                       self.sup.robot)
        except (ValueError, KeyError):
            text = f"{human}, it is your turn."
        self.sup.record("plan-ask", task=follower.states.fact_name(task), agent=human, text=text)
        generation = follower.generation

        def asked(run: Any) -> None:
            if generation != follower.generation or task not in follower.current \
                    or follower.finished:
                return
            if run.outcome != "done":
                follower.partner_absent(task, human)
            else:  # heard: they have the ladder's patience to act on it
                follower.recovery.wait(task, "ask")

        tell(self.sup, human, text, on_finish=asked)

    # -- recognitions -------------------------------------------------------------------

    def recognized(self, recognition: Any) -> None:
        """The recognizer's listener: queue the work on the loop (it runs in fact delivery)."""
        self.follower.progressed()
        if recognition.state in ("started", "achieved") and recognition.agent is not None:
            self.sup.loop.call_soon(self._match, recognition)
        elif recognition.state == "progressing" and recognition.agent is not None:
            self.sup.loop.call_soon(self._progressing, recognition)

    def _progressing(self, recognition: Any) -> None:
        """A due task under way whose end the robot cannot see (its objects out of the
        camera's view): look at them now, before its effect is needed."""
        follower = self.follower
        if follower.finished:
            return
        for task in follower.current:
            if self.matches(task, recognition):
                unseen = follower.recovery.unseen(task)
                if unseen:
                    self.sup.record("plan-recover", task=follower.states.fact_name(task),
                                    agent=recognition.agent, rung="look", objects=unseen,
                                    why="under way out of view", name=follower.plan.
                                    primitive[task].label())
                    follower.recovery.look(task, unseen[-1], follower.recovery.patience)

    def matches(self, task: int, recognition: Any, any_agent: bool = False) -> bool:
        """Whether ``recognition`` is ``task`` (its class, its objects; its agent too
        unless ``any_agent``)."""
        follower = self.follower
        spec = follower.plan.primitive[task]
        cls = self.ontology.action_class(spec.name)
        seen = self.ontology.action_class(recognition.action)
        if cls is None or seen is None or not self.ontology.is_a(cls, seen):
            return False
        agent = follower.agents.get(task, spec.agent)
        if not any_agent:
            if isinstance(agent, dict):
                if recognition.agent not in agent.get("any-of", ()):
                    return False
            elif agent != recognition.agent:
                return False
        objects = {str(v) for v in follower.objects_of(task)}
        named = {str(v) for v in recognition.params.values() if v is not None}
        return bool(named) and named <= objects

    def _match(self, recognition: Any) -> None:
        follower = self.follower
        if follower.finished:
            return
        due = [t for t in follower.current if self.matches(t, recognition)]
        if recognition.state == "started":
            for task in due:
                follower.human_started(task)
            return
        if due:
            follower.human_did(due[0])
            return
        ahead = [t for t in follower.ahead() if self.matches(t, recognition, any_agent=True)]
        if ahead:
            self.sup.record("plan-match", task=follower.states.fact_name(ahead[0]),
                            agent=recognition.agent, match="useful",
                            action=recognition.action, why="an unexpected action the plan "
                            "has further on: accepted")
            follower.done_ahead(ahead[0], recognition.agent)
            return
        if any(self.matches(t, recognition, any_agent=True) for t in follower.executed):
            return  # what is done already, seen again
        self.sup.record("plan-match", agent=recognition.agent, match="harmful",
                        action=recognition.action,
                        params={k: str(v) for k, v in recognition.params.items()},
                        why="nothing in the plan expects it: replan")
        follower.replan(f"{recognition.agent} did {recognition.action} "
                        f"({', '.join(str(v) for v in recognition.params.values())})")
