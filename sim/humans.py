"""Simulated people: behaviour profiles, and the places people stand, sit or go.

A :class:`Profile` says how a person behaves (``sim/profiles/*.yaml`` or
inline in a scenario): how they answer the robot's questions and after what
delay, where their attention goes (a phone call when the robot's arm starts
moving towards them, and for how long), whether they take what is held out
to them, whether they help, and a script of things they do on their own.
Delays given as ``[low, high]`` are drawn from the run's seeded generator,
so a seed gives the same run every time.

This module is plain data (no PyBullet): reading a scenario or a profile
never loads the physics engine.  The bodies that play a person in the world
are :mod:`sim.avatar`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from userfiles.limits import seconds

TORSO_RADIUS = 0.2
ARM_LENGTH = 0.85
"""A person reaches objects this far (horizontally) from where they stand, bending over."""
WALK_SPEED = 0.9
"""m/s unless the profile says otherwise."""

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
    """How a person answers one act: the act they reply with, when; or words alone (the
    robot hears a sentence: "I'll take the bottle myself"); neither: silence."""

    reply: str | None
    after: tuple[float, float] = (1.0, 1.0)
    choose: dict[str, Any] | None = None
    """For a question (ASK-WHICH): the description of the thing meant (``{isOn: shelf}``)."""
    words: str | None = None
    """What the person says as the answer ("The one on the store table."): the robot
    hears the sentence (instead of a description)."""


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
    act: str | None = None
    """A communication act the person starts (ASK-TASK, CANCEL) about ``task``; without
    one, what the person says (``words``) is heard by the robot as a sentence."""
    task: str | None = None
    args: dict[str, Any] = field(default_factory=dict)
    """The act's task arguments: names, or descriptions (``{type: Cube, color: green}``)."""
    words: str | None = None
    """What the person says aloud with the act."""
    leave: bool = False
    """Walk out of the room by the door: the robot perceives them no more."""


@dataclass(frozen=True)
class Profile:
    """A person's behaviour (see the module's docstring)."""

    name: str
    answers: dict[str, tuple[Answer, ...]] = field(default_factory=dict)
    """Act -> the answers to it, the first time, the second …; the last one repeats."""
    attention: str = "robot"
    distractions: tuple[Distraction, ...] = ()
    takes: tuple[float, float] | None = (1.0, 1.0)
    helps: bool = True
    speed: float = WALK_SPEED
    script: tuple[ScriptStep, ...] = ()
    doc: str = ""


def parse_range(value: Any) -> tuple[float, float]:
    """``2s``, ``2`` or ``[1s, 3s]`` -> (low, high) in seconds."""
    if isinstance(value, list):
        return seconds(value[0]), seconds(value[1])
    return seconds(value), seconds(value)


def profile_from(name: str, data: dict[str, Any]) -> Profile:
    """A :class:`Profile` from checked YAML data (see sim/schemas/profile.schema.json)."""
    answers = {}
    for act, given in (data.get("answers") or {}).items():
        answers[act] = tuple(Answer(spec.get("reply"), parse_range(spec.get("after", "1s")),
                                    spec.get("choose"), spec.get("say"))
                             for spec in (given if isinstance(given, list) else [given]))
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
                                 spec.get("take"), spec.get("look"), spec.get("act"),
                                 spec.get("task"), dict(spec.get("with") or {}),
                                 spec.get("say"), bool(spec.get("leave", False))))
    return Profile(name, answers, str(data.get("attention", "robot")), tuple(distractions),
                   None if takes is None else parse_range(takes.get("after", "1s")),
                   bool(data.get("helps", True)), float(data.get("speed", WALK_SPEED)),
                   tuple(script), str(data.get("doc", "")))
