"""Stacking in the living room's physics: the robot places on a cube, the robot sees
what rests on what.

The living room's executors and perception know furniture as supports; the
StackBuildingTask puts cubes on placements, a stick across two cubes and cubes
on the stick.  :class:`StackExecutors` places on any object (the gripper goes
to the top of the support, centred on it) and :class:`StackPerception` adds
``isOn(object, support)`` for an object resting on another one.
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
