"""Executors: the robot's atomic tasks performed in the PyBullet world.

:class:`RobotExecutors` fills shary's executor port (``start(request,
reporter)``, ``cancel(request)``) for every atomic task of the core recipe
library: ``navigate`` (along the roadmap of places, which keeps the base clear
of furniture), ``move-arm`` (iterated inverse kinematics, then a joint-space
motion), ``pick`` (fails with the reason when the object is out of reach),
``place``, ``put-back``, ``dump`` (physics decides whether it fell in),
``give`` (hold the object out to a person's hand, wait for the take,
release), ``look-at`` (the pan-tilt head) and ``speak`` (to the terminal and
the log).  Each reports exactly one outcome — done, failed with a reason, or
cancelled — and stops at once when cancelled, leaving the arm where it was,
so that a resumed act continues from there.

People are not commanded: a request for an action by a person fails, saying
so; the robot involves people through joint tasks (ask-help), and their
simulated behaviour lives in :mod:`sim.people`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import networkx as nx

from .kinematics import reach, set_gripper
from .motion import (
    HEAD_SPEED,
    JOINT_SPEED,
    Activity,
    BaseMotion,
    Instant,
    JointMotion,
    Lazy,
    Sequence,
    Wait,
)
from .narration import action_text
from .simulation import Simulation, standing_height
from .world import FURNITURE, MANIPULATION_PLACES

NEAR_PEOPLE_SPEED = 0.5
"""Joint speed (rad/s) when the arm moves towards a person: slower, as near people it must."""
TAKE_WITHIN = 20.0
"""How long the arm holds an object out to a person before the give fails ("alice did
not take the yellow bottle within 20 s"): people here take within seconds when they
attend; one who looked away already makes the give wait (WAIT-ATTENTION) and cancels
it.  Without a bound, a person who never takes would hold the robot for ever."""
REACH_TOLERANCE = 0.015
"""An IK answer further than this from the target means the target is out of reach."""
ROBOT_REACH = 0.95
"""Horizontal distance from the arm mount beyond which nothing is tried (Jido's arm
reaches table height up to about this far; IK decides below it)."""
LIFT = 0.12
WORDS_PER_SECOND = 2.6
PLACE_FURNITURE = {place: furniture for furniture, place in MANIPULATION_PLACES.items()}
"""What the robot looks at when it looks at a place."""


class ActionFailed(Exception):
    """An action cannot be done; the message is the reason reported."""


@dataclass
class _Running:
    request: Any
    reporter: Any
    handle: int = 0
    failure: list[str] = field(default_factory=list)
    on_cancel: list[Callable[[], Any]] = field(default_factory=list)

    def failed(self) -> bool:
        return bool(self.failure)


_NAME = re.compile(r"\b([a-z]+(?:-[a-z]+)+)\b")


def spoken(text: str) -> str:
    """Text as said aloud: the names of things lose their hyphens ("the yellow bottle").

    Names in the world are identifiers (``yellow-bottle``, ``coffee-table``);
    recipes put them into sentences, where a listener expects words.
    """
    return _NAME.sub(lambda m: m.group(1).replace("-", " "), text)


class _HeadTurn(Activity):
    """A head motion that ends as soon as a newer one has started (see ``_head_turn``)."""

    label = "look"

    def __init__(self, executors: RobotExecutors, turn: int, motion: Activity):
        self.executors = executors
        self.turn = turn
        self.motion = motion

    def advance(self, dt: float) -> bool:
        return self.turn != self.executors._head_turn or self.motion.advance(dt)


class RobotExecutors:
    """The robot's executors (see the module's docstring)."""

    def __init__(self, sim: Simulation, say: Callable[..., Any],
                 learned: Callable[[str, str, Any], Any] | None = None,
                 progress: Callable[[str, str, str], Any] | None = None):
        self.sim = sim
        self.world = sim.world
        self.robot = sim.robot
        self.say = say
        self.learned = learned or (lambda s, p, o: None)
        self.progress = progress or (lambda who, kind, text: None)
        self.people: dict[str, Any] = {}
        self.faults: dict[str, list[str]] = {}
        """Atomic task -> reasons of the next injected failures (a scenario's faults)."""
        self.picked_from: dict[str, tuple[tuple[float, float, float], str | None, str]] = {}
        """Object -> where it was picked: its position, its furniture, the robot's place."""
        self._running: dict[str, _Running] = {}
        self.speaking = False
        self._head_turn = 0
        """The latest head motion's number: an older one still under way gives way
        (a place turns the head to its spot while a look-at may be turning it too;
        two motions of the same joints would fight and neither would end)."""

    # -- the executor port ---------------------------------------------------------

    def start(self, request: Any, reporter: Any) -> None:
        if request.agent != self.robot:
            reporter.failed(request, f"{request.agent} is a person: the robot does not command "
                            f"people; it asks them in a joint task (ask-help)")
            return
        if request.atomic != "speak":
            self.progress(self.robot, "action", action_text(request.atomic, request.args))
        running = _Running(request, reporter)
        if self.faults.get(request.atomic):
            reason = self.faults[request.atomic].pop(0)
            self.progress(self.robot, "failed", f"{request.atomic} failed: {reason}")
            reporter.failed(request, reason)
            return
        method = getattr(self, "_" + request.atomic.replace("-", "_"), None)
        if method is None:
            reporter.failed(request, f"the simulated {self.robot} cannot {request.atomic}")
            return
        try:
            activity = method(running, **request.args)
        except ActionFailed as err:
            self.progress(self.robot, "failed", f"{request.atomic} failed: {err}")
            reporter.failed(request, str(err))
            return
        self._running[request.id] = running
        running.handle = self.sim.start(activity, lambda: self._finished(running))
        for person in self.people.values():
            person.robot_started(request.atomic, request.args)

    def cancel(self, request: Any) -> None:
        running = self._running.pop(request.id, None)
        if running is None:
            return
        self.sim.stop(running.handle)
        if request.atomic == "speak":
            self.speaking = False
        for undo in running.on_cancel:
            undo()
        running.reporter.cancelled(request, "cancelled; stopped where it was")

    def _finished(self, running: _Running) -> None:
        if self._running.pop(running.request.id, None) is None:
            return
        if running.failure:
            self.progress(self.robot, "failed",
                          f"{running.request.atomic} failed: {running.failure[0]}")
            running.reporter.failed(running.request, running.failure[0])
        else:
            running.reporter.done(running.request)

    # -- geometry -------------------------------------------------------------------

    def _mount(self) -> tuple[float, float, float]:
        return self.world.shoulder(self.robot)

    def _arm_to(self, running: _Running, point: Callable[[], tuple[float, float, float]],
                what: str, speed: float = JOINT_SPEED) -> Activity:
        """Move the arm so the gripper reaches ``point()`` (computed when the motion starts)."""
        def build() -> Activity:
            target = point()
            q, error = reach(self.world, self.robot, target)
            if error > REACH_TOLERANCE:
                running.failure.append(f"{what} is out of reach: the gripper gets within "
                                       f"{error * 100:.0f} cm of it")
                return Instant(lambda: None)
            arm = self.world.robot(self.robot).arm()
            return JointMotion(self.world, self.robot, dict(zip(arm.joints, q, strict=True)),
                               speed)

        return Lazy(build, f"arm to {what}")

    def _home(self) -> Activity:
        r = self.world.robot(self.robot)
        arm = r.arm()
        return JointMotion(self.world, self.robot, {j: r.home.get(j, 0.0) for j in arm.joints})

    def _gripper(self, opening: float) -> Activity:
        return Instant(lambda: set_gripper(self.world, self.robot, opening), "gripper")

    def _point_of(self, target: str) -> tuple[float, float, float]:
        if target in self.sim.people:
            return self.sim.people[target].eyes
        if target in PLACE_FURNITURE:
            target = PLACE_FURNITURE[target]
        if target in FURNITURE:
            f = self.world.footprints[target]
            return (f.x, f.y, self.world.top(target))
        if target in self.world.places:
            x, y, _ = self.world.places[target]
            return (x, y, 0.5)
        try:
            return self.world.position(target)
        except KeyError:
            raise ActionFailed(f"{target!r} is nothing {self.robot} can see") from None

    def _handover_point(self, person: str) -> tuple[float, float, float]:
        mx, my, _ = self._mount()
        hx, hy, _ = self.sim.people[person].hand_position()
        d = math.hypot(hx - mx, hy - my)
        reach_out = max(0.3, min(0.6, d - 0.35))
        return (mx + (hx - mx) * reach_out / d, my + (hy - my) * reach_out / d, 0.85)

    def _check_reach(self, obj: str) -> tuple[float, float, float]:
        x, y, z = self.world.position(obj)
        mx, my, _ = self._mount()
        distance = math.hypot(x - mx, y - my)
        if distance > ROBOT_REACH:
            raise ActionFailed(f"{obj} is out of reach ({distance:.2f} m from the arm, "
                               f"reach {ROBOT_REACH:.2f} m)")
        return x, y, z

    # -- the atomic tasks -------------------------------------------------------------

    def _speak(self, running: _Running, text: str) -> Activity:
        text = spoken(str(text))
        seconds = 0.4 + len(text.split()) / WORDS_PER_SECOND
        self.say(self.robot, text, running.request.id)
        self.speaking = True

        def heard() -> None:
            self.speaking = False
            for person in self.people.values():
                person.heard()

        return Sequence([Wait(seconds, label="speak"), Instant(heard, "heard")], "speak")

    def _look_at(self, running: _Running, target: str) -> Activity:
        return self._head_to(self._point_of(target))

    def _head_to(self, point: tuple[float, float, float]) -> Activity:
        """Turn the pan-tilt head so the camera looks at ``point``."""
        def build() -> Activity:
            tx, ty, tz = point
            r = self.world.robot(self.robot)
            pan, tilt = r.joint("head_pan_joint"), r.joint("head_tilt_joint")
            hx, hy, hz = self.world.link_position(self.robot, "head_tilt_link")
            _, _, yaw = self.world.base_pose(self.robot)
            rel = math.atan2(ty - hy, tx - hx) - yaw
            rel = math.atan2(math.sin(rel), math.cos(rel))
            down = math.atan2(hz - tz, math.hypot(tx - hx, ty - hy))
            goal = {pan: min(max(rel, r.limits[pan][0]), r.limits[pan][1]),
                    tilt: min(max(down, r.limits[tilt][0]), r.limits[tilt][1])}
            self._head_turn += 1
            turn, motion = self._head_turn, JointMotion(self.world, self.robot, goal, HEAD_SPEED)
            return _HeadTurn(self, turn, motion)

        return Lazy(build, "look")

    def _navigate(self, running: _Running, place: str) -> Activity:
        if place not in self.world.places:
            raise ActionFailed(f"{place!r} is not a place of the roadmap "
                               f"({', '.join(self.world.places)})")
        x, y, _ = self.world.base_pose(self.robot)
        here, _ = self.world.nearest_place(x, y)
        graph = nx.Graph()
        for a, neighbours in self.world.roadmap.items():
            for b in neighbours:
                graph.add_edge(a, b, weight=math.dist(self.world.places[a][:2],
                                                      self.world.places[b][:2]))
        try:
            path = nx.shortest_path(graph, here, place, weight="weight")
        except (nx.NetworkXNoPath, nx.NodeNotFound):
            raise ActionFailed(f"no way on the roadmap from {here} to {place}") from None
        waypoints = [self.world.places[p][:2] for p in path]
        return BaseMotion(self.world, self.robot, waypoints, self.world.places[place][2])

    def _move_arm(self, running: _Running, target: str) -> Activity:
        if target in self.sim.people:
            return self._arm_to(running, lambda: self._handover_point(target),
                                f"the hand-over point towards {target}", NEAR_PEOPLE_SPEED)
        point = self._point_of(target)
        return self._arm_to(running, lambda: (point[0], point[1], point[2] + LIFT), target)

    def _pick(self, running: _Running, object: str) -> Activity:
        held = self.sim.held_by(self.robot)
        if held is not None:
            raise ActionFailed(f"{self.robot} already holds {held}")
        if object in self.sim.holder:
            raise ActionFailed(f"{self.sim.holder[object]} holds {object}")
        if object not in self.world.sizes:
            raise ActionFailed(f"{object!r} is not an object that can be picked up")
        width = self.world.sizes[object][1]
        opening = self._gripper_opening()
        if width > opening:
            raise ActionFailed(f"{object} is too big to grasp: {width * 100:.0f} cm wide, "
                               f"the gripper opens to {opening * 100:.0f} cm")
        try:
            x, y, z = self._check_reach(object)
            _, error = reach(self.world, self.robot, (x, y, z))
            if error > REACH_TOLERANCE:
                raise ActionFailed(f"{object} is out of reach: the gripper gets within "
                                   f"{error * 100:.0f} cm of it")
        except ActionFailed:
            self.learned(object, "robot_reach", False)
            raise

        def grasp() -> None:
            furniture = next((f for f in FURNITURE
                              if self.world.footprints[f].contains(x, y)), None)
            place, _ = self.world.nearest_place(*self.world.base_pose(self.robot)[:2])
            self.picked_from[object] = ((x, y, z), furniture, place)
            set_gripper(self.world, self.robot, width / 2)  # the fingers close on its sides
            self.sim.attach(object, self.robot)

        return Sequence([self._gripper(0.04),
                         self._arm_to(running, lambda: (x, y, z + LIFT), f"above {object}"),
                         self._arm_to(running, lambda: (x, y, z), object),
                         Instant(grasp, "grasp"),
                         self._arm_to(running, lambda: (x, y, z + LIFT), f"above {object}")],
                        f"pick {object}", running.failed)

    def _gripper_opening(self) -> float:
        """How wide the robot's gripper opens (metres, between the fingers)."""
        r = self.world.robot(self.robot)
        return 2 * min(r.limits[j][1] for j in r.arm().fingers)

    def _free_spot(self, obj: str, furniture: str, near: tuple[float, float] | None = None
                   ) -> tuple[float, float, float]:
        f = self.world.footprints[furniture]
        mx, my, _ = self._mount()
        height, width = self.world.sizes[obj]
        z = standing_height(self.world.top(furniture), height)
        others = [(*self.world.position(b)[:2], self.world.sizes[b][1])
                  for b in self.world.movables if b not in self.sim.holder]
        candidates = []
        steps = 9
        for i in range(steps):
            for j in range(steps):
                lx = -f.half_x + 0.08 + (2 * f.half_x - 0.16) * i / (steps - 1)
                ly = -f.half_y + 0.08 + (2 * f.half_y - 0.16) * j / (steps - 1)
                c, s = math.cos(f.yaw), math.sin(f.yaw)
                x, y = f.x + c * lx - s * ly, f.y + s * lx + c * ly
                if math.hypot(x - mx, y - my) > ROBOT_REACH - 0.1:
                    continue
                if any(math.hypot(x - o[0], y - o[1]) < width + o[2] for o in others):
                    continue
                key = math.dist((x, y), near) if near else math.hypot(x - mx, y - my)
                candidates.append((key, x, y))
        for _, x, y in sorted(candidates)[:6]:
            if reach(self.world, self.robot, (x, y, z))[1] <= REACH_TOLERANCE:
                return x, y, z
        raise ActionFailed(f"no free spot on the {furniture} within reach")

    def _put_down(self, running: _Running, obj: str, spot: tuple[float, float, float],
                  furniture: str) -> Activity:
        x, y, z = spot

        def let_go() -> None:
            set_gripper(self.world, self.robot, 0.04)
            self.sim.settle(obj)
            self.sim.observe()

        return Sequence([self._head_to(spot),
                         self._arm_to(running, lambda: (x, y, z + LIFT), f"above the {furniture}"),
                         self._arm_to(running, lambda: (x, y, z), f"the spot on the {furniture}"),
                         Instant(let_go, "release"),
                         self._arm_to(running, lambda: (x, y, z + LIFT), f"above the {furniture}"),
                         self._home()], f"put {obj} on {furniture}", running.failed)

    def _holding(self, obj: str) -> None:
        if self.sim.held_by(self.robot) != obj:
            raise ActionFailed(f"{self.robot} does not hold {obj}")

    def _place(self, running: _Running, object: str, on: str) -> Activity:
        self._holding(object)
        if on not in FURNITURE:
            raise ActionFailed(f"{on!r} is not a piece of furniture")
        return self._put_down(running, object, self._free_spot(object, on), on)

    def _put_back(self, running: _Running, object: str) -> Activity:
        self._holding(object)
        origin = self.picked_from.get(object)
        if origin is None or origin[1] is None:
            raise ActionFailed(f"{self.robot} does not know where {object} came from")
        (x, y, _), furniture, place = origin

        def put_down() -> Activity:
            try:
                spot = self._free_spot(object, furniture, (x, y))
            except ActionFailed as err:
                running.failure.append(str(err))
                return Instant(lambda: None)
            return self._put_down(running, object, spot, furniture)

        return Sequence([self._navigate(running, place), Lazy(put_down, "put down")],
                        f"put {object} back", running.failed)

    def _dump(self, running: _Running, object: str, into: str) -> Activity:
        self._holding(object)
        if into not in FURNITURE:
            raise ActionFailed(f"{into!r} is not a piece of furniture")
        f = self.world.footprints[into]
        above = (f.x, f.y, self.world.top(into) + 0.22)

        def drop() -> None:
            set_gripper(self.world, self.robot, 0.04)
            self.sim.settle(object)
            self.sim.observe()
            x, y, z = self.world.position(object)
            if not (f.contains(x, y) and z < self.world.top(into)):
                running.failure.append(f"{object} missed the {into}: it lies at "
                                       f"({x:.2f}, {y:.2f}, {z:.2f})")

        return Sequence([self._head_to((f.x, f.y, self.world.top(into))),
                         self._arm_to(running, lambda: above, f"above the {into}"),
                         Instant(drop, "drop"), self._home()], f"dump {object}", running.failed)

    def _give(self, running: _Running, object: str, to: str) -> Activity:
        self._holding(object)
        person = self.people.get(to)
        if person is None:
            raise ActionFailed(f"{to!r} is not a person here")
        taken: list[bool] = []

        def offer() -> None:
            person.offered(object, self.robot, lambda: taken.append(True))

        def release() -> None:
            set_gripper(self.world, self.robot, 0.04)

        def not_taken() -> None:
            if not taken and not running.failure:
                person.withdraw()
                running.failure.append(f"{to} did not take the {object} within "
                                       f"{TAKE_WITHIN:g} s")

        running.on_cancel.append(person.withdraw)
        return Sequence([self._arm_to(running, lambda: self._handover_point(to),
                                      f"the hand-over point towards {to}", NEAR_PEOPLE_SPEED),
                         Instant(offer, "hold out"),
                         Wait(TAKE_WITHIN, until=lambda: bool(taken) or bool(running.failure),
                              label="wait for the take"),
                         Instant(not_taken, "taken?"),
                         Instant(release, "release"),
                         # given once taken: the arm's way back is not part of the give
                         # (a person who looks away now does not undo it)
                         Instant(lambda: self._finished(running), "given"),
                         self._home()], f"give {object}", running.failed)

    def take_from(self, person: str, obj: str, done: Callable[[], Any]) -> bool:
        """A person holds ``obj`` out: reach their hand and grasp (the receiving side).

        Not a request of the supervisor's (the person acts; the robot's ask-help act
        only watches for the object in its hand), so nothing can cancel it: it is a
        second or two of arm motion.  False when the robot's gripper is not free.
        """
        if self.sim.held_by(self.robot) is not None or self.sim.holder.get(obj) != person:
            return False

        def grasp() -> None:
            if failure:  # the hand was out of reach: nothing changes hands
                self.say(self.robot, f"(cannot reach {person}'s hand)")
                return
            set_gripper(self.world, self.robot, self.world.sizes[obj][1] / 2)
            self.sim.attach(obj, self.robot)
            self.sim.observe()
            done()

        hand = self.sim.people[person].hand_position()
        failure: list[str] = []
        holder = _Running(None, None, failure=failure)
        self.sim.start(Sequence([self._gripper(0.04), self._arm_to(holder, lambda: hand,
                                                                   f"{person}'s hand"),
                                 Instant(grasp, "take")], f"take {obj} from {person}"))
        return True
