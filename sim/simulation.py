"""The simulation's clockwork: activities ticked on the supervisor's clock, carried objects.

A :class:`Simulation` shares the supervisor's :class:`~shary.kernel.loop.EventLoop`
(one clock, one thread, deterministic).  While some activity runs, a tick is
scheduled every :data:`TICK` simulated seconds: each activity advances, what
people and robots hold follows their hands, and the observers (perception)
look at the world.  When nothing moves, no tick is scheduled at all and the
loop jumps straight to its next timer (a person's delayed answer, a scheme's
timeout), which is most of why a run goes far faster than real time.

Contact is simulated only where it decides the outcome: :meth:`settle` steps
PyBullet's physics after an object is let go, so it stands on a table, topples
or falls into the bin as physics says (until everything that moves is at rest:
:mod:`sim.settling`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import Any

import networkx as nx

from .avatar import Avatar
from .humans import HUMAN_PLACES, TORSO_RADIUS, WAYPOINTS
from .motion import Activity, wrap
from .settling import Settling
from .world import BOTTLE_HEIGHT, LivingRoom, pb

TICK = 0.1
"""Simulated seconds between two ticks while something moves."""
SETTLE_SECONDS = 0.8
"""Physics time given at most to an object let go (stepping ends once all is at rest)."""
PERSON_CLEARANCE = TORSO_RADIUS + 0.08


class Simulation:
    """The world, its activities and its carried objects, on the supervisor's loop."""

    def __init__(self, world: LivingRoom, loop: Any, robot: str):
        self.world = world
        self.loop = loop
        self.robot = robot
        self.people: dict[str, Avatar] = {}
        self.holder: dict[str, str] = {}  # object -> the agent holding it
        self.observers: list[Callable[[], Any]] = []
        self.tick_hooks: list[Callable[[], Any]] = []
        self._activities: dict[int, tuple[Activity, Callable[[], Any] | None]] = {}
        self._ids = itertools.count(1)
        self._timer: Any = None
        self.physics_steps = 0
        self.physics = Settling(world)

    # -- activities ------------------------------------------------------------

    def start(self, activity: Activity, done: Callable[[], Any] | None = None) -> int:
        """Run an activity from the next tick on; ``done()`` when it is over."""
        handle = next(self._ids)
        self._activities[handle] = (activity, done)
        if self._timer is None:
            self._timer = self.loop.call_later(TICK, self._tick)
        return handle

    def stop(self, handle: int) -> bool:
        """Stop an activity where it is (its ``done`` is not called)."""
        return self._activities.pop(handle, None) is not None

    @property
    def busy(self) -> bool:
        return bool(self._activities)

    def _tick(self) -> None:
        self._timer = None
        for handle, (activity, done) in list(self._activities.items()):
            if handle not in self._activities:
                continue  # stopped by an earlier activity's completion this tick
            if activity.advance(TICK):
                del self._activities[handle]
                if done is not None:
                    self.loop.call_soon(done)
        for hook in self.tick_hooks:
            hook()
        self.carry()
        self.observe()
        if self._activities and self._timer is None:
            self._timer = self.loop.call_later(TICK, self._tick)

    def observe(self) -> None:
        """Let the observers (perception) look at the world now."""
        for observer in self.observers:
            observer()

    # -- holding -----------------------------------------------------------------

    def hand_of(self, agent: str) -> tuple[float, float, float]:
        if agent in self.people:
            return self.people[agent].hand_position()
        return self.world.gripper(agent)

    def carry(self) -> None:
        """Held objects follow their holder's hand, upright."""
        for obj, agent in self.holder.items():
            x, y, z = self.hand_of(agent)
            self.world.call(pb.resetBasePositionAndOrientation, self.world.body(obj),
                            [x, y, z], [0, 0, 0, 1])

    def attach(self, obj: str, agent: str) -> None:
        self.holder[obj] = agent
        self.carry()

    def release(self, obj: str) -> None:
        self.holder.pop(obj, None)

    def settle(self, obj: str, at: tuple[float, float, float] | None = None) -> None:
        """Let an object go (optionally from ``at``) and step physics until it has settled,
        robots and the objects still held standing still."""
        holder = self.holder.get(obj)
        if at is None and holder is not None:
            # from the hand as it is now: a motion that ended this tick moved it after the
            # last carry, and the object would drop from where the hand was a tick ago
            at = self.hand_of(holder)
        self.release(obj)
        body = self.world.body(obj)
        if at is not None:
            self.world.call(pb.resetBasePositionAndOrientation, body, list(at), [0, 0, 0, 1])
        self.world.call(pb.resetBaseVelocity, body, [0, 0, 0], [0, 0, 0])
        # the gripper still closes round the object: without this, the overlap would
        # shoot the object away on the first physics step
        pairs = []
        if holder in self.world.robots:
            robot = self.world.robots[holder]
            pairs = [(robot.body, link) for link in range(-1, len(robot.links))]
        for other, link in pairs:
            self.world.call(pb.setCollisionFilterPair, other, body, link, -1, 0)
        free = [name for name in self.world.movables if name not in self.holder]
        self.physics_steps += self.physics.settle(free, [*self.world.robots, *self.holder],
                                                  SETTLE_SECONDS)
        for other, link in pairs:
            self.world.call(pb.setCollisionFilterPair, other, body, link, -1, 1)

    def held_by(self, agent: str) -> str | None:
        return next((o for o, a in self.holder.items() if a == agent), None)

    # -- people ------------------------------------------------------------------

    def add_person(self, name: str, at: str, shirt: tuple[float, float, float, float]) -> Avatar:
        x, y, yaw, seated = HUMAN_PLACES[at]
        avatar = Avatar(self.world, name, x, y, yaw, shirt)
        avatar.seated = seated
        avatar.place()
        self.people[name] = avatar
        return avatar

    def person_path(self, name: str, goal: tuple[float, float],
                    goal_yaw: float | None = None) -> list[tuple[float, float]]:
        """Waypoints from where a person stands to ``goal``, round the furniture.

        A person sitting on the sofa (or standing right against furniture)
        first steps forward into the clear, and reaches a seat from the front.
        """
        avatar = self.people[name]
        start = (avatar.x, avatar.y)
        first = self._clear_point(start, avatar.yaw)
        last = self._clear_point(goal, goal_yaw if goal_yaw is not None else 0.0)
        points = [first, last, *WAYPOINTS, *((x, y) for x, y, _, _ in HUMAN_PLACES.values())]
        points = [p for p in points if self._clear_spot(p)]
        graph = nx.Graph()
        graph.add_nodes_from([first, last])
        for i, a in enumerate(points):
            for b in points[i + 1:]:
                if a != b and self._clear_for_person(a, b):
                    graph.add_edge(a, b, weight=math.dist(a, b))
        try:
            path = nx.shortest_path(graph, first, last, weight="weight")
        except (nx.NetworkXNoPath, nx.NodeNotFound):
            raise LookupError(f"{name} finds no way from ({start[0]:.2f}, {start[1]:.2f}) "
                              f"to ({goal[0]:.2f}, {goal[1]:.2f})") from None
        path = [p for p in path if p != start]
        if not path or path[-1] != goal:
            path.append(goal)
        return path

    def _clear_spot(self, p: tuple[float, float]) -> bool:
        return self.world.segment_clear(p, p, clearance=PERSON_CLEARANCE)

    def _clear_point(self, p: tuple[float, float], yaw: float) -> tuple[float, float]:
        """``p`` if a person fits there, else the first point in front of it that fits."""
        for i in range(21):
            q = (p[0] + 0.05 * i * math.cos(yaw), p[1] + 0.05 * i * math.sin(yaw))
            if self._clear_spot(q):
                return q
        return p

    def _clear_for_person(self, a: tuple[float, float], b: tuple[float, float]) -> bool:
        if not self.world.segment_clear(a, b, clearance=PERSON_CLEARANCE, step=0.05):
            return False
        rx, ry, _ = self.world.base_pose(self.robot)
        return _segment_distance((rx, ry), a, b) > 0.5

    def meeting_point(self, name: str) -> tuple[float, float]:
        """Where a person stands to hand the robot something: in front, on its arm's side."""
        x, y, yaw = self.world.base_pose(self.robot)
        forward = (math.cos(yaw), math.sin(yaw))
        right = (math.sin(yaw), -math.cos(yaw))
        for side in (1.0, -1.0):  # the arm is on the robot's right
            px = x + 0.35 * forward[0] + side * 0.8 * right[0]
            py = y + 0.35 * forward[1] + side * 0.8 * right[1]
            if self.world.segment_clear((px, py), (px, py), clearance=PERSON_CLEARANCE):
                return px, py
        raise LookupError(f"{name} finds no room beside {self.robot}")


class Walk(Activity):
    """A person walking through waypoints, turning as they go."""

    label = "walk"

    def __init__(self, avatar: Avatar, waypoints: list[tuple[float, float]], speed: float,
                 final_yaw: float | None = None, seated: bool = False):
        self.avatar = avatar
        self.waypoints = list(waypoints)
        self.speed = speed
        self.final_yaw = final_yaw
        self.seated = seated
        avatar.seated = False

    def advance(self, dt: float) -> bool:
        a = self.avatar
        while self.waypoints and dt > 1e-9:
            tx, ty = self.waypoints[0]
            distance = math.hypot(tx - a.x, ty - a.y)
            if distance > 1e-6:
                a.yaw = math.atan2(ty - a.y, tx - a.x)
            step = min(distance, self.speed * dt)
            if distance > 1e-6:
                a.x += (tx - a.x) * step / distance
                a.y += (ty - a.y) * step / distance
            dt -= step / self.speed
            if step >= distance:
                self.waypoints.pop(0)
        if not self.waypoints:
            if self.final_yaw is not None:
                a.yaw = wrap(self.final_yaw)
            a.seated = self.seated
        a.place()
        return not self.waypoints


def _segment_distance(p: tuple[float, float], a: tuple[float, float],
                      b: tuple[float, float]) -> float:
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy)
                                             / length2))
    return math.hypot(p[0] - (ax + t * dx), p[1] - (ay + t * dy))


def standing_height(obj_top: float, height: float = BOTTLE_HEIGHT) -> float:
    """Height of the centre of an object ``height`` tall (a bottle by default) standing
    on a surface at ``obj_top``."""
    return obj_top + height / 2 + 1e-3
