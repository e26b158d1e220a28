"""Perception: what the robot knows of the world, as facts in its perspective.

After every tick (and every instant change) :class:`Perception` computes the
facts the world makes true — ``isAt``, ``isOn``/``isIn``, ``isHolding``,
``looksAt``, ``sees``, ``handMovingToward`` (a person's reaching hand), ``isNear``,
``isReachableBy``, ``isSeatedOn``, ``position`` —
and publishes only the difference to the fact database, so monitors and
chronicles hear of changes, not of ticks.

What the robot can know is limited the way SHARY's robot was:

* **objects are seen, not known**: where an object is changes in the robot's
  beliefs only when the object (or the spot where it was believed to be) is
  in the head camera's field of view — which is why Jido must go and look at
  the table after a person has been there (Fig. 12);
* **what is out of view is unknown, not unchanged**: ``sees(robot, object)``
  holds exactly while the object is in the camera's view; the facts about an
  object without it are the last ones seen, which the plan managers do not
  take as evidence that an expected effect has not happened (they look
  first: :mod:`shary.plans.recovery`);
* **people are tracked** (the paper's motion capture): where they are, what
  they hold and where they look is always known.

Two filters make facts robust to a noisy feed: a fact that disappears is
only removed after it has stayed absent for ``hold`` seconds (a blink of the
detector does not make the person "look away"), and a fact that appears is
added at once.  Noise can be injected to test that (``flicker``: each fact of
a predicate is missed at a tick with some probability; ``lost``: an entity is
not detected at all for a while).
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from rdflib import Literal

from .executors import ROBOT_REACH
from .humans import ARM_LENGTH
from .simulation import TICK, Simulation
from .world import CONTAINERS, FURNITURE, SEATS, pb

Fact = tuple[str, str, Any]

NEAR = 0.9
"""A person this close to a piece of furniture (its footprint) is near it."""
GAZE_CONE = math.radians(12)
CAMERA_HALF_FOV = math.radians(36)
CAMERA_RANGE = 5.0
PLACE_TOLERANCE = 0.2
PERSON_AT = 1.5
"""A person within this distance of a robot place is at it (the planner's places are the
robot's: a person at sofa-area is one the robot serves from there)."""


@dataclass
class Noise:
    """Perception faults: per-predicate miss probability, and detection losses."""

    flicker: dict[str, float] = field(default_factory=dict)
    lost: list[tuple[str, float, float]] = field(default_factory=list)  # entity, from, to


class Perception:
    """Publishes the world's facts into a fact database (see the module's docstring)."""

    def __init__(self, sim: Simulation, facts: Any,
                 *, perspective: str = "robot", hold: float = 0.5, noise: Noise | None = None,
                 rng: random.Random | None = None):
        self.sim = sim
        self.world = sim.world
        self.facts = facts
        self.perspective = perspective
        self.hold = hold
        self.noise = noise or Noise()
        self.rng = rng or random.Random(0)
        self.published: dict[Fact, None] = {}
        self.misses = 0
        """Facts the injected noise made the detector miss, over the run."""
        self.missing_since: dict[Fact, float] = {}
        self.belief: dict[str, tuple[float, float, float]] = {}  # object -> where last seen
        self.object_facts: dict[str, tuple[Fact, ...]] = {}
        self._recheck: Any = None
        self._furniture_names = list(FURNITURE)
        self._furniture_points = [(self.world.footprints[f].x, self.world.footprints[f].y,
                                   self.world.top(f)) for f in FURNITURE]

    # -- the world's facts -------------------------------------------------------

    def start(self) -> None:
        """Publish what the robot knows at the start: it has seen every object once."""
        for obj in self.world.movables:
            self.belief[obj] = self.world.position(obj)
            self.object_facts[obj] = tuple(self._object_facts(obj, self.belief[obj]))
        self.update()

    def update(self) -> None:
        now = self.sim.loop.now()
        # lists and dicts, never sets: the order facts are published in (and so the
        # order subscribers hear them, and which fact each noise draw falls on) must
        # not depend on the process's string hashing
        seen = dict.fromkeys(self._facts(now))
        flickered = False
        for predicate, p in sorted(self.noise.flicker.items()):
            for fact in [f for f in seen if f[1] == predicate]:
                if self.rng.random() < p:
                    del seen[fact]
                    self.misses += 1
                    flickered = True
        for fact in seen:
            self.missing_since.pop(fact, None)
            if fact not in self.published:
                self.facts.add(*fact, perspective=self.perspective)
                self.published[fact] = None
        for fact in [f for f in self.published if f not in seen]:
            since = self.missing_since.setdefault(fact, now)
            if now - since >= self.hold - 1e-9:
                self.facts.remove(*fact, perspective=self.perspective)
                del self.published[fact]
                del self.missing_since[fact]
        if (self.missing_since or flickered) and self._recheck is None and not self.sim.busy:
            # nothing ticks while the world is still: keep looking at the tick's rate
            # until every missing fact is back or gone, and every fact a flicker hid
            # (one never seen yet included) has been seen
            self._recheck = self.sim.loop.call_later(TICK, self._look_again)

    def _look_again(self) -> None:
        self._recheck = None
        self.update()

    def _lost(self, entity: str, now: float) -> bool:
        return bool(self.noise.lost) and any(e == entity and t0 <= now < t1
                                             for e, t0, t1 in self.noise.lost)

    def _facts(self, now: float) -> Iterable[Fact]:
        world, sim = self.world, self.sim
        robot = sim.robot
        rx, ry, _ = world.base_pose(robot)
        place, distance = world.nearest_place(rx, ry)
        if distance <= PLACE_TOLERANCE:
            yield (robot, "isAt", place)
        for obj, holder in sim.holder.items():
            if holder == robot:
                yield (robot, "isHolding", obj)
        positions = {obj: world.position(obj) for obj in world.movables}
        names, points = self._targets(positions)
        camera, forward = self._camera()
        looked = self._looked_at(camera, forward, robot, names, points)
        if looked is not None:
            yield (robot, "looksAt", looked)
        mount = world.shoulder(robot)
        for obj, where_now in positions.items():
            if self._lost(obj, now):
                continue
            if obj in sim.holder or self._visible(camera, forward, where_now):
                self.belief[obj] = where_now
                self.object_facts[obj] = tuple(self._object_facts(obj, where_now))
                if obj not in sim.holder:
                    yield (robot, "sees", obj)
            elif obj in self.belief and self._visible(camera, forward, self.belief[obj]):
                # looking where it was, and it is not there any more
                del self.belief[obj]
                self.object_facts[obj] = ()
            yield from self.object_facts.get(obj, ())
            where = self.belief.get(obj)
            if where is not None and obj not in sim.holder:
                if math.hypot(where[0] - mount[0], where[1] - mount[1]) <= ROBOT_REACH:
                    yield (obj, "isReachableBy", robot)
        for name, avatar in sim.people.items():
            if self._lost(name, now):
                continue
            # a person is "at" the robot place from which the robot can serve them
            place, distance = world.nearest_place(avatar.x, avatar.y)
            if distance <= PERSON_AT:
                yield (name, "isAt", place)
            for obj, holder in sim.holder.items():
                if holder == name and not self._lost(obj, now):
                    yield (name, "isHolding", obj)
            looked = self._looked_at(avatar.eyes, avatar.gaze_direction(), name, names, points)
            if looked is not None:
                yield (name, "looksAt", looked)
            if avatar.hand_out is not None:  # a movement action recognition starts from
                target = self._reached(avatar.hand_out, positions, name)
                if target is not None:
                    yield (name, "handMovingToward", target)
            for furniture in FURNITURE:
                if world.footprints[furniture].contains(avatar.x, avatar.y, NEAR):
                    yield (name, "isNear", furniture)
            if math.hypot(avatar.x - rx, avatar.y - ry) <= 1.5:
                yield (name, "isNear", robot)
            if avatar.seated:
                for seat in SEATS:
                    if world.footprints[seat].contains(avatar.x, avatar.y, 0.1):
                        yield (name, "isSeatedOn", seat)
            for obj, where in self.belief.items():  # what the robot believes is where
                if (obj not in sim.holder and not self._lost(obj, now)
                        and math.hypot(where[0] - avatar.x, where[1] - avatar.y) <= ARM_LENGTH):
                    yield (obj, "isReachableBy", name)

    def truth(self) -> Iterable[tuple[str, str, str]]:
        """What the world makes true of its objects now, seen or not: who holds what,
        what rests on or in what (from true poses, without noise or the camera's view)."""
        for obj, holder in self.sim.holder.items():
            yield (holder, "isHolding", obj)
        for obj in self.world.movables:
            for s, p, o in self._object_facts(obj, self.world.position(obj)):
                if p in ("isOn", "isIn"):
                    yield (s, p, str(o))

    def _reached(self, hand: tuple[float, float, float],
                 positions: dict[str, tuple[float, float, float]], person: str) -> str | None:
        """What a reaching hand goes for: an object it is on (10 cm), else the furniture
        whose top it is over, else nothing."""
        for obj, where in positions.items():
            if self.sim.holder.get(obj) != person and math.dist(where, hand) <= 0.1:
                return obj
        for furniture in FURNITURE:
            if self.world.footprints[furniture].contains(hand[0], hand[1]):
                return furniture
        return None

    def _object_facts(self, obj: str, where: tuple[float, float, float]) -> Iterable[Fact]:
        """Where an object is, from its true pose (called when the robot sees it)."""
        if obj in self.sim.holder:
            return
        x, y, z = where
        yield (obj, "position", Literal(f"{x:.2f} {y:.2f} {z:.2f}"))
        bottom = z - self.world.sizes[obj][0] / 2
        for furniture in FURNITURE:
            footprint = self.world.footprints[furniture]
            if not footprint.contains(x, y):
                continue
            top = self.world.top(furniture)
            if furniture in CONTAINERS and bottom < top:
                yield (obj, "isIn", furniture)
            elif abs(bottom - top) < 0.04:
                yield (obj, "isOn", furniture)

    # -- geometry -----------------------------------------------------------------

    def _camera(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """Where the head camera is, and the direction it looks in (its x axis)."""
        pos, orn = self.world.link_pose(self.sim.robot, "camera_link")
        m = pb.getMatrixFromQuaternion(orn)  # row-major: the x axis is the first column
        return pos, (m[0], m[3], m[6])

    @staticmethod
    def _angle(origin: Any, direction: Any, point: Any) -> float:
        # plain floats: numpy's overhead on three numbers was a third of a tick's cost
        vx, vy, vz = point[0] - origin[0], point[1] - origin[1], point[2] - origin[2]
        n = math.hypot(vx, vy, vz)
        if n < 1e-9:
            return math.pi
        dx, dy, dz = direction
        return math.acos(max(-1.0, min(1.0, (vx * dx + vy * dy + vz * dz) / n)))

    def _visible(self, camera: Any, forward: Any, point: Any) -> bool:
        return (math.dist(camera, point) <= CAMERA_RANGE
                and self._angle(camera, forward, point) <= CAMERA_HALF_FOV)

    def _targets(self, positions: dict[str, tuple[float, float, float]]
                 ) -> tuple[list[str], np.ndarray]:
        """Everything one may look at, and where (computed once per update)."""
        world, sim = self.world, self.sim
        names = [sim.robot, *sim.people, *positions, *self._furniture_names]
        points = [world.link_position(sim.robot, "camera_link"),
                  *(a.eyes for a in sim.people.values()), *positions.values(),
                  *self._furniture_points]
        return names, np.asarray(points, dtype=float)

    def _looked_at(self, eyes: Any, direction: Any, exclude: str, names: list[str],
                   points: np.ndarray) -> str | None:
        """What lies closest to the line of sight, within the gaze cone."""
        v = points - np.asarray(eyes, dtype=float)
        norms = np.linalg.norm(v, axis=1)
        norms[norms < 1e-9] = np.inf
        cosines = (v @ np.asarray(direction, dtype=float)) / norms
        for i, name in enumerate(names):
            if name == exclude:
                cosines[i] = -2.0
        best = int(np.argmax(cosines))
        return names[best] if cosines[best] >= math.cos(GAZE_CONE) else None
