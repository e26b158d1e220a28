"""Stacking in the living room's physics: the robot places on a cube, the robot sees
what rests on what.

The living room's executors and perception know furniture as supports; the
StackBuildingTask puts cubes on placements, a stick across two cubes and cubes
on the stick.  :class:`StackExecutors` places on any object (the gripper goes
to the top of the support, centred on it) and :class:`StackPerception` adds
``isOn(object, support)`` for an object resting on another one.

Two red cubes, two blue cubes and two placements look alike; what tells them
apart for a person is where they are for them: perception also says which
agent an object on the table is near (``isNear(object, agent)``: "the red
cube near you") and on which side of each person it lies
(``leftOf``/``rightOf(object, person)``, from where they stand: "the placement
on your left"), the relations :mod:`shary.dialogue.reg` describes things with.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from sim.executors import ActionFailed, RobotExecutors
from sim.perception import Perception
from sim.simulation import standing_height
from sim.world import pb

__all__ = ["StackExecutors", "StackPerception", "top_of"]

RESTING = 0.02
"""How close (m) an object's bottom must be to a support's top to rest on it."""
NEAR_AGENT = 1.0
"""How far (m) an object may be from the agent it is near."""
CLEARLY = 0.1
"""How much nearer (m) to one agent than to any other an object must be to be near it."""
SIDE = 0.05
"""How far (m) from a person's line of sight to the table's centre an object must be
to be on their left or right."""
TABLE = "coffee-table"
"""The stack table (sim/stack/table.py)."""


def top_of(world: Any, support: str) -> tuple[float, float, float]:
    """The centre of ``support``'s top face."""
    (x0, y0, _), (x1, y1, z1) = world.aabb(support)
    return ((x0 + x1) / 2, (y0 + y1) / 2, z1)


class StackExecutors(RobotExecutors):
    """The robot's executors, whose ``place`` also puts an object on another object."""

    def _place(self, running: Any, object: str, on: str) -> Any:
        if on in self.world.footprints:
            return super()._place(running, object, on)
        self._holding(object)
        if on not in self.world.sizes:
            raise ActionFailed(f"{on!r} is nothing {self.robot} can place on")
        x, y, z = top_of(self.world, on)
        return self._put_down(running, object,
                              (x, y, standing_height(z, self.world.sizes[object][0])), on)


class StackPerception(Perception):
    """The robot's perception, which also sees an object resting on another object.

    Which object rests on which depends on every object's bounding box, so it is
    worked out once per look at a scene, not once per object and tick: the boxes are
    read when first needed and each object's facts kept, until something moves (an
    object's pose or who holds what changes: :meth:`_look`).  While the robot moves
    its arm or talks, nothing on the table does, and perception costs a few pose reads.
    """

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self._scene: Any = None
        self._boxes: dict[str, tuple[Any, Any]] = {}
        self._facts_seen: dict[tuple[str, tuple[float, float, float]], tuple[Any, ...]] = {}

    def update(self) -> None:
        self._look()
        super().update()

    def _look(self) -> None:
        """Forget the boxes and facts worked out if anything moved since they were."""
        world = self.world
        scene = (tuple(world.call(pb.getBasePositionAndOrientation, world.body(obj))
                       for obj in world.movables), tuple(self.sim.holder))
        if scene != self._scene:
            self._scene = scene
            self._boxes.clear()
            self._facts_seen.clear()

    def _box(self, obj: str) -> tuple[Any, Any]:
        box = self._boxes.get(obj)
        if box is None:
            box = self._boxes[obj] = self.world.aabb(obj)
        return box

    def _object_facts(self, obj: str, where: tuple[float, float, float]) -> Iterable[Any]:
        if self._scene is None:  # the first look (Perception.start), before any update
            self._look()
        key = (obj, where)
        facts = self._facts_seen.get(key)
        if facts is None:
            facts = self._facts_seen[key] = tuple(self._stacked_facts(obj, where))
        return facts

    def _stacked_facts(self, obj: str, where: tuple[float, float, float]) -> Iterable[Any]:
        on = list(self._on_objects(obj, where))
        for fact in super()._object_facts(obj, where):
            if not (on and fact[1] == "isOn"):  # on a cube, not on the table under it
                yield fact
        yield from on
        if obj not in self.sim.holder:
            yield from self._around(obj, where)

    def _around(self, obj: str, where: tuple[float, float, float]) -> Iterable[Any]:
        """Which agent ``obj`` is near, and on which side of each person it is."""
        rx, ry, _ = self.world.base_pose(self.sim.robot)
        agents = {self.sim.robot: (rx, ry)}
        cx, cy, _ = top_of(self.world, TABLE)
        for name, avatar in self.sim.people.items():
            agents[name] = (avatar.x, avatar.y)
            # Left and right as the person sees the table: across their line of sight
            # to its centre (not their body's heading: they stand off-centre).
            ahead = math.hypot(cx - avatar.x, cy - avatar.y)
            if ahead < 1e-6:
                continue
            left = (-(cy - avatar.y) / ahead, (cx - avatar.x) / ahead)
            side = (where[0] - avatar.x) * left[0] + (where[1] - avatar.y) * left[1]
            if abs(side) >= SIDE:
                yield (obj, "leftOf" if side > 0 else "rightOf", name)
        distances = sorted((math.hypot(where[0] - x, where[1] - y), name)
                           for name, (x, y) in agents.items())
        if distances[0][0] <= NEAR_AGENT and (len(distances) == 1
                                              or distances[1][0] - distances[0][0] >= CLEARLY):
            yield (obj, "isNear", distances[0][1])

    def _on_objects(self, obj: str, where: tuple[float, float, float]) -> Iterable[Any]:
        if obj in self.sim.holder:
            return
        bottom = where[2] - self.world.sizes[obj][0] / 2
        for other in self.world.movables:
            if other == obj or other in self.sim.holder:
                continue
            (x0, y0, _), (x1, y1, z1) = self._box(other)
            if (x0 - 0.01 <= where[0] <= x1 + 0.01 and y0 - 0.01 <= where[1] <= y1 + 0.01
                    and abs(bottom - z1) < RESTING):
                yield (obj, "isOn", other)
            elif self._across(obj, other, bottom, z1):
                yield (obj, "isOn", other)

    def _across(self, obj: str, other: str, bottom: float, top: float) -> bool:
        """A long object (the stick) lies across ``other`` when its ends reach over it."""
        if abs(bottom - top) >= RESTING:
            return False
        (a0, b0, _), (a1, b1, _) = self._box(obj)
        (x0, y0, _), (x1, y1, _) = self._box(other)
        return a0 <= x1 and x0 <= a1 and b0 <= y1 and y0 <= b1 and \
            math.hypot(a1 - a0, b1 - b0) > 2 * math.hypot(x1 - x0, y1 - y0)
