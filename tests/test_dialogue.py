"""The dialogue on a scripted world: attention before speaking, person-initiated acts,
disambiguation, cancellation, plan negotiation (shary/dialogue)."""

from __future__ import annotations

import pytest
from scripted import World

import planner
from planner.model.domain import Assignment
from shary.dialogue.attention import tell
from shary.dialogue.negotiation import Taken


def said(world: World) -> list[str]:
    return [args["text"] for _, atomic, args in world.executor.started if atomic == "speak"]


def kinds(world: World, kind: str) -> list[dict]:
    return [data for _, k, _, _, data in world.log.events if k == kind]


class Log:
    def __init__(self):
        self.events = []

    def record(self, t, kind, *, task=None, agent=None, **data):
        self.events.append((t, kind, task, agent, data))


@pytest.fixture
def world() -> World:
    w = World(log=Log())
    w.log = w.sup.log
    for thing, kind, colour, where in (("bottle", "Bottle", "yellow", "table"),
                                       ("cube-a", "Cube", "green", "table"),
                                       ("cube-b", "Cube", "green", "shelf"),
                                       ("cube-c", "Cube", "red", "table")):
        w.facts.add(thing, "type", kind)
        w.facts.add(thing, "color", colour)
        w.facts.add(thing, "isOn", where)
    for furniture, kind in (("table", "Table"), ("shelf", "Shelf")):
        w.facts.add(furniture, "type", kind)
    w.facts.add("alice", "type", "Human")
    w.facts.add("jido", "type", "Robot")
    return w


# -- attention before speaking ------------------------------------------------------

def test_inform_waits_until_the_partner_looks_then_speaks(world):
    world.facts.remove("alice", "looksAt", "jido")
    run = tell(world.sup, "alice", "The bottle is in the trash.")
    world.run(5)
    assert said(world) == []  # nothing said to someone who does not attend
    world.facts.add("alice", "looksAt", "jido")
    world.run(5)
    assert said(world) == ["The bottle is in the trash."]
    assert run.outcome == "done"


def test_inform_calls_the_partner_then_gives_up_without_telling(world):
    world.facts.remove("alice", "looksAt", "jido")
    run = tell(world.sup, "alice", "The bottle is in the trash.")
    world.run(40)
    assert said(world) == ["Excuse me, Alice."]
    assert run.outcome == "failed"


def test_a_sentence_waiting_for_the_voice_is_not_said_to_someone_who_looked_away(world):
    world.executor.durations["speak"] = 5.0
    first = tell(world.sup, "alice", "The bottle is in the trash.")
    second = tell(world.sup, "alice", "The cube is on the shelf.")
    world.run(5)  # the second sentence waits for the voice; she looks away meanwhile
    world.facts.remove("alice", "looksAt", "jido")
    world.run(30)
    assert said(world) == ["The bottle is in the trash.", "Excuse me, Alice."]
    assert (first.outcome, second.outcome) == ("done", "failed")


def test_a_question_waits_until_the_partner_looks_then_asks(world):
    world.facts.remove("alice", "looksAt", "jido")
    world.give()
    world.run(5)
    assert said(world) == []  # "Shall I give you …?" is not asked of someone looking away
    world.facts.add("alice", "looksAt", "jido")
    world.run(2)
    assert said(world) == ["Shall I give you the bottle?"]


def test_a_question_nobody_attends_to_calls_then_gives_up_saying_why(world):
    world.facts.remove("alice", "looksAt", "jido")
    run = world.give()
    world.run(40)
    assert said(world) == ["Excuse me, Alice.",
                           "You are busy, so I will not give you the bottle."]
    assert run.outcome == "failed"


def test_a_call_for_help_nobody_attends_to_calls_then_gives_up_saying_why(world):
    world.facts.remove("alice", "looksAt", "jido")
    run = world.sup.start_task("ask-help", {"helper": "alice", "object": "bottle"})
    world.run(9)
    assert said(world) == []  # no "Can you give me …?" to someone looking away
    world.run(40)
    assert said(world) == ["Excuse me, Alice.", "You are busy, so I will do without the bottle."]
    assert run.outcome == "failed"


def test_a_helper_called_by_name_who_looks_is_asked(world):
    world.facts.remove("alice", "looksAt", "jido")
    world.sup.start_task("ask-help", {"helper": "alice", "object": "bottle"})
    world.run(12)
    assert said(world) == ["Excuse me, Alice."]
    world.facts.add("alice", "looksAt", "jido")
    world.run(3)
    assert said(world) == ["Excuse me, Alice.", "Can you give me the bottle?"]


class GoToTable:
    """A planner whose plan for anything is to go to the table."""

    domain = planner.load_domain("living-room")

    def plan_steps(self, spec, args, facts, assigned=()):
        from shary.kernel.recipes import Step, Term

        return [Step("go", "navigate", None, {"place": Term("const", "table")}, None, ())]


def test_a_plan_is_proposed_to_the_person_who_asked_once_they_look(world):
    world.sup.planners["*"] = GoToTable()
    world.sup.dialogue.hear("alice", "Jido, could you clean up the yellow bottle?")
    world.facts.remove("alice", "looksAt", "jido")  # she asked, then took a call
    world.run(15)
    assert said(world) == ["Excuse me, Alice."]  # no yes, no plan to her back
    world.facts.add("alice", "looksAt", "jido")
    world.run(1)
    assert said(world)[-1].startswith("Here is my plan.")


def test_a_plan_nobody_looks_to_hear_is_given_up_saying_why(world):
    world.sup.planners["*"] = GoToTable()
    world.sup.dialogue.hear("alice", "Jido, could you clean up the yellow bottle?")
    world.facts.remove("alice", "looksAt", "jido")
    world.run(40)
    assert said(world) == ["Excuse me, Alice.", "You are busy, so I will leave it."]
    assert world.sup.agenda.goals[0].run.outcome == "failed"


# -- person-initiated acts -------------------------------------------------------------

def test_a_persons_request_starts_the_task_with_its_requested_variant(world):
    world.sup.dialogue.hear("alice", "Jido, could you give me the yellow bottle?")
    world.run(1)
    goal = world.sup.agenda.goals[0]
    assert (goal.task, goal.args, goal.initiator) == (
        "give-object", {"object": "bottle", "partner": "alice"}, "alice")
    assert goal.run.scheme.name == "task-requested"
    assert said(world)[0] == "Yes, I will do that."


def test_the_robot_refuses_when_its_hand_is_busy(world):
    world.facts.add("jido", "isHolding", "cube-c")
    world.sup.receive_act("alice", "ASK-TASK", {"task": "give-object",
                                                "with": {"object": "bottle"}})
    world.run(5)
    assert said(world) == ["Sorry, I cannot: my hand is busy with the red cube."]
    assert world.sup.agenda.goals[0].run.outcome == "failed"
    assert "pick" not in world.executor.names()


def test_nothing_fits_the_robot_says_so(world):
    world.sup.receive_act("alice", "ASK-TASK", {"task": "give-object",
                                                "with": {"object": {"type": "Cube",
                                                                    "color": "blue"}}})
    world.run(5)
    assert said(world) == ["Sorry, I see no blue cube."]
    assert world.sup.agenda.goals == []


def test_several_fit_the_robot_asks_and_gives_the_one_meant(world):
    world.sup.dialogue.hear("alice", "give me the green cube")
    world.run(2)
    assert said(world) == ["Do you mean the green cube on the table or the one on the "
                           "shelf?"]
    task = next(r for r in world.sup.runs.values() if r.type.name == "disambiguate")
    world.sup.receive_act("alice", "SAY-WHICH", {"text": "the one on the shelf"},
                          task=task.node)
    world.run(3)
    assert said(world)[1] == "All right, the green cube on the shelf."
    goal = world.sup.agenda.goals[0]
    assert goal.args["object"] == "cube-b"
    # the thing understood reached the scheme as its event's data, and the scheme kept it
    assert task.instance.data["choice"] == "cube-b"


def test_an_answer_that_fits_nothing_is_asked_again_then_given_up(world):
    world.sup.dialogue.hear("alice", "give me the green cube")
    world.run(2)
    for _ in range(2):
        task = next(r for r in world.sup.runs.values() if r.type.name == "disambiguate")
        world.sup.receive_act("alice", "SAY-WHICH", {"text": "the purple one"},
                              task=task.node)
        world.run(3)
    assert said(world)[1] == "Sorry, I did not understand which one."
    assert said(world)[-1].startswith("I did not understand which one you meant")
    assert world.sup.agenda.goals == []


def test_silence_to_the_question_gives_up(world):
    world.sup.dialogue.hear("alice", "give me the green cube")
    world.run(30)
    assert said(world)[-1].startswith("I did not understand which one you meant")


def test_which_one_is_not_asked_of_someone_looking_away_who_is_called_then_given_up(world):
    world.sup.dialogue.hear("alice", "give me the green cube")
    world.facts.remove("alice", "looksAt", "jido")  # she asked, then took a call
    world.run(40)
    assert said(world) == ["Excuse me, Alice.",
                           "You are busy, so I will not ask which one you meant."]
    assert world.sup.agenda.goals == []


def test_a_sentence_the_robot_cannot_read_is_answered(world):
    world.sup.dialogue.hear("alice", "frobnicate the bottle")
    world.run(2)
    assert said(world) == ["I did not understand 'frobnicate'."]


def test_cancel_stops_the_task_and_puts_back_what_it_took(world):
    world.executor.durations["move-arm"] = 10.0
    world.sup.dialogue.hear("alice", "give me the yellow bottle")
    world.run(4)
    world.facts.add("jido", "isHolding", "bottle")
    world.sup.receive_act("alice", "CANCEL", {"task": "give-object"})
    world.run(10)
    assert said(world)[-1] == "All right, I will stop and put the bottle back."
    assert "put-back" in world.executor.names()
    assert world.sup.agenda.goals[0].run.outcome == "failed"
    assert not world.sup.runs


def test_cancel_of_a_goal_without_a_cancel_in_its_scheme(world):
    goal = world.sup.agenda.add("give-object", {"object": "bottle", "partner": "alice"})
    world.run(0.5)
    world.sup.receive_act("alice", "CANCEL", {})
    world.run(1)
    assert goal.state == "cancelled" and goal.run.outcome == "cancelled"
    assert world.sup.agenda.active is None


def test_cancel_with_nothing_to_cancel_is_unexpected(world):
    world.sup.receive_act("alice", "CANCEL", {})
    world.run(1)
    assert kinds(world, "act-unexpected")


# -- plan negotiation -----------------------------------------------------------------

def test_the_planner_honours_an_assignment():
    problem = planner.load_problem(next(p for p in planner.builtin_problems()
                                        if p.stem == "clean-up"),
                                   planner.load_domain("living-room"))
    free = planner.plan(problem, 500).plan
    picker = {a.agent for a in free.actions if a.name == "Pick"}
    obj = next(a.args for a in free.actions if a.name == "Pick")[1]
    human = next(e for e, t in problem.entities.items() if t == "Agent"
                 and problem.initial.get((e, "kind")) == "human")
    assert human not in picker
    problem.assigned = (Assignment("Pick", (obj,), human),)
    constrained = planner.plan(problem, 500).plan
    assert constrained is not None
    assert {a.agent for a in constrained.actions if a.name == "Pick"} == {human}


def test_taken_steps_reach_the_planner(world):
    seen = []

    class Planner:
        def plan_steps(self, spec, args, facts, assigned=()):
            seen.append(tuple(assigned))
            return []

    world.sup.planners["*"] = Planner()
    run = world.sup.start_task("clean-up", {"object": "bottle"})
    run.assigned.append(Taken("Pick", ("bottle",), "alice"))
    for act in run.acts.values():
        act.replan("alice takes on Pick")
    assert seen[-1] == (Taken("Pick", ("bottle",), "alice"),)


def test_a_step_taken_on_while_the_task_runs_replans_it(world):
    from shary.kernel.recipes import Step, Term

    seen = []

    class Planner:
        domain = planner.load_domain("living-room")

        def plan_steps(self, spec, args, facts, assigned=()):
            seen.append(tuple(assigned))
            return [Step("go", "navigate", None, {"place": Term("const", "table")}, None, ())]

    world.sup.planners["*"] = Planner()
    world.executor.durations["navigate"] = 10.0
    goal = world.sup.agenda.add("clean-up", {"object": "bottle"})
    world.run(1)
    world.sup.dialogue.hear("alice", "I'll take the yellow bottle myself")
    world.run(1)
    assert seen == [(), (Taken("Pick", ("bottle",), "alice"),)]
    assert goal.run.assigned == [Taken("Pick", ("bottle",), "alice")]
    assert ("navigate" in world.executor.names()
            and world.executor.cancelled[0][1] == "navigate")  # the old plan's step stopped
