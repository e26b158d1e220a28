"""A person's bodies in the world: a kinematic avatar.

An :class:`Avatar` is three bodies moved kinematically: a torso (a cylinder
that robots and perception can bump into), a head whose direction is the
person's attention, and a hand that reaches out, takes and holds objects.
People do not need dynamics for what the scenarios ask of them — where they
stand, where they look, what they hold — and skipping it keeps runs fast.
"""

from __future__ import annotations

import math

from .humans import TORSO_RADIUS
from .world import LivingRoom, pb

STANDING_EYES = 1.62
SEATED_DROP = 0.45
SKIN = (0.87, 0.7, 0.58, 1.0)


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
