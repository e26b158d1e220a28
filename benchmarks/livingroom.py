"""Living-room clean-up problems of growing size, for the planner's benchmark.

``clean_up(bottles, agents)`` writes the problem as a YAML file for the
built-in ``living-room`` domain and loads it the way a user's file is loaded
(``planner.load_problem``): Jido (a robot) and up to two humans, Alice and
Bob; bottles spread over the coffee table, the sofa and the side table, every
other one out of Jido's reach (so that, with a human present, the plan asks
for help); one ``CleanUp`` task per bottle; no goal, so that the search
chooses between throwing and storing each bottle; and every social rule of
the domain selected (its seven rules cover the six kinds HATP names: state,
sequence, decomposition, effort, timeout, crossed links).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import _first  # noqa: F401  (this folder after the packages: see _first.py)
import yaml

from planner import Problem, load_domain, load_problem

AGENTS = (
    ("jido", {"kind": "robot", "move_cost": 2, "pick_cost": 1, "speed": 1, "at": "base"}),
    ("alice", {"kind": "human", "move_cost": 4, "pick_cost": 2, "speed": 1, "at": "sofa-area"}),
    ("bob", {"kind": "human", "move_cost": 3, "pick_cost": 2, "speed": 1,
             "at": "kitchen-area"}),
)
"""The robot and the humans, in the order they join (1 to 3 agents)."""
SHELVES = ("coffee-table", "sofa", "side-table")
"""Where the bottles start, in turn."""
COLORS = ("yellow", "red", "green", "blue", "white", "black", "orange", "purple")
RULES = {
    "object-on-seat": {"penalty": 5},
    "putdown-then-pickup": {"penalty": {"robot": 10, "human": 10, "default": 10}},
    "move-then-move": {"penalty": 1},
    "store-not-throw": {"penalty": 2},
    "effort-balance": {"penalty": 2},
    "long-waits": {"penalty": 0.5},
    "joint-actions": {"penalty": 1},
}
"""Every rule of the living-room domain, with its penalty."""


def clean_up_text(bottles: int, agents: int, *, rules: bool = True) -> str:
    """The problem as YAML text (bottles 1-8, agents 1-3)."""
    if not 1 <= bottles <= len(COLORS) or not 1 <= agents <= len(AGENTS):
        raise ValueError(f"bottles 1-{len(COLORS)} and agents 1-{len(AGENTS)}")
    places = ["base", "coffee-area", "trash-area", "store-area", "sofa-area", "side-area",
              "kitchen-area"]
    entities: dict[str, dict] = {p: {"type": "Place"} for p in places}
    for name, attrs in AGENTS[:agents]:
        entities[name] = {"type": "Agent", **attrs}
    furniture = {"coffee-table": ("coffee-area", False, False),
                 "trash": ("trash-area", True, False),
                 "store-table": ("store-area", False, False),
                 "sofa": ("sofa-area", False, True),
                 "side-table": ("side-area", False, False)}
    for name, (place, container, seat) in furniture.items():
        entities[name] = {"type": "Furniture", "place": place, "container": container,
                          "seat": seat}
    tasks = []
    for index, color in enumerate(COLORS[:bottles]):
        bottle = f"{color}-bottle"
        entities[bottle] = {"type": "Object", "color": color, "drink": True,
                            "on": SHELVES[index % len(SHELVES)],
                            "robot_reach": agents == 1 or index % 2 == 0}
        tasks.append(f"CleanUp({bottle})")
    problem = {"problem": f"clean-up-{bottles}-bottles-{agents}-agents",
               "domain": "living-room",
               "doc": "Benchmark: every bottle taken away, by Jido, helped where it cannot "
                      "reach.",
               "entities": entities, "tasks": tasks,
               "rules": RULES if rules else {}, "budget_ms": 60_000}
    return yaml.safe_dump(problem, sort_keys=False)


def clean_up(bottles: int, agents: int, *, rules: bool = True) -> Problem:
    """The clean-up problem, loaded and checked like a user's file."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"clean-up-{bottles}-{agents}.yaml"
        path.write_text(clean_up_text(bottles, agents, rules=rules), "utf-8")
        return load_problem(path, load_domain("living-room"))


if __name__ == "__main__":
    print("benchmarks/livingroom.py: problems and helpers that "
          "benchmarks/planner.py time; run that instead")
