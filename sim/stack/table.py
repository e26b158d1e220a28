"""The stack table: the objects of the StackBuildingTask on the coffee table.

The robot stands at ``coffee-area`` (south of the table, y < 0), the human at
``coffee-north`` (north, y > 0).  Each side has its cubes; the ones at the
far ends are within one agent's reach only.  Names are the planner's
(``planner/problems/stack.yaml``): placement_1/2, red_cube_1/2, stick,
blue_cube_1/2, green_cube, plus yellow cubes nobody needs.
"""

from __future__ import annotations

from typing import Any

CUBE = 0.05
"""A cube's side (m)."""

# name -> (x, y on the coffee table, shape spec, kind, colour)
LAYOUT: dict[str, tuple[float, float, list[float], str, str]] = {
    "placement_1": (-0.12, 0.0, [0.08, 0.08, 0.01], "placement", "white"),
    "placement_2": (0.12, 0.0, [0.08, 0.08, 0.01], "placement", "white"),
    "red_cube_1": (0.05, -0.18, [CUBE] * 3, "cube", "red"),
    "red_cube_2": (-0.2, 0.16, [CUBE] * 3, "cube", "red"),
    "stick": (-0.32, 0.1, [0.3, 0.04, 0.03], "stick", "brown"),
    "blue_cube_1": (0.1, -0.1, [CUBE] * 3, "cube", "blue"),
    "blue_cube_2": (-0.06, 0.18, [CUBE] * 3, "cube", "blue"),
    "green_cube": (-0.08, -0.18, [CUBE] * 3, "cube", "green"),
    "yellow_cube_1": (0.4, -0.2, [CUBE] * 3, "cube", "yellow"),
    "yellow_cube_2": (-0.4, 0.2, [CUBE] * 3, "cube", "yellow"),
}
TYPES = {"placement": ("Placement", "Support"), "cube": ("Cube", "Support"),
         "stick": ("Stick", "Support")}
"""The classes of each kind: a cube and the stick are supports too (things go on them);
both are Pickable in the action ontology, which the action models' roles name."""


BOTTLES_AWAY = {"yellow-bottle": (1.8, 1.6), "green-bottle": (2.0, 1.6),
                "orange-bottle": (2.2, 1.6), "blue-bottle": (2.4, 1.6)}
"""The living room's bottles, cleared from the coffee table to the store table."""


def objects() -> dict[str, dict[str, Any]]:
    """The scenario's ``objects:`` entries of the stack table (the cubes, the stick and
    the placements as new objects; the bottles moved away)."""
    out: dict[str, dict[str, Any]] = {name: {"on": "store-table", "at": list(at)}
                                      for name, at in BOTTLES_AWAY.items()}
    for name, (x, y, size, kind, colour) in LAYOUT.items():
        out[name] = {"shape": "box", "size": size, "colour": colour, "kind": kind,
                     "on": "coffee-table", "at": [x, y],
                     **({"mass": 5.0} if kind == "placement" else {})}
    return out


def a_priori(facts: Any) -> None:
    """What the robot knows of the stack table before it looks: each object's classes."""
    for name, (_, _, _, kind, colour) in LAYOUT.items():
        for cls in TYPES[kind]:
            facts.add(name, "type", cls)
        facts.add(name, "color", colour)
        if colour == "blue":
            facts.add(name, "type", "BlueCube")
