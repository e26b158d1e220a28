"""New objects a scenario adds to the living room: a cup, a cube, a ball.

The room has its bottles; a scenario's ``objects:`` may also name objects of
its own, each with a shape, a colour, a size in metres and a place::

    objects:
      red-cup: {shape: cylinder, colour: red, size: [0.07, 0.1], on: coffee-table,
                at: [-0.15, 0.3], kind: cup}
      big-box: {shape: box, colour: [0.6, 0.4, 0.2], size: [0.3, 0.2, 0.15], on: store-table}

``size`` is ``[width, depth, height]`` for a box, ``[diameter, height]`` for a
cylinder, ``[diameter]`` for a sphere; ``mass`` (kg) is optional; ``kind`` is
the word the fact base types it with (``Cup``; by default the shape's).  The
JSON Schema checks the form; :func:`check_new_objects` checks the meaning
(sizes the room can hold, within bounds, names that are not already taken;
the reader refuses numbers that are not finite before), with each problem at its place in the file.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

SHAPES: dict[str, tuple[str, ...]] = {
    "box": ("width", "depth", "height"),
    "cylinder": ("diameter", "height"),
    "sphere": ("diameter",),
}
"""Each shape and what its ``size`` numbers are, in order."""
SIZE_RANGE = (0.02, 0.6)
"""Smallest and largest dimension in metres: a thimble is not seen, a wardrobe is furniture."""
MASS_RANGE = (0.01, 5.0)
DEFAULT_DENSITY = 300.0
"""kg per cubic metre, for a mass not given (a light plastic or wooden thing)."""
COLOURS: dict[str, tuple[float, float, float]] = {
    "red": (0.85, 0.12, 0.1), "green": (0.15, 0.65, 0.2), "blue": (0.12, 0.3, 0.9),
    "yellow": (0.95, 0.82, 0.1), "orange": (0.95, 0.5, 0.08), "purple": (0.55, 0.2, 0.7),
    "pink": (0.95, 0.5, 0.7), "white": (0.95, 0.95, 0.93), "black": (0.08, 0.08, 0.08),
    "grey": (0.5, 0.5, 0.5), "brown": (0.45, 0.28, 0.12),
}


@dataclass(frozen=True)
class NewObject:
    """An object a scenario adds: its shape and size, colour, mass and kind."""

    name: str
    shape: str
    size: tuple[float, ...]
    colour: str
    rgb: tuple[float, float, float]
    mass: float
    kind: str

    @property
    def height(self) -> float:
        return self.size[-1] if self.shape != "sphere" else self.size[0]

    @property
    def grasp_width(self) -> float:
        """How far the gripper must open to close round it: its narrower horizontal side."""
        return min(self.size[:2]) if self.shape == "box" else self.size[0]

    @property
    def volume(self) -> float:
        if self.shape == "box":
            return math.prod(self.size)
        if self.shape == "cylinder":
            return math.pi * (self.size[0] / 2) ** 2 * self.size[1]
        return 4 / 3 * math.pi * (self.size[0] / 2) ** 3


NEW_KEYS = ("shape", "size", "colour", "color", "mass", "kind")
"""The keys that only a new object has: an entry with one of them adds an object."""


def is_new(spec: Any) -> bool:
    """Whether an ``objects:`` entry adds an object or places one of the room's bottles."""
    return isinstance(spec, dict) and any(key in spec for key in NEW_KEYS)


def new_object(name: str, spec: dict[str, Any]) -> NewObject:
    """The object an entry adds (the entry already checked)."""
    raw = spec.get("colour", spec.get("color", "grey"))
    rgb = COLOURS[raw] if isinstance(raw, str) else tuple(float(c) for c in raw)
    colour = raw if isinstance(raw, str) else _nearest_colour(rgb)
    size = tuple(float(v) for v in spec["size"])
    obj = NewObject(name, spec["shape"], size, colour, rgb, 0.0,
                    str(spec.get("kind", spec["shape"])))
    mass = float(spec["mass"]) if "mass" in spec else min(
        max(DEFAULT_DENSITY * obj.volume, MASS_RANGE[0]), MASS_RANGE[1])
    return NewObject(name, obj.shape, size, colour, rgb, mass, obj.kind)


def _nearest_colour(rgb: tuple[float, ...]) -> str:
    """The colour name nearest an RGB triple, for the fact base's ``color``."""
    return min(COLOURS, key=lambda n: sum((a - b) ** 2 for a, b in zip(COLOURS[n], rgb,
                                                                      strict=True)))


def check_new_objects(objects: dict[str, Any], taken: Iterable[str],
                      problem: Callable[..., Any]) -> None:
    """Report what is wrong with the new objects of ``objects:`` (the entries with a shape).

    ``taken`` holds the names already in use (bottles, furniture, places of
    the room, the robot, the people); ``problem(where, message, key)`` reports
    one problem at a path of the file (``key``: at the key rather than the value).
    """
    taken = set(taken)
    for name, spec in objects.items():
        if not is_new(spec):
            continue
        where = ("objects", name)
        if name in taken:
            problem(where, f"{name!r} already names something in the room; a new object "
                    "needs a name of its own", key=True)
        shape = spec.get("shape")
        size = spec.get("size")
        if shape is None or size is None:
            missing = " and ".join(k for k, v in (("shape", shape), ("size", size)) if v is None)
            problem(where, f"{name!r} is not one of the room's bottles, so it is a new object: "
                    f"it needs a {missing} (shape: box, cylinder or sphere; size in metres)",
                    key=True)
        if shape in SHAPES and isinstance(size, list):
            meaning = SHAPES[shape]
            if len(size) != len(meaning):
                problem(where + ("size",), f"a {shape}'s size is [{', '.join(meaning)}] in "
                        f"metres: {len(meaning)} number{'s' if len(meaning) > 1 else ''}, "
                        f"not {len(size)}")
            for i, value in enumerate(size):
                _bounded(problem, where + ("size", i), value, SIZE_RANGE, "m",
                         meaning[i] if i < len(meaning) else "size")
        if "mass" in spec:
            _bounded(problem, where + ("mass",), spec["mass"], MASS_RANGE, "kg", "mass")
        raw = spec.get("colour", spec.get("color"))
        key = "colour" if "colour" in spec else "color"
        if isinstance(raw, str) and raw not in COLOURS:
            problem(where + (key,), f"unknown colour {raw!r}; colours: {', '.join(COLOURS)}, "
                    "or [red, green, blue] from 0 to 1")
        elif isinstance(raw, list):
            for i, value in enumerate(raw):
                _bounded(problem, where + (key, i), value, (0.0, 1.0), "", "colour component")
        if "colour" in spec and "color" in spec:
            problem(where + ("color",), "give 'colour' or 'color', not both", key=True)


def _bounded(problem: Callable[..., Any], where: tuple, value: Any,
             bounds: tuple[float, float], unit: str, what: str) -> None:
    low, high = bounds
    if isinstance(value, bool) or not isinstance(value, int | float):
        problem(where, f"the {what} must be a number")
    elif not low <= value <= high:
        problem(where, f"the {what} must be from {low:g} to {high:g}{' ' + unit if unit else ''}"
                f", not {value:g}")
