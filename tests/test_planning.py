"""Planner-backed recipes in the kernel: plans become steps; failures make new plans."""

from __future__ import annotations

from scripted import World

from shary.planning import HatpPlanner
from shary.recipes import parse_refinement

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


def living_room_world(**kwargs) -> World:
    world = World(planners={"living-room": HatpPlanner("living-room", budget_ms=2000)},
                  **kwargs)
    for entity, attributes in LIVING_ROOM.items():
        for attribute, value in attributes.items():
            world.facts.set(entity, attribute, value)
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


def test_unreachable_bottle_replans_with_the_human_as_in_fig_10():
    world = living_room_world()
    agents = []
    original = world.executor.start

    def start(request, reporter):
        agents.append((request.atomic, request.agent))
        if request.atomic == "pick" and request.agent == "jido":
            # perception finds out: the bottle is out of Jido's reach
            world.facts.set("yellow-bottle", "robot_reach", False)
            world.executor.failures["pick"] = ["out of reach"]
        original(request, reporter)

    world.executor.start = start
    run = world.sup.start_task("clean-up", {"object": "yellow-bottle"})
    world.run(120)
    assert run.outcome == "done"
    assert [a for a in agents if a[0] not in ("speak", "look-at")] == [
        ("navigate", "jido"), ("pick", "jido"),                       # the first plan fails
        ("navigate", "alice"), ("pick", "alice"), ("navigate", "alice"),  # the new plan:
        ("give", "alice"), ("navigate", "jido"), ("dump", "jido")]    # Alice hands it over
    tree = world.sup.tree
    kinds = [tree.node(n)["name"] for n in tree.graph]
    assert kinds.count("pick") == 1  # the failed pick was cut with the first plan's rest
    moves = [n for n in tree.graph if tree.node(n)["name"] == "move-for-manipulate"]
    refined = {tree.node(c)["name"] for m in moves for c in tree.children(m)}
    assert refined == {"REALIZE-TASK x move-for-manipulate"}  # the plan's leaves, refined
    assert ("look-at", "alice") in agents  # Alice's moves are hers


def test_no_plan_fails_the_act_cleanly():
    world = living_room_world()
    world.facts.remove("yellow-bottle", "on", "coffee-table")
    run = world.sup.start_task("clean-up", {"object": "yellow-bottle"})
    world.run(60)
    assert run.outcome == "failed"
