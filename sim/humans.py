"""Simulated people: kinematic avatars, and behaviour profiles that drive them.

An :class:`Avatar` is three bodies moved kinematically: a torso (a cylinder
that robots and perception can bump into), a head whose direction is the
person's attention, and a hand that reaches out, takes and holds objects.
People do not need dynamics for what the scenarios ask of them — where they
stand, where they look, what they hold — and skipping it keeps runs fast.

A :class:`Profile` says how a person behaves (``sim/profiles/*.yaml`` or
inline in a scenario): how they answer the robot's questions and after what
delay, where their attention goes (a phone call when the robot's arm starts
moving towards them, and for how long), whether they take what is held out
to them, whether they help, and a script of things they do on their own.
Delays given as ``[low, high]`` are drawn from the run's seeded generator,
so a seed gives the same run every time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .world import LivingRoom, pb

TORSO_RADIUS = 0.2
STANDING_EYES = 1.62
SEATED_DROP = 0.45
ARM_LENGTH = 0.85
"""A person reaches objects this far (horizontally) from where they stand, bending over."""
WALK_SPEED = 0.9
"""m/s unless the profile says otherwise."""
SKIN = (0.87, 0.7, 0.58, 1.0)

# Where people stand, sit or go (x, y, yaw, seated).  Robot places are for bases;
# these are for people: the sofa seat, the sides of the tables, the door.
HUMAN_PLACES: dict[str, tuple[float, float, float, bool]] = {
    "sofa-seat": (0.55, 1.3, -math.pi / 2, True),
    "sofa-end": (1.2, 1.2, -math.pi / 2, False),
    "coffee-north": (-0.3, 0.62, -math.pi / 2, False),
    "coffee-east": (0.85, 0.0, math.pi, False),
    "store-side": (1.25, 1.7, 0.0, False),
    "door": (2.55, -2.05, math.pi / 2, False),
    "corridor": (2.55, 0.2, math.pi, False),
}
# Points people walk through to go round the furniture (not destinations).
WAYPOINTS: list[tuple[float, float]] = [
    (-0.8, 0.62), (0.85, 0.62), (0.85, -0.6), (-0.85, -0.6), (1.6, -1.1), (2.55, -1.0),
    (1.5, 0.6),
]


@dataclass(frozen=True)
class Answer:
    """How a person answers one act: the act they reply with (None: silence), when."""

    reply: str | None
    after: tuple[float, float] = (1.0, 1.0)


@dataclass(frozen=True)
class Distraction:
    """Attention elsewhere: when (a time, or when the robot starts an action), how long."""

    look: str
    after: tuple[float, float] = (0.0, 0.0)
    at: float | None = None
    robot_starts: str | None = None
    duration: float | None = None  # None: never looks back


@dataclass(frozen=True)
class ScriptStep:
    """Something a person does on their own: walk, sit, put an object down, look."""

    after: tuple[float, float]
    at: float | None
    walk: str | None = None
    put: str | None = None
    on: str | None = None
    take: str | None = None
    look: str | None = None


@dataclass(frozen=True)
class Profile:
    """A person's behaviour (see the module's docstring)."""

    name: str
    answers: dict[str, Answer] = field(default_factory=dict)
    attention: str = "robot"
    distractions: tuple[Distraction, ...] = ()
    takes: tuple[float, float] | None = (1.0, 1.0)
    helps: bool = True
    speed: float = WALK_SPEED
    script: tuple[ScriptStep, ...] = ()
    doc: str = ""


class Avatar:
    """A person's bodies in the world, moved kinematically."""

    def __init__(self, world: LivingRoom, name: str, x: float, y: float, yaw: float,
                 shirt: tuple[float, float, float, float]):
        self.world = world
        self.name = name
        self.x, self.y, self.yaw = x, y, yaw
        self.seated = False
        self.gaze = (x + math.cos(yaw), y + math.sin(yaw), 1.0)
        self.hand_out: tuple[float, float, float] | None = None
        call = world.call
        torso_col = call(pb.createCollisionShape, pb.GEOM_CYLINDER, radius=TORSO_RADIUS,
                         height=1.4)
        torso_vis = call(pb.createVisualShape, pb.GEOM_CYLINDER, radius=TORSO_RADIUS,
                         length=1.4, rgbaColor=list(shirt))
        head_vis = call(pb.createVisualShape, pb.GEOM_SPHERE, radius=0.11, rgbaColor=list(SKIN))
        nose_vis = call(pb.createVisualShape, pb.GEOM_BOX, halfExtents=[0.06, 0.025, 0.02],
                        rgbaColor=[0.15, 0.15, 0.15, 1])
        hand_vis = call(pb.createVisualShape, pb.GEOM_SPHERE, radius=0.045, rgbaColor=list(SKIN))
        self.torso = call(pb.createMultiBody, baseMass=0, baseCollisionShapeIndex=torso_col,
                          baseVisualShapeIndex=torso_vis, basePosition=[x, y, 0.7])
        self.head = call(pb.createMultiBody, baseMass=0, baseVisualShapeIndex=head_vis,
                         basePosition=[x, y, STANDING_EYES])
        self.nose = call(pb.createMultiBody, baseMass=0, baseVisualShapeIndex=nose_vis,
                         basePosition=[x, y, STANDING_EYES])
        self.hand = call(pb.createMultiBody, baseMass=0, baseVisualShapeIndex=hand_vis,
                         basePosition=[x, y, 0.8])
        world.register(name, self.torso)
        self.place()

    @property
    def eyes(self) -> tuple[float, float, float]:
        return (self.x, self.y, STANDING_EYES - (SEATED_DROP if self.seated else 0.0))

    @property
    def shoulder(self) -> tuple[float, float, float]:
        return (self.x + 0.2 * math.cos(self.yaw - math.pi / 2),
                self.y + 0.2 * math.sin(self.yaw - math.pi / 2), self.eyes[2] - 0.25)

    def hand_position(self) -> tuple[float, float, float]:
        if self.hand_out is not None:
            return self.hand_out
        sx, sy, sz = self.shoulder
        return (sx + 0.15 * math.cos(self.yaw), sy + 0.15 * math.sin(self.yaw), sz - 0.45)

    def look_at_point(self, point: tuple[float, float, float]) -> None:
        self.gaze = point
        self.place()

    def place(self) -> None:
        """Put the bodies where the person's state says (after a walk step, a look, a reach)."""
        call = self.world.call
        drop = SEATED_DROP if self.seated else 0.0
        call(pb.resetBasePositionAndOrientation, self.torso, [self.x, self.y, 0.7 - drop],
             [0, 0, math.sin(self.yaw / 2), math.cos(self.yaw / 2)])
        ex, ey, ez = self.eyes
        gx, gy, gz = self.gaze
        heading = math.atan2(gy - ey, gx - ex)
        pitch = math.atan2(gz - ez, math.hypot(gx - ex, gy - ey))
        call(pb.resetBasePositionAndOrientation, self.head, [ex, ey, ez], [0, 0, 0, 1])
        nose = (ex + 0.11 * math.cos(heading) * math.cos(pitch),
                ey + 0.11 * math.sin(heading) * math.cos(pitch), ez + 0.11 * math.sin(pitch))
        call(pb.resetBasePositionAndOrientation, self.nose, list(nose),
             pb.getQuaternionFromEuler([0, -pitch, heading]))
        call(pb.resetBasePositionAndOrientation, self.hand, list(self.hand_position()),
             [0, 0, 0, 1])

    def gaze_direction(self) -> tuple[float, float, float]:
        ex, ey, ez = self.eyes
        gx, gy, gz = self.gaze
        n = math.dist(self.eyes, self.gaze) or 1.0
        return ((gx - ex) / n, (gy - ey) / n, (gz - ez) / n)


def seconds(value: Any) -> float:
    """A duration from a file (its form checked by the schema): a number of seconds, or
    ``5s``, ``2 min``, ``500ms``."""
    from shary.model import parse_duration

    if isinstance(value, int | float):
        return float(value)
    text = "".join(str(value).split())
    try:
        return float(text)
    except ValueError:
        return parse_duration(text)


def parse_range(value: Any) -> tuple[float, float]:
    """``2s``, ``2`` or ``[1s, 3s]`` -> (low, high) in seconds."""
    if isinstance(value, list):
        return seconds(value[0]), seconds(value[1])
    return seconds(value), seconds(value)


def profile_from(name: str, data: dict[str, Any]) -> Profile:
    """A :class:`Profile` from checked YAML data (see sim/schemas/profile.schema.json)."""
    answers = {}
    for act, spec in (data.get("answers") or {}).items():
        answers[act] = Answer(spec.get("reply"), parse_range(spec.get("after", "1s")))
    distractions = []
    for spec in data.get("distractions") or []:
        when = spec.get("when", {})
        duration = spec.get("for", "never")
        distractions.append(Distraction(
            str(spec.get("look", "away")), parse_range(spec.get("after", 0)),
            seconds(when["at"]) if "at" in when else None,
            when.get("robot-starts"),
            None if duration == "never" else parse_range(duration)[0]))
    takes = data.get("takes", {"after": "1s"})
    script = []
    for spec in data.get("script") or []:
        script.append(ScriptStep(parse_range(spec.get("after", 0)),
                                 seconds(spec["at"]) if "at" in spec else None,
                                 spec.get("walk"), spec.get("put"), spec.get("on"),
                                 spec.get("take"), spec.get("look")))
    return Profile(name, answers, str(data.get("attention", "robot")), tuple(distractions),
                   None if takes is None else parse_range(takes.get("after", "1s")),
                   bool(data.get("helps", True)), float(data.get("speed", WALK_SPEED)),
                   tuple(script), str(data.get("doc", "")))
