"""The living room of SHARY Fig. 8 in PyBullet, with a Jido-like robot.

:class:`LivingRoom` builds the scene the paper's scenarios run in: a coffee
table with four coloured bottles, a store table, a trash bin, a sofa, two
chairs and a cupboard, inside two walls.  Furniture is static (mass 0) and made
of boxes, so contacts are cheap and exact; bottles are light cylinders with
mass, so they can be picked, dropped and knocked over.

Robots are loaded from the hand-written URDF files in ``sim/models`` with a
*fixed* base that the world moves kinematically (:meth:`LivingRoom.set_base_pose`):
navigation in these scenarios is about where the robot is, not about wheel
slip, and not simulating wheels is what lets runs go much faster than real
time.

Design rules kept here:

- Every PyBullet call names this world's client id, so several worlds can live
  in one process (tests run them side by side; a planner may keep a scratch
  world to try motions in).
- PyBullet's C-level chatter is silenced around connecting and loading
  (:mod:`sim.quiet`), so standard output stays machine-readable.
- Poses handed in and out are those of the URDF/body *frames*.  PyBullet's
  base pose is the centre of mass; the conversion lives in one place
  (:meth:`LivingRoom.set_base_pose` / :meth:`LivingRoom.base_pose`).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from userfiles.outputs import write_output

from .objects import NewObject
from .png import caption_height, encode_png, with_caption
from .quiet import silenced
from .robots import MODELS, MODELS_DIR, Robot, describe
from .room import (  # noqa: F401 (the room's data, also named through sim.world)
    BOTTLE_HEIGHT,
    BOTTLE_MASS,
    BOTTLE_RADIUS,
    BOTTLES,
    CLEARANCE,
    CONTAINERS,
    FLOOR_RGBA,
    FOOTPRINTS,
    FURNITURE,
    MANIPULATION_PLACES,
    PLACES,
    ROOM,
    SEATS,
    WALL_HEIGHT,
    WALL_RGBA,
    WOOD_DARK,
    WOOD_LIGHT,
    Colour,
    Footprint,
    Part,
    Place,
    Vec3,
    footprint,
)

with silenced():  # the import prints a "pybullet build time" banner on stderr
    import pybullet as pb


@dataclass(frozen=True)
class Camera:
    """A fixed camera: eye, target, vertical field of view in degrees, up direction."""

    eye: Vec3
    target: Vec3
    fov: float = 60.0
    up: Vec3 = (0.0, 0.0, 1.0)


CAMERAS: dict[str, Camera] = {
    "overview": Camera((3.0, -4.2, 4.2), (-0.2, 0.4, 0.0), 52.0),
    "top": Camera((0.0, 0.05, 7.5), (0.0, 0.05, 0.0), 48.0, up=(0.0, 1.0, 0.0)),
}
LIGHT_DIRECTION = (1.0, -0.6, 2.0)


def framing(points: list[Vec3], aspect: float, fov: float = 50.0,
            looking_from: Camera = CAMERAS["overview"]) -> Camera:
    """A camera that frames ``points``: the robot first, then its partners.

    It looks across the line from the robot to the first partner, so that
    neither stands in front of the other, from the side nearer the direction
    of ``looking_from`` and as high above the floor (over the walls); it is
    pulled back until a sphere around all the points fits the narrower field
    of view.  The fixed overview shows the whole room, where a person on the
    sofa is a few pixels tall and may stand behind the robot.
    """
    pts = np.array(points, dtype=float)
    centre = pts.mean(axis=0)
    centre[2] = 0.7  # about the height of hands and tables
    radius = max(float(np.max(np.linalg.norm(pts - centre, axis=1))), 0.8) + 0.7
    half = math.radians(fov) / 2
    narrower = min(half, math.atan(math.tan(half) * aspect))
    usual = np.subtract(looking_from.eye, looking_from.target)
    flat = math.hypot(usual[0], usual[1])
    side = usual[:2] / flat
    if len(pts) > 1 and np.linalg.norm(pts[1, :2] - pts[0, :2]) > 1e-6:
        line = (pts[1, :2] - pts[0, :2]) / np.linalg.norm(pts[1, :2] - pts[0, :2])
        across = np.array([-line[1], line[0]])
        side = across if across @ side >= 0 else -across
    direction = np.array([side[0] * flat, side[1] * flat, usual[2]])
    direction /= np.linalg.norm(direction)
    eye = centre + direction * max(radius / math.sin(narrower), 2.5)
    return Camera(tuple(eye.tolist()), tuple(centre.tolist()), fov)


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


# --------------------------------------------------------------------- the world

class LivingRoom:
    """The SHARY living room in its own PyBullet client (DIRECT unless ``gui``).

    Bodies are known by name: the furniture (``coffee-table``, ``store-table``,
    ``trash``, ``sofa``, ``chair-1``, ``chair-2``, ``cupboard``), the bottles
    (``yellow-bottle`` …), the robots (``jido``), ``floor`` and the walls.
    ``places`` maps place names to robot base poses (x, y, yaw); ``roadmap``
    joins places whose straight segment keeps a robot base clear of furniture.

    Use it as a context manager, or call :meth:`close`, so the PyBullet client
    is released.
    """

    def __init__(self, gui: bool = False, robot: str | None = "jido",
                 timestep: float = 1.0 / 240.0, gravity: float = -9.81):
        self.gui = gui
        self.timestep = timestep
        self.time = 0.0
        self._bodies: dict[str, int] = {}
        self.sizes: dict[str, tuple[float, float]] = {}
        """Each movable object's (height, width to grasp) in metres."""
        self.added: dict[str, NewObject] = {}
        """The objects a scenario added (:mod:`sim.objects`), beside the bottles."""
        self.robots: dict[str, Robot] = {}
        self.footprints: dict[str, Footprint] = {}
        self.places: dict[str, Place] = dict(PLACES)
        if gui and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
            # PyBullet would call exit(1) from C, killing the process silently.
            raise RuntimeError("the PyBullet GUI needs an X display (DISPLAY is not set); "
                               "run headless, which is the default")
        with silenced(stderr=not gui):  # a GUI failure explains itself on stderr
            self.client = pb.connect(pb.GUI if gui else pb.DIRECT)
        if self.client < 0:
            raise RuntimeError("could not connect to PyBullet"
                               + (" (only one GUI window per process)" if gui else ""))
        self._connected = True
        try:
            self.call(pb.setGravity, 0, 0, gravity)
            self.call(pb.setTimeStep, timestep)
            if gui:
                self.call(pb.configureDebugVisualizer, pb.COV_ENABLE_GUI, 0)
                cam = CAMERAS["overview"]
                dx, dy, dz = (e - t for e, t in zip(cam.eye, cam.target, strict=True))
                self.call(pb.resetDebugVisualizerCamera, math.hypot(dx, dy, dz),
                          math.degrees(math.atan2(dy, dx)) + 90,
                          -math.degrees(math.atan2(dz, math.hypot(dx, dy))), cam.target)
            self._furnish()
            if robot is not None:
                self.add_robot(robot, robot, "base")
        except BaseException:
            self.close()
            raise

    # ----------------------------------------------------------------- plumbing

    def call(self, fn: Any, *args: Any, **kwargs: Any) -> Any:
        """Call a PyBullet function on this world's client."""
        return fn(*args, physicsClientId=self.client, **kwargs)

    def close(self) -> None:
        """Disconnect from PyBullet; safe to call twice."""
        if getattr(self, "_connected", False):
            self._connected = False
            pb.disconnect(physicsClientId=self.client)

    def __enter__(self) -> LivingRoom:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ----------------------------------------------------------------- building

    def _furnish(self) -> None:
        """Build the scene: the room, its furniture and bottles, the roadmap (another
        site, such as :class:`sim.weld.site.WeldSite`, builds its own here)."""
        self._build_room()
        for name, (x, y, yaw, parts) in FURNITURE.items():
            self._add_static(name, x, y, yaw, parts)
        for name, (x, y, rgba) in BOTTLES.items():
            self.add_bottle(name, x, y, self.top("coffee-table"), rgba)
        self.roadmap = self.build_roadmap()

    def _add_static(self, name: str, x: float, y: float, yaw: float,
                    parts: Sequence[Part]) -> int:
        """A static body from boxes; its footprint is the parts' bounding rectangle."""
        types = [pb.GEOM_BOX] * len(parts)
        halves = [list(p.half_extents) for p in parts]
        offsets = [list(p.offset) for p in parts]
        col = self.call(pb.createCollisionShapeArray, types, halfExtents=halves,
                        collisionFramePositions=offsets)
        vis = self.call(pb.createVisualShapeArray, types, halfExtents=halves,
                        visualFramePositions=offsets, rgbaColors=[list(p.rgba) for p in parts])
        body = self.call(pb.createMultiBody, baseMass=0, baseCollisionShapeIndex=col,
                         baseVisualShapeIndex=vis, basePosition=[x, y, 0],
                         baseOrientation=yaw_quaternion(yaw))
        self._bodies[name] = body
        self.footprints[name] = footprint(x, y, yaw, parts)
        return body

    def _build_room(self) -> None:
        x0, x1, y0, y1 = ROOM
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        floor = [Part(((x1 - x0) / 2, (y1 - y0) / 2, 0.05), (0, 0, -0.05), FLOOR_RGBA)]
        self._add_static("floor", cx, cy, 0.0, floor)
        del self.footprints["floor"]
        t, h = 0.05, WALL_HEIGHT / 2
        self._add_static("wall-north", cx, y1 + t, 0.0,
                         [Part(((x1 - x0) / 2 + 2 * t, t, h), (0, 0, h), WALL_RGBA)])
        self._add_static("wall-west", x0 - t, cy, 0.0,
                         [Part((t, (y1 - y0) / 2, h), (0, 0, h), WALL_RGBA)])

    def add_bottle(self, name: str, x: float, y: float, z_bottom: float,
                   rgba: Colour = (0.5, 0.5, 0.5, 1.0)) -> int:
        """A bottle (a cylinder with mass) standing at (x, y) on a surface at ``z_bottom``."""
        col = self.call(pb.createCollisionShape, pb.GEOM_CYLINDER, radius=BOTTLE_RADIUS,
                        height=BOTTLE_HEIGHT)
        vis = self.call(pb.createVisualShape, pb.GEOM_CYLINDER, radius=BOTTLE_RADIUS,
                        length=BOTTLE_HEIGHT, rgbaColor=list(rgba))
        body = self.call(pb.createMultiBody, baseMass=BOTTLE_MASS, baseCollisionShapeIndex=col,
                         baseVisualShapeIndex=vis,
                         basePosition=[x, y, z_bottom + BOTTLE_HEIGHT / 2 + 1e-4])
        self.call(pb.changeDynamics, body, -1, lateralFriction=0.8, rollingFriction=0.001,
                  spinningFriction=0.001)
        self._bodies[name] = body
        self.sizes[name] = (BOTTLE_HEIGHT, 2 * BOTTLE_RADIUS)
        return body

    def add_object(self, obj: NewObject, x: float, y: float, z_bottom: float) -> int:
        """A scenario's new object (a box, a cylinder or a sphere with mass) resting
        at (x, y) on a surface at ``z_bottom``."""
        rgba = [*obj.rgb, 1.0]
        if obj.shape == "box":
            half = [v / 2 for v in obj.size]
            col = self.call(pb.createCollisionShape, pb.GEOM_BOX, halfExtents=half)
            vis = self.call(pb.createVisualShape, pb.GEOM_BOX, halfExtents=half, rgbaColor=rgba)
        elif obj.shape == "cylinder":
            radius, height = obj.size[0] / 2, obj.size[1]
            col = self.call(pb.createCollisionShape, pb.GEOM_CYLINDER, radius=radius,
                            height=height)
            vis = self.call(pb.createVisualShape, pb.GEOM_CYLINDER, radius=radius,
                            length=height, rgbaColor=rgba)
        else:
            col = self.call(pb.createCollisionShape, pb.GEOM_SPHERE, radius=obj.size[0] / 2)
            vis = self.call(pb.createVisualShape, pb.GEOM_SPHERE, radius=obj.size[0] / 2,
                            rgbaColor=rgba)
        body = self.call(pb.createMultiBody, baseMass=obj.mass, baseCollisionShapeIndex=col,
                         baseVisualShapeIndex=vis,
                         basePosition=[x, y, z_bottom + obj.height / 2 + 1e-4])
        # a ball must not roll off the table: friction that stops rolling
        self.call(pb.changeDynamics, body, -1, lateralFriction=0.8,
                  rollingFriction=0.05 if obj.shape == "sphere" else 0.001,
                  spinningFriction=0.001)
        self._bodies[obj.name] = body
        self.sizes[obj.name] = (obj.height, obj.grasp_width)
        self.added[obj.name] = obj
        return body

    def add_robot(self, name: str, model: str | None = None,
                  at: str | Place = "base") -> Robot:
        """Load a robot model (``jido``, ``pr2like``) as ``name`` at a place, arms tucked."""
        model = name if model is None else model
        if name in self._bodies:
            raise ValueError(f"a body named {name!r} already exists")
        try:
            spec = MODELS[model]
        except KeyError:
            raise KeyError(f"unknown robot model {model!r} "
                           f"(models: {', '.join(MODELS)})") from None
        with silenced():
            body = self.call(pb.loadURDF, str(MODELS_DIR / spec.urdf), useFixedBase=True,
                             flags=pb.URDF_USE_INERTIA_FROM_FILE)
        self._bodies[name] = body
        robot = describe(name, model, body, self.client, spec.home)
        self.robots[name] = robot
        positions = {j: robot.home.get(j, 0.0) for j in robot.movable}
        self.set_joints(name, positions)
        x, y, yaw = self.places[at] if isinstance(at, str) else at
        self.set_base_pose(name, x, y, yaw)
        return robot

    def register(self, name: str, body: int) -> None:
        """Name a body built elsewhere (a person's torso), so queries find it."""
        if name in self._bodies:
            raise ValueError(f"a body named {name!r} already exists")
        self._bodies[name] = body

    # ----------------------------------------------------------------- queries

    @property
    def names(self) -> list[str]:
        """Every named body, in creation order."""
        return list(self._bodies)

    @property
    def bottles(self) -> list[str]:
        return [n for n in self._bodies if n.endswith("-bottle")]

    @property
    def movables(self) -> list[str]:
        """The objects that can be picked, carried and put down: bottles and added ones."""
        return [n for n in self._bodies if n in self.sizes]

    @property
    def furniture(self) -> list[str]:
        return list(FURNITURE)

    def body(self, name: str) -> int:
        """The PyBullet body id of a named body (valid on this world's client only)."""
        try:
            return self._bodies[name]
        except KeyError:
            raise KeyError(f"no body named {name!r} in this world") from None

    def robot(self, name: str) -> Robot:
        """What the world knows of a loaded robot: joints, links, arms, limits."""
        try:
            return self.robots[name]
        except KeyError:
            raise KeyError(f"no robot named {name!r} in this world") from None

    def pose(self, name: str) -> tuple[Vec3, tuple[float, float, float, float]]:
        """Position and orientation (quaternion) of a body's frame.

        For robots that is the URDF base frame (on the floor), not PyBullet's
        centre of mass; furniture frames are on the floor, bottle frames at
        their centre.
        """
        body = self.body(name)
        pos, orn = self.call(pb.getBasePositionAndOrientation, body)
        if name in self.robots:
            local_pos, local_orn = self.call(pb.getDynamicsInfo, body, -1)[3:5]
            inv_pos, inv_orn = pb.invertTransform(local_pos, local_orn)
            pos, orn = pb.multiplyTransforms(pos, orn, inv_pos, inv_orn)
        return tuple(pos), tuple(orn)

    def position(self, name: str) -> Vec3:
        """Position of a body's frame (see :meth:`pose`)."""
        return self.pose(name)[0]

    def aabb(self, name: str) -> tuple[Vec3, Vec3]:
        """Axis-aligned bounding box (min corner, max corner) of a whole body."""
        body = self.body(name)
        lo, hi = self.call(pb.getAABB, body, -1)
        for link in range(self.call(pb.getNumJoints, body)):
            a, b = self.call(pb.getAABB, body, link)
            lo = [min(u, v) for u, v in zip(lo, a, strict=True)]
            hi = [max(u, v) for u, v in zip(hi, b, strict=True)]
        return tuple(lo), tuple(hi)

    def top(self, name: str) -> float:
        """Height of the highest part of a piece of furniture (a table's surface)."""
        if name not in FURNITURE:
            raise KeyError(f"{name!r} is not furniture (furniture: {', '.join(FURNITURE)})")
        parts = FURNITURE[name][3]
        return max(p.offset[2] + p.half_extents[2] for p in parts)

    def link_pose(self, robot: str, link: str | int) -> tuple[Vec3, tuple[float, ...]]:
        """World pose of a robot link's URDF frame."""
        r = self.robot(robot)
        index = r.link(link) if isinstance(link, str) else link
        state = self.call(pb.getLinkState, r.body, index, computeForwardKinematics=True)
        return tuple(state[4]), tuple(state[5])

    def link_position(self, robot: str, link: str | int) -> Vec3:
        return self.link_pose(robot, link)[0]

    def shoulder(self, robot: str, arm: str | None = None) -> Vec3:
        """Where an arm starts (its first joint), whatever the model calls its links."""
        return self.link_position(robot, self.robot(robot).arm(arm).joints[0])

    def gripper(self, robot: str, arm: str | None = None) -> Vec3:
        """Where an arm grasps (its grasp link)."""
        return self.link_position(robot, self.robot(robot).arm(arm).gripper_link)

    def joint_positions(self, robot: str, joints: Iterable[int] | None = None) -> dict[int, float]:
        r = self.robot(robot)
        joints = r.movable if joints is None else tuple(joints)
        states = self.call(pb.getJointStates, r.body, list(joints))
        return {j: s[0] for j, s in zip(joints, states, strict=True)}

    def collisions(self, name: str, margin: float = 0.0,
                   ignore: Iterable[str] = ()) -> list[str]:
        """Names of bodies within ``margin`` of (or touching, or inside) body ``name``."""
        body, skip = self.body(name), set(ignore) | {name}
        return [other for other, b in self._bodies.items()
                if other not in skip
                and self.call(pb.getClosestPoints, body, b, margin)]

    # ----------------------------------------------------------------- motion

    def set_base_pose(self, robot: str, x: float, y: float, yaw: float) -> None:
        """Put a robot's base frame at (x, y) on the floor, heading ``yaw``.

        Kinematic: the robot jumps there.  PyBullet places a base by its
        centre of mass, so the URDF frame is converted here.
        """
        body = self.robot(robot).body
        local_pos, local_orn = self.call(pb.getDynamicsInfo, body, -1)[3:5]
        pos, orn = pb.multiplyTransforms([x, y, 0.0], yaw_quaternion(yaw), local_pos, local_orn)
        self.call(pb.resetBasePositionAndOrientation, body, pos, orn)

    def base_pose(self, robot: str) -> Place:
        """(x, y, yaw) of a robot's base frame."""
        pos, orn = self.pose(robot)
        yaw = pb.getEulerFromQuaternion(orn)[2]
        return pos[0], pos[1], yaw

    def set_joints(self, robot: str, positions: Mapping[int, float]) -> None:
        """Teleport joints and make their motors hold the new positions.

        Resetting alone would let the next physics step drop the arm under
        gravity; position motors at the joint's rated effort keep it there.
        """
        r = self.robot(robot)
        for j, value in positions.items():
            self.call(pb.resetJointState, r.body, j, value, 0.0)
        joints = list(positions)
        self.call(pb.setJointMotorControlArray, r.body, joints, pb.POSITION_CONTROL,
                  targetPositions=[positions[j] for j in joints],
                  forces=[r.efforts[j] for j in joints])

    def step(self, seconds: float) -> int:
        """Advance physics by ``seconds`` (rounded to whole time steps); return the steps."""
        steps = max(0, round(seconds / self.timestep))
        for _ in range(steps):
            self.call(pb.stepSimulation)
        self.time += steps * self.timestep
        return steps

    # ----------------------------------------------------------------- roadmap

    def segment_clear(self, a: tuple[float, float], b: tuple[float, float],
                      clearance: float = CLEARANCE, step: float = 0.02) -> bool:
        """Whether a base of radius ``clearance`` can slide from a to b missing furniture."""
        n = max(1, math.ceil(math.dist(a, b) / step))
        for i in range(n + 1):
            t = i / n
            px, py = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
            x0, x1, y0, y1 = ROOM
            if not (x0 + clearance <= px <= x1 - clearance
                    and y0 + clearance <= py <= y1 - clearance):
                return False
            if any(f.contains(px, py, clearance) for f in self.footprints.values()):
                return False
        return True

    def build_roadmap(self, clearance: float = CLEARANCE) -> dict[str, tuple[str, ...]]:
        """Place -> neighbouring places joined by a clear straight segment."""
        names = list(self.places)
        edges: dict[str, list[str]] = {n: [] for n in names}
        for i, a in enumerate(names):
            for b in names[i + 1:]:
                if self.segment_clear(self.places[a][:2], self.places[b][:2], clearance):
                    edges[a].append(b)
                    edges[b].append(a)
        return {n: tuple(sorted(v)) for n, v in edges.items()}

    def nearest_place(self, x: float, y: float) -> tuple[str, float]:
        """The place of the roadmap nearest to (x, y), and how far it is."""
        return min(((name, math.hypot(x - px, y - py))
                    for name, (px, py, _) in self.places.items()), key=lambda nd: nd[1])

    # ----------------------------------------------------------------- images

    def _view(self, camera: str | Camera, width: int,
              height: int) -> tuple[list[float], list[float]]:
        aspect = width / height
        if isinstance(camera, Camera) or camera in CAMERAS:
            cam = camera if isinstance(camera, Camera) else CAMERAS[camera]
            view = pb.computeViewMatrix(cam.eye, cam.target, cam.up)
            proj = pb.computeProjectionMatrixFOV(cam.fov, aspect, 0.1, 30.0)
            return view, proj
        if camera in self.robots and "camera_link" in self.robots[camera].links:
            pos, orn = self.link_pose(camera, "camera_link")
            rot = np.array(pb.getMatrixFromQuaternion(orn)).reshape(3, 3)
            forward, up = rot[:, 0], rot[:, 2]
            eye = np.array(pos) + 0.03 * forward  # just in front of the lens
            view = pb.computeViewMatrix(eye.tolist(), (eye + forward).tolist(), up.tolist())
            proj = pb.computeProjectionMatrixFOV(58.0, aspect, 0.05, 30.0)
            return view, proj
        known = [*CAMERAS, *(n for n, r in self.robots.items() if "camera_link" in r.links)]
        raise KeyError(f"unknown camera {camera!r} (cameras: {', '.join(known)})")

    def image(self, width: int = 320, height: int = 240,
              camera: str | Camera = "overview") -> bytes:
        """RGB bytes (rows top to bottom) seen by a camera, a named one or a robot's.

        ER_TINY_RENDERER is the software renderer: it works headless and needs
        no GPU or display.
        """
        view, proj = self._view(camera, width, height)
        _, _, rgba, _, _ = self.call(
            pb.getCameraImage, width, height, viewMatrix=view, projectionMatrix=proj,
            renderer=pb.ER_TINY_RENDERER, shadow=1, lightDirection=list(LIGHT_DIRECTION),
            flags=pb.ER_NO_SEGMENTATION_MASK)
        pixels = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)
        return pixels[:, :, :3].tobytes()

    def snapshot(self, path: str | Path, width: int = 320, height: int = 240,
                 camera: str | Camera = "overview", caption: list[str] = ()) -> Path:
        """Write a PNG of what ``camera`` sees (``overview``, ``top``, a robot's name or
        a :class:`Camera`), ``width`` x ``height`` in all: with a ``caption``, its
        lines are written in a strip along the bottom of the picture."""
        path = Path(path)
        write_output(path, self.picture(width, height, camera, caption))
        return path

    def picture(self, width: int = 320, height: int = 240, camera: str | Camera = "overview",
                caption: list[str] = ()) -> bytes:
        """The PNG bytes :meth:`snapshot` writes: a picture that travels without a file
        (a question's, sent to whoever answers whether or not the run keeps files)."""
        if not caption:
            return encode_png(width, height, self.image(width, height, camera))
        band = caption_height(len(caption), height)
        pixels = self.image(width, height - band, camera)
        return encode_png(width, height, with_caption(pixels, width, height - band,
                                                      caption, band))
