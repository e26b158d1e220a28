"""Plan negotiation: the robot says its plan, who does what; a person changes a step.

SHARY's PROPOSE-PLAN and MODIFY-PLAN acts (section 2.2), in the
``plan-requested`` scheme: the robot plans the task (its planner-backed
recipe for REALIZE-TASK, as it would to realize it) and says the plan in
words, one phrase per step, each agent's steps together ("I will go to the
coffee area, pick the orange bottle and drop it into the trash").  The
person may change a step by saying they do it ("I'll take the orange bottle
myself": a *constraint* read by :mod:`shary.dialogue.requests`); the robot
keeps it as a :class:`Taken` step on the task
(:attr:`shary.kernel.supervisor.TaskRun.assigned`: every action of that kind on
those things is done by that person), says so, and plans again: the planner
honours every assignment.

A MODIFY-PLAN that comes while the task already runs (no proposal pending)
is taken the same way, and the act in progress plans again from there
(:func:`constrain_running`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, NamedTuple

from shary.dialogue import attention
from shary.dialogue.steps import say
from shary.kernel.recipes import Recipe, Step

if TYPE_CHECKING:
    from shary.kernel.supervisor import TaskRun

REALIZE = "REALIZE-TASK"


class Taken(NamedTuple):
    """A step a person took on: every ``action`` (the planning domain's name) whose
    arguments include ``things`` is done by ``agent`` (the planner's Assignment)."""

    action: str
    things: tuple[str, ...]
    agent: str


def _ontology(run: TaskRun) -> Any:
    return run.sup.dialogue.ontology()


def _phrases(run: TaskRun, steps: list[Step], partner: str | None) -> list[tuple[str, str]]:
    """(performer, sentence) per step, in the partner's words ("I will pick …"): each
    step's action or task with its arguments in the ontology's order of parameters, said
    by the robot's speech (:mod:`shary.dialogue.speech`)."""
    sup, ontology = run.sup, _ontology(run)
    said = []
    for step in steps:
        name = step.atomic or step.task or step.name
        cls = ontology.action_class(name)
        kind = sup.library.atomic.get(name) or sup.library.tasks.get(name)
        if cls is None or kind is None:
            continue
        performer = str(step.by.resolve(run.env)) if step.by is not None else run.robot
        values = [performer]
        for parameter in ontology.parameters(cls):
            position = parameter.position - 1
            term = step.args.get(kind.params[position]) if position < len(kind.params) else None
            values.append(str(term.resolve(run.env)) if term is not None else "")
        if "" in values:
            continue
        try:
            sentence = sup.speech.say({"act": "inform-planned", "to": partner or "_",
                                       "about": f"{name}({', '.join(values)})"}, run.robot)
        except ValueError:
            continue
        said.append((performer, sentence))
    return said


def plan_in_words(run: TaskRun, steps: list[Step], partner: str | None) -> str:
    """The plan said as sentences, one per run of steps by the same agent:
    "I will go to the coffee area, pick the orange bottle and drop it into the trash."."""
    phrases = _phrases(run, steps, partner)
    out: list[str] = []
    group: list[str] = []
    current: str | None = None

    def flush() -> None:
        if not group:
            return
        first, rest = group[0].rstrip("."), [g.rstrip(".").split(" will ", 1)[-1]
                                             for g in group[1:]]
        words = [first, *rest]
        out.append(", ".join(words[:-1]) + (" and " if len(words) > 1 else "") + words[-1]
                   + ".")

    for performer, sentence in phrases:
        if performer != current:
            flush()
            group, current = [], performer
        group.append(sentence)
    flush()
    return " Then ".join([out[0], *(o[:1].lower() + o[1:] if not o.startswith("I ")
                                    else o for o in out[1:])]) if out else ""


def _planned_recipe(run: TaskRun) -> Recipe | None:
    return next((r for r in run.sup.library.recipes_for(run.type.name, REALIZE)
                 if r.plan is not None and run.sup.holds(r.when, run.env)), None)


def propose_plan(run: TaskRun, recipe: Recipe) -> list[Step]:
    """PROPOSE-PLAN: plan the task as REALIZE-TASK would, and say the plan, to a partner
    who attends (one who looks away is waited for first: a proposal asks them)."""
    unheard = attention.await_attention(run, "plan")
    if unheard:
        return unheard
    planned = _planned_recipe(run)
    if planned is None:
        return [say("nothing", "I will do it myself.")]
    steps = run.sup.expand(run, planned)  # LookupError: no plan (the act fails)
    partner = run.roles.get("partner")
    text = plan_in_words(run, steps, partner)
    return [say("plan", f"Here is my plan. {text} Is that all right?" if text
                else "I have a plan. Is that all right?")]


def assignment_of(run: TaskRun, heard: Any) -> tuple[Taken, str] | None:
    """The step a person's MODIFY-PLAN takes on (a constraint
    :class:`~shary.dialogue.requests.Request`, resolved), and that step in words
    ("you will pick the orange bottle"); None when it names nothing or no action of
    the task's planning domain."""
    from shary.dialogue.reg import PerspectiveIndex
    from shary.dialogue.requests import Request, resolve

    data = heard.get("data") if isinstance(heard, dict) else None
    request = data.get("request") if isinstance(data, dict) else None
    if not isinstance(request, Request):
        return None
    resolution = resolve(request, PerspectiveIndex.from_facts(run.sup.facts, "robot"))
    if resolution.status != "one":
        return None
    agent = str(resolution.bindings.get("Agent", request.agent))
    values = [str(resolution.bindings[r]) for r in request.roles if r != "Agent"]
    action = _domain_action(run, request.action)
    if action is None:
        return None
    try:
        words = run.sup.speech.say({"act": "inform-planned", "to": agent,
                                    "about": f"{request.action}({agent}, {', '.join(values)})"},
                                   run.robot)
    except ValueError:
        words = ""
    return Taken(action, tuple(sorted(values)), agent), words


def _domain_action(run: TaskRun, name: str) -> str | None:
    """The planning domain's action that the ontology calls ``name`` (pick -> Pick)."""
    planned = _planned_recipe(run)
    planner = (run.sup.planners.get(planned.plan.domain) or run.sup.planners.get("*")
               if planned and planned.plan else None)
    domain = getattr(planner, "domain", None)
    if domain is None:
        return None
    ontology = _ontology(run)
    wanted = ontology.action_class(name)
    return next((a for a in domain.actions if ontology.action_class(a) == wanted), None)


def modify_plan(run: TaskRun, recipe: Recipe) -> list[Step]:
    """MODIFY-PLAN: keep the person's step as an assignment, and say so to a partner who
    attends (one who said it and turned away, to do that step, is not spoken to: the
    new plan's proposal waits for their attention)."""
    found = assignment_of(run, run.entered_data.get("MODIFY-PLAN"))
    if found is None:
        return [attention.if_attending(
            run, say("unclear", "Sorry, I did not understand what you want to change."))]
    assignment, words = found
    run.assigned.append(assignment)
    run.sup.record("plan-assigned", task=run.node, agent=assignment.agent,
                   action=assignment.action, things=list(assignment.things))
    return [attention.if_attending(
        run, say("noted", f"All right: {words[:1].lower()}{words[1:]} I will plan again."
                 if words else "All right, I will plan again."))]


def constrain_running(run: TaskRun, assignment: Any) -> None:
    """A step taken on while the task runs: keep it, and plan again from here."""
    run.assigned.append(assignment)
    run.sup.record("plan-assigned", task=run.node, agent=assignment.agent,
                   action=assignment.action, things=list(assignment.things))
    for act in list(run.acts.values()):
        if act.recipe is not None and act.recipe.plan is not None and not act.over:
            act.replan(f"{assignment.agent} takes on {assignment.action}")
