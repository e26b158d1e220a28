"""Planner-backed recipes in the kernel: plans become steps; failures make new plans."""

from __future__ import annotations

from scripted import World

from shary.kernel.planning import HatpPlanner
from shary.kernel.recipes import parse_refinement

LIVING_ROOM = {
    "base": {"type": "Place"}, "coffee-area": {"type": "Place"},
    "trash-area": {"type": "Place"}, "sofa-area": {"type": "Place"},
    "jido": {"type": "Agent", "kind": "robot", "move_cost": 2, "pick_cost": 1, "speed": 1,
             "at": "base"},
    "alice": {"type": "Agent", "kind": "human", "move_cost": 4, "pick_cost": 2, "speed": 1,
              "at": "sofa-area"},
    "coffee-table": {"type": "Furniture", "place": "coffee-area", "container": False,
                     "seat": False},
    "trash": {"type": "Furniture", "place": "trash-area", "container": True, "seat": False},
    "yellow-bottle": {"type": "Object", "color": "yellow", "drink": True, "on": "coffee-table",
                      "robot_reach": True},
}


PERCEIVED = {"at": "isAt", "on": "isOn"}
"""The attributes the clean-up recipe reads from perception's predicates (plan.facts)."""


def living_room_world(**kwargs) -> World:
    world = World(planners={"living-room": HatpPlanner("living-room", budget_ms=2000)},
                  **kwargs)
    for entity, attributes in LIVING_ROOM.items():
        for attribute, value in attributes.items():
            world.facts.set(entity, PERCEIVED.get(attribute, attribute), value)
    return world


def test_refinement_syntax():
    assert parse_refinement("navigate(place=to)") == ("navigate", {"place": "to"})
    assert parse_refinement("speak") == ("speak", {})


def test_clean_up_runs_the_plan_of_fig_9b():
    world = living_room_world()
    run = world.sup.start_task("clean-up", {"object": "yellow-bottle"})
    world.run(60)
    assert run.outcome == "done"
    done = [(name, args) for _, name, args in world.executor.started
            if name not in ("speak", "look-at")]
    assert done == [("navigate", {"place": "coffee-area"}), ("pick", {"object": "yellow-bottle"}),
                    ("navigate", {"place": "trash-area"}),
                    ("dump", {"object": "yellow-bottle", "into": "trash"})]


def fig10_world(**kwargs) -> tuple[World, list[tuple[str, str]]]:
    """The clean-up of Fig. 10, scripted: Jido's pick fails (out of reach); asked for
    help, Alice agrees and hands the bottle over.  Also returns the (atomic, agent) list
    of the requests, filled as the run goes."""
    world = living_room_world(**kwargs)
    agents: list[tuple[str, str]] = []
    original = world.executor.start

    def start(request, reporter):
        agents.append((request.atomic, request.agent))
        if request.atomic == "pick" and request.agent == "jido":
            # perception finds out: the bottle is out of Jido's reach
            world.facts.set("yellow-bottle", "robot_reach", False)
            world.executor.failures["pick"] = ["out of reach"]
        if request.atomic == "speak" and "Can you give me" in request.args["text"]:
            # Alice agrees, fetches the bottle and hands it over
            world.loop.call_later(2, world.sup.receive_act, "alice", "H-AGREE")
            world.loop.call_later(10, world.facts.remove, "yellow-bottle", "isOn",
                                  "coffee-table")
            world.loop.call_later(10, world.facts.add, "jido", "isHolding", "yellow-bottle")
        original(request, reporter)

    world.executor.start = start
    return world, agents


def test_unreachable_bottle_replans_with_the_human_as_in_fig_10():
    world, agents = fig10_world()
    run = world.sup.start_task("clean-up", {"object": "yellow-bottle"})
    world.run(120)
    assert run.outcome == "done"
    assert [a for a in agents if a[0] not in ("look-at",)] == [
        ("navigate", "jido"), ("pick", "jido"),          # the first plan fails
        ("speak", "jido"), ("speak", "jido"),             # the new plan: Jido asks Alice,
        ("speak", "jido"),                                # she hands it over (END-TASK),
        ("navigate", "jido"), ("dump", "jido"),           # Jido dumps it
        ("speak", "jido")]                                # and announces the end
    tree = world.sup.tree
    kinds = [tree.node(n)["name"] for n in tree.graph]
    assert kinds.count("pick") == 0  # the failed pick was cut with the first plan's rest
    assert kinds.count("ask-help") == 1  # Alice's part of the plan: one joint task
    ask = next(n for n in tree.graph if tree.node(n)["name"] == "ask-help")
    acts = {tree.node(c)["name"] for c in tree.children(ask)}
    # attention first (she attends already: the wait ends at once), then the question
    assert acts == {"WAIT-ATTENTION x ask-help", "ASK-HELP x ask-help",
                    "REALIZE-TASK x ask-help", "END-TASK x ask-help"}, acts
    plan = world.sup.planners["living-room"].last.plan
    assert [(a.name, a.agent) for a in plan.actions] == [
        ("Move", "alice"), ("Pick", "alice"), ("Move", "alice"), ("Give", "alice"),
        ("Move", "jido"), ("Dump", "jido")]


def test_no_plan_fails_the_act_cleanly():
    world = living_room_world()
    world.facts.remove("yellow-bottle", "isOn", "coffee-table")
    run = world.sup.start_task("clean-up", {"object": "yellow-bottle"})
    world.run(60)
    assert run.outcome == "failed"
