"""Physics after an object is let go: step until whatever moves has come to rest.

The simulation moves robots, people and held objects kinematically and hands
the world to PyBullet only when an object is let go (:meth:`Simulation.settle
<sim.simulation.Simulation.settle>`), so that contact decides whether it stands,
topples or falls.  What that costs is the number of 240 Hz steps times the
bodies each step solves, and both used to be far more than the question needs:

* **Robots and held objects are still.**  They are position-controlled and
  carried kinematically everywhere else; stepped as multibodies they cost most
  of a step (a PR2 is 27 links and motors) and their motors at the rated effort
  do not hold an outstretched arm, which sagged by centimetres into the stack
  it had just built, and a cube held in a hand fell out of it.  While physics
  steps, they are obstacles of mass 0 (static for Bullet: other bodies collide
  with them, they do not move), their masses and inertias put back after.
* **Stepping ends when every free object is at rest**, at most after the
  time given: an object dropped one millimetre onto a table rests within a few
  hundredths of a second; one that falls, rolls or is knocked keeps physics
  going until it stops too.
* **Resting objects sleep**: one at rest for :data:`CALM_CHECKS` checks in a
  row is put to sleep (and its velocity cleared), so a step costs only what
  still moves.  A sleeping body is still an obstacle, and Bullet wakes it the
  moment a moving body touches it (the two are one island), so a cube dropped
  on a sleeping stack knocks it as it would an awake one.  An object the last
  let-go left at rest starts the next one asleep if it is still where it was
  and nothing moved away from near it; any other (the one let go, one left in
  the air by a support picked away, one still moving when time ran out) starts
  awake.  After stepping, every object is as it was created: awake, never put
  to sleep by Bullet.

What is left is mostly the contact solver on a stack a cube lands on: the
whole stack is one island while the cube settles (docs/benchmarks.md).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from .world import pb

CHECK_STEPS = 3
"""Physics steps between two looks at whether the free objects are at rest (1/80 s)."""
REST_SPEED = 0.01
"""m/s: slower than this, an object is not going anywhere."""
REST_SPIN = 0.1
"""rad/s: turning slower than this, an object is not toppling."""
CALM_CHECKS = 2
"""Checks in a row an object must be at rest before it sleeps: a body at the top of
a bounce is slow for an instant, never for two checks 1/80 s apart (gravity alone
changes its speed by 0.12 m/s in that time)."""
NEAR = 0.02
"""m: an object whose box comes this close to where a moved object was may have
rested on it or against it."""


_SLEEP = pb.ACTIVATION_STATE_ENABLE_SLEEPING | pb.ACTIVATION_STATE_SLEEP
_WAKE = pb.ACTIVATION_STATE_ENABLE_SLEEPING | pb.ACTIVATION_STATE_WAKE_UP
_AWAKE = pb.ACTIVATION_STATE_DISABLE_SLEEPING
"""As bodies are created: awake, and never put to sleep by Bullet."""


class Settling:
    """A world's physics after let-gos, remembering what each one left at rest.

    An object left at rest, and still where it was, starts the next settling asleep,
    unless an object it may have rested against has moved since (picked, carried,
    let go: its old box is the place to look): so only what a let-go can have
    disturbed is stepped from the start, and Bullet wakes the rest on contact.
    """

    def __init__(self, world: Any):
        self.world = world
        self.resting: dict[str, tuple[Any, tuple[Any, Any]]] = {}
        """Objects the last settling left at rest: their pose and bounding box."""

    def settle(self, free: Sequence[str], still: Iterable[str], seconds: float) -> int:
        """Step the physics until the ``free`` objects are all at rest, at most
        ``seconds``, with the ``still`` bodies (robots, held objects) as fixed
        obstacles; return the number of steps."""
        world = self.world
        bodies = {name: world.body(name) for name in free}
        limit = max(0, round(seconds / world.timestep))
        disturbed = self._disturbed(free)
        calm = {name: 0 if name in disturbed else CALM_CHECKS for name in free}
        steps = 0
        with held_still(world, still):
            for name, body in bodies.items():
                world.call(pb.changeDynamics, body, -1,
                           activationState=_WAKE if name in disturbed else _SLEEP)
            try:
                while steps < limit and not all(n >= CALM_CHECKS for n in calm.values()):
                    steps += world.step(min(CHECK_STEPS, limit - steps) * world.timestep)
                    for name, body in bodies.items():
                        if not _at_rest(world, body):
                            calm[name] = 0
                            continue
                        calm[name] += 1
                        if calm[name] == CALM_CHECKS:  # at rest: still, and asleep
                            world.call(pb.resetBaseVelocity, body, (0, 0, 0), (0, 0, 0))
                            world.call(pb.changeDynamics, body, -1, activationState=_SLEEP)
            finally:
                for body in bodies.values():
                    world.call(pb.changeDynamics, body, -1, activationState=_AWAKE)
        self.resting = {name: (self._pose(name), world.aabb(name))
                        for name in free if calm[name] >= CALM_CHECKS}
        return steps

    def _pose(self, name: str) -> Any:
        return self.world.call(pb.getBasePositionAndOrientation, self.world.body(name))

    def _disturbed(self, free: Sequence[str]) -> set[str]:
        """The free objects to step from the start: those not left at rest where they
        are now, and those whose box comes near where a moved object was."""
        moved = {name for name in free
                 if name not in self.resting or self._pose(name) != self.resting[name][0]}
        vacated = [box for name, (_, box) in self.resting.items()
                   if name in moved or name not in free]
        return moved | {name for name in free if name not in moved
                        and any(_near(self.world.aabb(name), box) for box in vacated)}


def _near(a: tuple[Any, Any], b: tuple[Any, Any], margin: float = NEAR) -> bool:
    (a0, a1), (b0, b1) = a, b
    return all(a0[i] <= b1[i] + margin and b0[i] <= a1[i] + margin for i in range(3))


def _at_rest(world: Any, body: int) -> bool:
    linear, angular = world.call(pb.getBaseVelocity, body)
    return math.hypot(*linear) < REST_SPEED and math.hypot(*angular) < REST_SPIN


@contextmanager
def held_still(world: Any, names: Iterable[str]) -> Iterator[None]:
    """The named bodies (robots, held objects) as static obstacles for the duration:
    every link of mass 0, a robot's joint motors off (holding nothing, they would still
    be most of a step's cost), and asleep, so that Bullet does not even run their
    motionless dynamics until something touches them.  After, the masses and inertias
    are put back exactly and a robot's motors hold its joints where they are, as
    :meth:`~sim.world.LivingRoom.set_joints` leaves them."""
    names = list(names)
    saved: list[tuple[int, int, float, Any]] = []
    try:
        for name in names:
            body = world.body(name)
            for link in range(-1, world.call(pb.getNumJoints, body)):
                mass, _, inertia = world.call(pb.getDynamicsInfo, body, link)[:3]
                if mass > 0:
                    saved.append((body, link, mass, inertia))
                    world.call(pb.changeDynamics, body, link, mass=0.0)
            if name in world.robots:
                movable = list(world.robots[name].movable)
                world.call(pb.setJointMotorControlArray, body, movable, pb.VELOCITY_CONTROL,
                           forces=[0.0] * len(movable))
            world.call(pb.changeDynamics, body, -1, activationState=_SLEEP)
        yield
    finally:
        for body, link, mass, inertia in saved:
            world.call(pb.changeDynamics, body, link, mass=mass, localInertiaDiagonal=inertia)
        for name in names:
            if name in world.robots:
                world.set_joints(name, world.joint_positions(name))
            world.call(pb.changeDynamics, world.body(name), -1, activationState=_AWAKE)
