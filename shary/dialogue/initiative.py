"""Person-initiated acts: a person asks for a task, cancels one, or changes a plan.

The supervisor gives an act that no task expects to its ``initiative``
handlers (:attr:`shary.kernel.supervisor.Supervisor.initiative`); :class:`Initiative`
is the dialogue's.  The act's data says what it is about:

``ASK-TASK``  ``{task: NAME, with: {PARAM: VALUE}}``; a value is a thing's
              name or a description (``{type: Cube, color: green}``).  Each
              description is resolved in the robot's facts: nothing fits ->
              the robot says so (attention first: :func:`~shary.dialogue.attention.tell`);
              several fit -> it asks which (:mod:`~shary.dialogue.disambiguation`);
              one -> the task goes to the agenda with its H-initiated variant,
              the ``task-requested`` scheme (the robot agrees or refuses, e.g.
              when its hand is busy).  Parameters the person leaves out that
              a role of the task would take (``partner``) are the person.
``CANCEL``    ``{task: NAME}`` (or nothing: the person's current task).  A task
              whose scheme expects CANCEL hears it (``task-requested`` stops
              and puts back what it took); any other is cancelled on the agenda.

The robot's side of these dialogues are recipes with functions, registered
here on the supervisor: ``reply-task``, ``stop-task`` (and the
disambiguation's ``ask-which``, ``understand-which``).
"""

from __future__ import annotations

import itertools
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from shary.dialogue import attention, disambiguation, negotiation, sessions
from shary.dialogue.disambiguation import Question
from shary.dialogue.reg import PerspectiveIndex, Referrer
from shary.dialogue.requests import Grammar, Query, Request, Resolution, resolve
from shary.dialogue.steps import say
from shary.kernel.recipes import ROBOT_PARAM, Recipe, Step, Term

if TYPE_CHECKING:
    from shary.kernel.agenda import Goal
    from shary.kernel.supervisor import Supervisor, TaskRun
    from shary.statechart.model import Scheme

REQUESTED_SCHEME = "task-requested"
"""The H-initiated variant a task runs with when a person asked for it."""
PLAN_REQUESTED_SCHEME = "plan-requested"
"""The H-initiated variant with plan negotiation, for a task planned by the planner."""
DISAMBIGUATE_TASK = "disambiguate"


class Initiative:
    """The dialogue's handler of person-initiated acts (see the module's docstring)."""

    def __init__(self, sup: Supervisor):
        self.sup = sup
        self.questions: dict[str, Question] = {}
        self._ids = itertools.count(1)
        self._requested: dict[str, Scheme] = {}
        self._grammar: Grammar | None = None
        self.sessions: Any = None
        """The interaction sessions, when the robot keeps them
        (:class:`~shary.dialogue.sessions.Sessions`)."""
        sup.initiative.append(self.handle)
        sup.functions.setdefault("reply-task", reply_task)
        sup.functions.setdefault("stop-task", stop_task)
        sup.functions.setdefault("ask-which", disambiguation.ask_which)
        sup.functions.setdefault("understand-which", disambiguation.understand_which)
        sup.functions.setdefault("farewell", sessions.farewell)
        sup.functions.setdefault("call-attention", attention.call_attention)
        sup.functions.setdefault("propose-plan", negotiation.propose_plan)
        sup.functions.setdefault("modify-plan", negotiation.modify_plan)

    # -- what people say -------------------------------------------------------------

    def ontology(self) -> Any:
        """The action ontology: the one the robot's speech uses (read once)."""
        from shary.dialogue.speech import core_ontology

        return self.sup.speech.ontology or core_ontology()

    def grammar(self) -> Grammar:
        """The requests' grammar, from the action ontology's labels."""
        if self._grammar is None:
            self._grammar = Grammar.from_ontology(self.ontology())
        return self._grammar

    def hear(self, agent: str, sentence: str) -> None:
        """A person said ``sentence`` to the robot: a request becomes their ASK-TASK, a
        sentence the robot cannot read is answered with what it did not understand."""
        sup = self.sup
        sup.record("heard", agent=agent, text=sentence)
        words = sentence.strip()
        robot = sup.robot.lower()
        if words.lower().startswith(robot) and words[len(robot):len(robot) + 1] in ",!:":
            words = words[len(robot) + 1:].strip()  # "Jido, could you …": said to it
        index = PerspectiveIndex.from_facts(sup.facts, "robot")
        understood = self.grammar().parse(words, index, speaker=agent, addressee=sup.robot)
        if understood.request is None:
            attention.tell(sup, agent, understood.problem or "Sorry, I did not understand.")
            return
        request = understood.request
        if request.kind == "request":
            sup.receive_act(agent, "ASK-TASK", {"task": request.action, "request": request,
                                                "text": sentence})
        else:  # "I'll take the bottle myself": a step of a plan taken on
            sup.receive_act(agent, "MODIFY-PLAN", {"step": request.action, "request": request,
                                                   "text": sentence})

    # -- acts ----------------------------------------------------------------------

    def handle(self, agent: str, act: str, data: Any) -> bool:
        """Take a person's act that no task expects; False when it is not one of ours."""
        data = data if isinstance(data, dict) else {}
        if act == "ASK-TASK":
            request = data.get("request")
            if not isinstance(request, Request):
                params = dict(data.get("with") or {})
                request = Request("request", str(data.get("task", "")), self.sup.robot,
                                  tuple(params), {p: disambiguation.query_of(v)
                                                  for p, v in params.items()}, "", "")
            self.pursue(agent, request)
            return True
        if act == "CANCEL":
            return self.cancel(agent, data.get("task"))
        if act == "MODIFY-PLAN":
            return self.modify(agent, data)
        return False

    def requested_scheme(self, task: str) -> Scheme:
        """The H-initiated variant of ``task``: with plan negotiation when the task's
        plan comes from the planner (``plan-requested``), else ``task-requested``."""
        planned = any(r.plan is not None
                      for r in self.sup.library.recipes_for(task, negotiation.REALIZE))
        name = PLAN_REQUESTED_SCHEME if planned else REQUESTED_SCHEME
        if name not in self._requested:
            from shary.io.schemes import load_scheme

            self._requested[name] = load_scheme(name, acts=self.sup.library.acts)
        return self._requested[name]

    def pursue(self, agent: str, request: Request) -> None:
        """A person asked for a task: resolve what they described; none -> say so,
        several -> ask which, one -> put the task on the agenda, H-initiated."""
        sup = self.sup
        task_type = sup.library.tasks.get(request.action)
        if task_type is None:
            sup.record("request-refused", agent=agent, name=request.action,
                       reason="not a task of the library")
            attention.tell(sup, agent, "Sorry, I cannot do that on its own.")
            return
        resolution = resolve(request, PerspectiveIndex.from_facts(sup.facts, "robot"))
        sup.record("request-resolved", agent=agent, name=request.action,
                   status=resolution.status,
                   matches={r: list(m) for r, m in resolution.matches.items()})
        if resolution.status == "none":
            attention.tell(sup, agent, f"Sorry, {_lower_first(str(resolution.message))}")
            return
        if resolution.status == "several":
            self._ask_which(agent, request, resolution)
            return
        args = {}
        for role, thing in resolution.bindings.items():
            param = self._param(request.action, role, task_type.params)
            if param is not None:
                args[param] = thing
        for role, term in task_type.roles.items():
            if (term.kind == "param" and term.value not in args and role != ROBOT_PARAM
                    and term.value in task_type.params):
                args[term.value] = agent  # "give me …": the asker is the partner
        missing = [p for p in task_type.params if p not in args]
        if missing:
            sup.record("request-refused", agent=agent, name=request.action,
                       reason=f"missing {', '.join(missing)}")
            attention.tell(sup, agent, "Sorry, I did not understand all of it.")
            return
        goal = sup.agenda.add(request.action, args, source=f"request:{agent}",
                              scheme=self.requested_scheme(request.action), initiator=agent)
        sup.record("request-accepted", agent=agent, name=request.action, goal=goal.id)

    def _param(self, action: str, role: str, params: tuple[str, ...]) -> str | None:
        """The task parameter a role of a request fills: the same name, else the one at
        the role's place in the action ontology (``{Agent} @Clean up {Place}``: the
        first parameter); None for the agent."""
        if role.lower() in params:
            return role.lower()
        if role != "Agent":
            ontology = self.ontology()
            cls = ontology.action_class(action)
            for parameter in ontology.parameters(cls) if cls else ():
                if parameter.role == role and parameter.position - 1 < len(params):
                    return params[parameter.position - 1]
        return None

    def _ask_which(self, agent: str, request: Request, resolution: Resolution) -> None:
        role = str(resolution.role)

        def then(q: Question) -> None:
            if q.chosen is not None:
                params = {**request.params, role: Query(name=q.chosen, words=q.chosen)}
                self.pursue(agent, replace(request, params=params))

        q = Question(f"q{next(self._ids)}", agent, resolution, then)
        self.questions[q.id] = q
        self.sup.start_task(DISAMBIGUATE_TASK, {"partner": agent, "question": q.id},
                            on_finish=lambda run: self._answered(q))

    def _answered(self, q: Question) -> None:
        self.questions.pop(q.id, None)
        self.sup.record("question-over", agent=q.partner, question=q.id, chosen=q.chosen,
                        candidates=list(q.resolution.candidates))
        q.then(q)

    def _goal_of(self, agent: str, task: Any) -> Goal | None:
        """The person's goal (the named task, or their latest) that is not over."""
        return next((g for g in reversed(self.sup.agenda.goals)
                     if g.state in ("pending", "active", "suspended")
                     and (task is None or g.task == task)
                     and (g.initiator == agent or agent in map(str, g.args.values()))), None)

    def modify(self, agent: str, data: dict[str, Any]) -> bool:
        """A step taken on while no proposal is pending: the running task plans again."""
        goal = self._goal_of(agent, None) or self.sup.agenda.active  # or the robot's own
        run = goal.run if goal is not None else None
        if run is None or run.ended:
            attention.tell(self.sup, agent, "Sorry, I am not doing anything I could change.")
            return True
        found = negotiation.assignment_of(run, {"agent": agent, "data": data})
        if found is None:
            attention.tell(self.sup, agent, "Sorry, I did not understand what to change.")
            return True
        negotiation.constrain_running(run, found[0])
        return True

    def cancel(self, agent: str, task: Any) -> bool:
        """Stop the person's task (the named one, or their latest)."""
        sup = self.sup
        goal = self._goal_of(agent, task)
        if goal is None:
            return False
        run = goal.run
        if run is not None and not run.ended and run.expects("CANCEL"):
            run.stopped_by = f"cancelled by {agent}"
            run.deliver("CANCEL", {"agent": agent})
        else:
            sup.agenda.cancel(goal, f"cancelled by {agent}")
        return True


def _lower_first(text: str) -> str:
    return text[:1].lower() + text[1:] if text[:2] != "I " else text


# -- the robot's side: recipe functions -------------------------------------------

def _task_object(run: TaskRun) -> str | None:
    value = run.env.get("object")
    return None if value is None else str(value)


def reply_task(run: TaskRun, recipe: Recipe) -> list[Step]:
    """REPLY-TASK: refuse (R-DISAGREE) when the hand holds something the task is not
    about, saying so; agree otherwise (the act is ``done``), aloud to a partner who
    attends."""
    facts, robot = run.sup.facts, run.robot
    held = sorted(str(o) for o in facts.objects(robot, "isHolding"))
    wanted = _task_object(run)
    busy = [o for o in held if o != wanted]
    if busy:
        held = Referrer.for_perspective(facts, "robot").describe(busy[0], by_name=True).text()
        return [say("refuse", f"Sorry, I cannot: my hand is busy with {held}.",
                    emit="R-DISAGREE")]
    # asked, then turned away (a call, the door): they will see it
    return [attention.if_attending(run, say("agree", "Yes, I will do that."))]


def stop_task(run: TaskRun, recipe: Recipe) -> list[Step]:
    """STOP-TASK: put back the task's object if the robot holds it, and say so (to a
    partner who attends: they cancelled, so it is no news to one who looks away)."""
    wanted = _task_object(run)
    holding = wanted is not None and run.sup.facts.holds(run.robot, "isHolding", wanted)
    if holding:
        described = Referrer.for_perspective(run.sup.facts, "robot").describe(
            wanted, by_name=True)
        thing = described.text(people={run.robot: "me",
                                        str(run.roles.get("partner")): "you"})
        # a long phrase after the particle ("put back the green cube in my hand"), a
        # short one before it ("put the yellow bottle back"), as English places them
        words = (f"All right, I will stop and put back {thing}." if described.relations
                 else f"All right, I will stop and put {thing} back.")
    else:
        words = "All right, I will stop."
    steps = [attention.if_attending(run, say("stop", words))]
    if holding and "put-back" in run.sup.library.atomic:
        steps.append(Step("put-back", "put-back", None, {"object": Term("const", wanted)},
                          None, ("stop",)))
    return steps
