"""Motion over simulated time, without physics: activities advanced tick by tick.

Stepping PyBullet at 240 Hz with an arm on a mobile base runs at about 16
times real time; the scenarios need more than 50.  Nothing in them needs
dynamics while a base drives or an arm swings: those are *kinematic*
activities here — each tick puts the joints and bases where the motion says
they are at that time (a base at a bounded speed along roadmap segments, an
arm interpolated in joint space at a bounded joint speed).  Physics steps run
only where contact decides the outcome: an object let go settles on a table
or falls into the bin (:meth:`sim.simulation.Simulation.settle`).

An :class:`Activity` is advanced with the elapsed time and says when it is
over; :class:`Sequence` chains activities and instant actions, which is how
an executor's pick becomes "pre-grasp, grasp, close, lift".  Cancelling an
activity leaves the body where it is: a resumed motion starts from there.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from collections.abc import Sequence as Seq

import numpy as np

from .world import LivingRoom

BASE_SPEED = 0.6
"""Robot base speed, m/s."""
TURN_SPEED = 1.6
"""Robot base turn rate, rad/s."""
JOINT_SPEED = 1.2
"""Fastest arm joint, rad/s: a motion takes as long as its largest joint change needs."""
HEAD_SPEED = 2.5
"""Pan-tilt head, rad/s."""


class Activity:
    """Something that changes the world over time; :meth:`advance` returns True when over."""

    label = "activity"

    def advance(self, dt: float) -> bool:
        raise NotImplementedError


def wrap(angle: float) -> float:
    """An angle in (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))


class Instant(Activity):
    """Run a function once (close the gripper, attach the object)."""

    def __init__(self, action: Callable[[], object], label: str = "instant"):
        self.action = action
        self.label = label

    def advance(self, dt: float) -> bool:
        self.action()
        return True


class Wait(Activity):
    """Let time pass (a settling pause), or wait until ``until()`` is true."""

    def __init__(self, seconds: float = math.inf, until: Callable[[], bool] | None = None,
                 label: str = "wait"):
        self.left = seconds
        self.until = until
        self.label = label

    def advance(self, dt: float) -> bool:
        if self.until is not None and self.until():
            return True
        self.left -= dt
        return self.left <= 0


class Sequence(Activity):
    """Activities one after another; time left over by one goes to the next."""

    def __init__(self, parts: Seq[Activity], label: str = "sequence",
                 abort: Callable[[], bool] | None = None):
        self.parts = list(parts)
        self.label = label
        self.abort = abort

    def advance(self, dt: float) -> bool:
        while self.parts:
            if self.abort is not None and self.abort():
                return True  # a part failed: the rest is not attempted
            part = self.parts[0]
            if not part.advance(dt):
                return False
            self.parts.pop(0)
            dt = 0.0  # instants and finished parts take no more of this tick
        return True


class Lazy(Activity):
    """An activity built when it starts (an arm target known only after the base moved)."""

    def __init__(self, build: Callable[[], Activity], label: str = "lazy"):
        self.build = build
        self.inner: Activity | None = None
        self.label = label

    def advance(self, dt: float) -> bool:
        if self.inner is None:
            self.inner = self.build()
        return self.inner.advance(dt)


class BaseMotion(Activity):
    """A robot base along waypoints (x, y), then turning to a final heading."""

    label = "drive"

    def __init__(self, world: LivingRoom, robot: str, waypoints: Seq[tuple[float, float]],
                 final_yaw: float, on_move: Callable[[], object] | None = None):
        self.world = world
        self.robot = robot
        self.waypoints = list(waypoints)
        self.final_yaw = final_yaw
        self.on_move = on_move

    def advance(self, dt: float) -> bool:
        x, y, yaw = self.world.base_pose(self.robot)
        while dt > 1e-9:
            if self.waypoints:
                tx, ty = self.waypoints[0]
                distance = math.hypot(tx - x, ty - y)
                if distance < 1e-4:
                    self.waypoints.pop(0)
                    continue
                heading = math.atan2(ty - y, tx - x)
            else:
                heading, distance = self.final_yaw, 0.0
            turn = wrap(heading - yaw)
            if abs(turn) > 1e-3:
                step = min(abs(turn), TURN_SPEED * dt)
                yaw = wrap(yaw + math.copysign(step, turn))
                dt -= step / TURN_SPEED
                continue
            if not self.waypoints:
                yaw = heading
                break
            step = min(distance, BASE_SPEED * dt)
            x += step * math.cos(heading)
            y += step * math.sin(heading)
            dt -= step / BASE_SPEED
        self.world.set_base_pose(self.robot, x, y, yaw)
        if self.on_move is not None:
            self.on_move()
        return not self.waypoints and abs(wrap(self.final_yaw - yaw)) <= 1e-3


class JointMotion(Activity):
    """Joints from where they are to a goal, linearly, at a bounded speed."""

    label = "joints"

    def __init__(self, world: LivingRoom, robot: str, goal: dict[int, float],
                 speed: float = JOINT_SPEED):
        self.world = world
        self.robot = robot
        self.goal = goal
        self.speed = speed

    def advance(self, dt: float) -> bool:
        now = self.world.joint_positions(self.robot, self.goal)
        joints = list(self.goal)
        current = np.array([now[j] for j in joints])
        target = np.array([self.goal[j] for j in joints])
        delta = target - current
        largest = float(np.max(np.abs(delta))) if len(delta) else 0.0
        step = self.speed * dt
        done = largest <= step
        position = target if done else current + delta * (step / largest)
        self.world.set_joints(self.robot, dict(zip(joints, map(float, position), strict=True)))
        return done
