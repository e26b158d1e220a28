"""The living room's static data: furniture, bottles, the robots' places.

Plain data with no PyBullet in it, so that reading a scenario (checking the
places, furniture and objects it names) never loads the physics engine;
:mod:`sim.world` builds the room in PyBullet from it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

Colour = tuple[float, float, float, float]
Vec3 = tuple[float, float, float]
Place = tuple[float, float, float]  # x, y, yaw of a robot base


# --------------------------------------------------------------------- scene data

@dataclass(frozen=True)
class Part:
    """One box of a piece of furniture, in the furniture's own frame."""

    half_extents: Vec3
    offset: Vec3
    rgba: Colour


@dataclass(frozen=True)
class Footprint:
    """An oriented rectangle on the floor, for roadmap and placement checks."""

    x: float
    y: float
    yaw: float
    half_x: float
    half_y: float

    def contains(self, px: float, py: float, margin: float = 0.0) -> bool:
        """Whether (px, py) lies within the rectangle grown by ``margin``."""
        dx, dy = px - self.x, py - self.y
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        return abs(lx) <= self.half_x + margin and abs(ly) <= self.half_y + margin


WOOD_DARK: Colour = (0.42, 0.27, 0.16, 1.0)
WOOD_LIGHT: Colour = (0.62, 0.46, 0.30, 1.0)


def _table(length: float, width: float, height: float, rgba: Colour) -> list[Part]:
    """A top and four legs; the top surface is at ``height``."""
    top, leg = 0.04, 0.025
    parts = [Part((length / 2, width / 2, top / 2), (0, 0, height - top / 2), rgba)]
    leg_half = (height - top) / 2
    for sx in (-1, 1):
        for sy in (-1, 1):
            parts.append(Part((leg, leg, leg_half),
                              (sx * (length / 2 - 2 * leg), sy * (width / 2 - 2 * leg), leg_half),
                              rgba))
    return parts


def _chair(rgba: Colour) -> list[Part]:
    """A seat at 0.45 m, four legs and a back; it faces its local +x."""
    seat, leg = 0.22, 0.02
    parts = [Part((seat, seat, 0.02), (0, 0, 0.43), rgba),
             Part((0.02, seat, 0.23), (-seat + 0.02, 0, 0.68), rgba)]
    for sx in (-1, 1):
        for sy in (-1, 1):
            parts.append(Part((leg, leg, 0.205), (sx * (seat - leg), sy * (seat - leg), 0.205),
                              rgba))
    return parts


def _sofa(frame: Colour, cushion: Colour) -> list[Part]:
    """A 1.8 m sofa, seat at 0.42 m; it faces its local +x."""
    return [Part((0.4, 0.9, 0.16), (0, 0, 0.16), frame),          # base
            Part((0.3, 0.74, 0.05), (0.08, 0, 0.37), cushion),    # seat cushion, top at 0.42
            Part((0.1, 0.9, 0.3), (-0.3, 0, 0.62), frame),        # back, top at 0.92
            Part((0.4, 0.08, 0.11), (0, 0.82, 0.43), frame),      # arm rests
            Part((0.4, 0.08, 0.11), (0, -0.82, 0.43), frame)]


def _bin(rgba: Colour) -> list[Part]:
    """An open box 0.4 x 0.4 x 0.5 m: a bottom and four walls, nothing on top."""
    h, w, t = 0.25, 0.2, 0.01
    return [Part((w, w, t), (0, 0, t), rgba),
            Part((t, w, h), (w - t, 0, h), rgba), Part((t, w, h), (-w + t, 0, h), rgba),
            Part((w, t, h), (0, w - t, h), rgba), Part((w, t, h), (0, -w + t, h), rgba)]


def _cupboard(rgba: Colour) -> list[Part]:
    """A closed cabinet 0.5 deep, 1.0 wide, 1.6 tall; doors face its local +x."""
    return [Part((0.25, 0.5, 0.8), (0, 0, 0.8), rgba),
            Part((0.005, 0.003, 0.7), (0.255, 0, 0.85), (0.25, 0.18, 0.1, 1.0))]


# name -> (x, y, yaw, parts).  Layout of Fig. 8: the coffee table in the middle
# of the room with the sofa behind it, chairs beside the coffee table and at the
# store table, the trash bin in a corner, the cupboard on the west wall.
FURNITURE: dict[str, tuple[float, float, float, list[Part]]] = {
    "coffee-table": (0.0, 0.0, 0.0, _table(0.9, 0.5, 0.45, WOOD_DARK)),
    "store-table": (2.1, 1.7, 0.0, _table(1.0, 0.6, 0.72, WOOD_LIGHT)),
    "sofa": (0.0, 1.35, -math.pi / 2, _sofa((0.45, 0.1, 0.12, 1), (0.62, 0.16, 0.18, 1))),
    "chair-1": (-1.35, 0.0, 0.0, _chair((0.3, 0.2, 0.12, 1))),
    "chair-2": (2.1, 2.25, -math.pi / 2, _chair((0.3, 0.2, 0.12, 1))),
    "trash": (-2.3, -1.7, 0.0, _bin((0.25, 0.4, 0.3, 1))),
    "cupboard": (-2.72, 1.0, 0.0, _cupboard((0.55, 0.38, 0.22, 1))),
}



def footprint(x: float, y: float, yaw: float, parts: Sequence[Part]) -> Footprint:
    """The bounding rectangle on the floor of boxes placed at (x, y, yaw)."""
    lo_x = min(p.offset[0] - p.half_extents[0] for p in parts)
    hi_x = max(p.offset[0] + p.half_extents[0] for p in parts)
    lo_y = min(p.offset[1] - p.half_extents[1] for p in parts)
    hi_y = max(p.offset[1] + p.half_extents[1] for p in parts)
    cx, cy = (lo_x + hi_x) / 2, (lo_y + hi_y) / 2
    c, s = math.cos(yaw), math.sin(yaw)
    return Footprint(x + c * cx - s * cy, y + s * cx + c * cy, yaw,
                     (hi_x - lo_x) / 2, (hi_y - lo_y) / 2)


FOOTPRINTS = {name: footprint(x, y, yaw, parts) for name, (x, y, yaw, parts) in FURNITURE.items()}
"""Each piece of furniture's footprint, known without building a world (to check files)."""

ROOM = (-3.0, 3.0, -2.5, 2.6)  # x min, x max, y min, y max of the floor
WALL_HEIGHT = 1.4
FLOOR_RGBA: Colour = (0.78, 0.72, 0.6, 1.0)
WALL_RGBA: Colour = (0.88, 0.87, 0.82, 1.0)

BOTTLE_RADIUS = 0.035
BOTTLE_HEIGHT = 0.22
BOTTLE_MASS = 0.4
# name -> (x, y on the coffee table, colour).  All within Jido's reach from
# coffee-area; a scenario that needs an unreachable bottle moves one.
BOTTLES: dict[str, tuple[float, float, Colour]] = {
    "yellow-bottle": (-0.3, 0.0, (0.95, 0.82, 0.1, 1.0)),
    "green-bottle": (-0.1, -0.08, (0.15, 0.65, 0.2, 1.0)),
    "orange-bottle": (0.12, 0.0, (1.0, 0.5, 0.05, 1.0)),
    "blue-bottle": (0.32, -0.08, (0.12, 0.3, 0.9, 1.0)),
}

# Robot base places (x, y, yaw), the nodes of the roadmap.  Each faces what is
# done there: the coffee table, the store table, the trash bin, the sofa.
PLACES: dict[str, Place] = {
    "base": (1.5, -1.75, math.pi / 2),
    "coffee-area": (0.0, -0.7, math.pi / 2),
    "store-area": (2.1, 0.95, math.pi / 2),
    "trash-area": (-1.55, -1.7, math.pi),
    "sofa-area": (1.4, 0.75, 3 * math.pi / 4),
}

MANIPULATION_PLACES: dict[str, str] = {"coffee-table": "coffee-area",
                                       "store-table": "store-area",
                                       "trash": "trash-area", "sofa": "sofa-area"}
"""Furniture -> the place a robot handles it from (HATP's ``f.place``)."""
CONTAINERS = ("trash",)
"""Furniture things are put *in* (and fall into), not *on*."""
SEATS = ("sofa",)
"""Furniture people sit on."""

# A robot base is kept this far from furniture footprints when the roadmap is
# built: Jido's base radius (0.3 m) plus a margin.
CLEARANCE = 0.35
