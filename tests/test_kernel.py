"""The execution kernel against a scripted world: SHARY's give-object, suspension, agenda."""

from __future__ import annotations

import pytest
from scripted import World

from shary.kernel.tasktree import ACT, CANCELLED, DONE, SUSPENDED


@pytest.fixture
def world():
    return World()


def acts_of(world: World) -> list[str]:
    tree = world.sup.tree
    return [tree.node(n)["act"] for n in tree.graph if tree.node(n)["kind"] == ACT]


def test_agreed_realized_ended(world):
    run = world.give()
    assert run.configuration == ("ask",)
    world.run(2)
    assert world.executor.names() == ["look-at", "speak"]
    world.sup.receive_act("alice", "H-AGREE")
    world.run(30)
    assert run.outcome == "done" and run.configuration == ("ended",)
    assert world.executor.names() == ["look-at", "speak", "pick", "move-arm", "give", "speak"]
    assert world.sup.tree.state(run.node) == DONE


def test_recipe_chosen_by_context(world):
    world.facts.add("jido", "isHolding", "bottle")
    world.give()
    world.sup.receive_act("alice", "H-AGREE")
    world.run(30)
    assert "pick" not in world.executor.names()


def test_refused_ends_without_arm_motion(world):
    run = world.give()
    world.sup.receive_act("alice", "H-DISAGREE")
    world.run(10)
    assert run.configuration == ("ended",)
    assert not {"pick", "move-arm", "give"} & set(world.executor.names())


def test_no_answer_gives_up_after_the_timeout(world):
    run = world.give()
    world.run(14)
    assert run.configuration == ("ask",)
    world.run(5)
    assert run.outcome == "failed" and run.configuration == ("abandoned",)


def test_acts_from_someone_else_or_unexpected_are_not_taken(world):
    run = world.give()
    world.sup.receive_act("bob", "H-AGREE")
    world.run(1)
    assert run.configuration == ("ask",)


def test_distracted_suspends_and_resumes_where_it_stopped(world):
    world.executor.durations.update({"move-arm": 4.0})
    run = world.give()
    world.sup.receive_act("alice", "H-AGREE")
    world.run(2.5)  # pick done at 1.0 (after the answer), move-arm started at 2.0... running
    assert world.executor.names()[-1] == "move-arm"
    world.facts.remove("alice", "looksAt", "jido")
    world.run(0.1)
    assert run.configuration == ("suspended",)
    assert world.executor.cancelled and world.executor.cancelled[-1][1] == "move-arm"
    realize = run.acts["realize"]
    assert realize.suspended and world.sup.tree.state(realize.node) == SUSPENDED
    world.run(10)
    world.facts.add("alice", "looksAt", "jido")
    world.run(0.1)
    assert run.configuration == ("approach",)
    world.run(30)
    assert run.outcome == "done"
    names = world.executor.names()
    assert names.count("pick") == 1 and names.count("move-arm") == 2 and names.count("give") == 1


def test_distracted_during_handover_resumes_the_handover(world):
    world.executor.durations.update({"give": 5.0})
    run = world.give()
    world.sup.receive_act("alice", "H-AGREE")
    world.run(3.5)
    assert run.configuration == ("handover",)
    world.facts.remove("alice", "looksAt", "jido")
    world.run(1)
    world.facts.add("alice", "looksAt", "jido")
    world.run(0.1)
    assert run.configuration == ("handover",)
    world.run(30)
    names = world.executor.names()
    assert run.outcome == "done" and names.count("move-arm") == 1 and names.count("give") == 2


def test_distracted_and_never_back_gives_up(world):
    world.executor.durations.update({"move-arm": 4.0})
    run = world.give()
    world.sup.receive_act("alice", "H-AGREE")
    world.run(2.5)
    world.facts.remove("alice", "looksAt", "jido")
    world.run(29)
    assert run.configuration == ("suspended",)
    world.run(10)
    assert run.outcome == "failed" and run.configuration == ("abandoned",)
    assert "You are busy, so I will not give you the bottle." in [
        a.get("text") for _, n, a in world.executor.started]


def test_executor_failure_retried_then_given_up(world):
    world.executor.failures["pick"] = ["out of reach", "out of reach"]
    run = world.give()
    world.sup.receive_act("alice", "H-AGREE")
    world.run(30)
    assert world.executor.names().count("pick") == 2
    assert run.outcome == "failed"


def test_executor_failure_retried_then_succeeds(world):
    world.executor.failures["pick"] = ["slipped"]
    run = world.give()
    world.sup.receive_act("alice", "H-AGREE")
    world.run(30)
    assert world.executor.names().count("pick") == 2 and run.outcome == "done"


def test_preempted_act_is_cut_from_the_tree(world):
    world.executor.durations.update({"speak": 5.0})
    run = world.give()
    ask_node = run.acts["ask"].node
    world.sup.receive_act("alice", "H-AGREE")
    world.run(0.1)
    assert ask_node not in world.sup.tree
    assert world.executor.cancelled == [(0.0, "speak")] or \
        world.executor.cancelled[-1][1] in ("look-at", "speak")
    assert acts_of(world) == ["REALIZE-TASK"]


def test_higher_priority_goal_suspends_then_resumes(world):
    agenda = world.sup.agenda
    world.executor.durations.update({"move-arm": 4.0})
    give = agenda.add("give-object", {"object": "bottle", "partner": "alice"}, priority=1)
    world.run(0.1)
    world.sup.receive_act("alice", "H-AGREE")
    world.run(2.5)
    explore = agenda.add("explore-place", {"place": "kitchen"}, priority=5)
    world.run(0.1)
    assert give.state == "suspended" and explore.state == "active"
    assert world.executor.cancelled[-1][1] == "move-arm"
    assert world.sup.tree.state(give.run.node) == SUSPENDED
    world.run(60)  # longer than any timeout of give-object: frozen while suspended
    assert explore.state == "done" and give.state == "done"
    names = world.executor.names()
    assert names.index("navigate") < len(names) - 1 - names[::-1].index("move-arm")


def test_same_goal_twice_is_one_task(world):
    agenda = world.sup.agenda
    first = agenda.add("explore-place", {"place": "kitchen"}, source="request")
    second = agenda.add("explore-place", {"place": "kitchen"}, source="initiative")
    world.run(30)
    assert first is second and first.sources == {"request", "initiative"}
    assert world.executor.names().count("navigate") == 1


CHRONICLE = """\
predicates:
  visits: unused here
chronicles:
  table-visit:
    doc: someone comes near a place, stays at least 5 s, then leaves
    events:
      - added: [$person, isNear, $place]
        stays: 5s
      - removed: [$person, isNear, $place]
        within: 2min
    goal: {task: explore-place, with: {place: $place}, priority: 2}
"""


def test_chronicle_creates_a_goal_once_not_twice(write):
    world = World(extra_library=[write("chronicle.yaml", CHRONICLE)])
    from shary.kernel.agenda import ChronicleRecognizer

    ChronicleRecognizer(world.sup)
    world.executor.durations["navigate"] = 100.0  # the goal stays open meanwhile
    facts = world.facts
    facts.add("bob", "isNear", "table")
    world.run(2)
    facts.remove("bob", "isNear", "table")  # left too soon: nothing
    world.run(1)
    assert world.sup.agenda.goals == []
    facts.add("bob", "isNear", "table")
    world.run(6)
    facts.remove("bob", "isNear", "table")
    facts.add("bob", "isNear", "table")
    world.run(6)
    facts.remove("bob", "isNear", "table")
    world.run(0.1)
    goals = world.sup.agenda.goals
    assert len(goals) == 1 and goals[0].args == {"place": "table"}
    assert goals[0].sources == {"chronicle:table-visit"}


def test_missing_executor_fails_the_step_cleanly(world):
    world.sup.executors = type(world.sup.executors)({})
    run = world.give()
    world.run(1)
    assert world.sup.missing_executors()
    assert run.configuration == ("ask",)
    world.run(20)
    assert run.outcome == "failed"


def test_cancelled_state_is_recorded_for_cut_nodes(world):
    states = []
    world.sup.tree._record = lambda kind, **data: states.append((kind, data.get("state")))
    world.give()
    world.sup.receive_act("alice", "H-DISAGREE")
    world.run(1)
    assert ("task-state", CANCELLED) in states


ADAPTED = """\
tasks:
  hand-over:
    doc: with a partner who knows the robot, skip the question (SHARY's adapted schemes)
    params: [object, partner]
    roles: {partner: $partner}
    scheme:
      - scheme: robot-task
        when: [{holds: [$partner, knows, $robot]}]
      - scheme: give-object
predicates:
  knows: a person is familiar with the robot
"""


def test_adapted_scheme_chosen_by_context(write):
    world = World(extra_library=[write("adapted.yaml", ADAPTED)])
    stranger = world.sup.start_task("hand-over", {"object": "bottle", "partner": "alice"})
    world.facts.add("alice", "knows", "jido")
    friend = world.sup.start_task("hand-over", {"object": "bottle", "partner": "alice"})
    assert (stranger.scheme.name, stranger.configuration) == ("give-object", ("ask",))
    assert (friend.scheme.name, friend.configuration) == ("robot-task", ("realize",))
