"""The seam-welding site of HRI/OS (paper 002, Section 4, Fig. 6) in PyBullet.

A truss frame stands along the x axis; four panels P1–P4 (1 m squares, 3 cm
thick, 15 kg) are mounted on its south face side by side, so three seams join
them: P1-P2 at x = 1, P2-P3 at x = 2, P3-P4 at x = 3.  Panels not yet mounted
lie flat on a pallet south-east of the frame.  The site is on the Moon
(gravity 1.62 m/s²), like the planetary surface operations the paper aims at.

Physics is real where it decides something: panels are dynamic bodies, carried
by a constraint that follows the carriers' hands, and *tacked* to the frame by
a fixed constraint; a panel let go untacked falls.  A weld lays a bead (a
thin body) along its seam, whose look (bright and even, or dark and pitted)
shows its quality in the rover's camera image.

Robots are the inspection rover ``K-10`` (model ``k10``: camera and spotlight
on a pan-tilt head) and the welding humanoid ``Robonaut-B`` (model
``pr2like``: two arms on a mobile base, like Robonaut-B on its Segway); the
suited astronauts are avatars (:class:`sim.avatar.Avatar`).  Like the living
room, bases move kinematically; :class:`WeldSite` is a
:class:`~sim.world.LivingRoom` that builds this site instead of the room, so
the arm kinematics, cameras and snapshots are the same code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..room import Part
from ..world import LivingRoom, Vec3, pb
from .layout import (
    PALLET,
    PALLET_TOP,
    PANEL_HEIGHT,
    PANEL_MASS,
    PANEL_THICKNESS,
    PANEL_WIDTH,
    PANEL_Y,
    PANEL_Z,
    PANELS,
    SEAM_BEAD,
    panel_x,
    robot_places,
    seam_x,
)

MOON_GRAVITY = -1.62
GROUND_RGBA = (0.55, 0.54, 0.52, 1.0)
FRAME_RGBA = (0.45, 0.47, 0.52, 1.0)
PANEL_RGBA = ((0.72, 0.74, 0.78, 1.0), (0.62, 0.66, 0.72, 1.0))
"""Panels alternate two greys, so their seams show."""
SPOT_RGBA = (1.0, 0.95, 0.45, 0.85)
SPOT_RADIUS = 0.12
GOOD_BEAD = (0.95, 0.72, 0.35, 1.0)
BAD_BEAD = (0.25, 0.18, 0.12, 1.0)


@dataclass(frozen=True)
class Bead:
    """A weld along a seam: its body and its quality (1 sound, 0 useless)."""

    body: int
    quality: float


class WeldSite(LivingRoom):
    """The seam-welding site (see the module's docstring), in its own PyBullet client."""

    def __init__(self, gui: bool = False):
        self.panels: dict[str, int] = {}
        self.tacks: dict[str, int] = {}
        self.carried: dict[str, int] = {}
        self.beads: dict[str, Bead] = {}
        self.spots: dict[str, int] = {}
        """A spotlight's name -> the disc of light it casts (where its beam meets a body)."""
        super().__init__(gui=gui, robot=None, gravity=MOON_GRAVITY)

    def _furnish(self) -> None:
        self.places = robot_places()
        ground = [Part((8.0, 6.0, 0.05), (0.0, 0.0, -0.05), GROUND_RGBA)]
        self._add_static("ground", 2.0, -1.0, 0.0, ground)
        del self.footprints["ground"]
        self._add_static("frame", 0.0, 0.0, 0.0, _truss())
        self._add_static("pallet", *PALLET, 0.0,
                         [Part((0.65, 0.65, PALLET_TOP / 2), (0, 0, PALLET_TOP / 2),
                               (0.5, 0.36, 0.2, 1.0))])
        for i, panel in enumerate(PANELS):
            half = [PANEL_WIDTH / 2, PANEL_THICKNESS / 2, PANEL_HEIGHT / 2]
            col = self.call(pb.createCollisionShape, pb.GEOM_BOX, halfExtents=half)
            vis = self.call(pb.createVisualShape, pb.GEOM_BOX, halfExtents=half,
                            rgbaColor=list(PANEL_RGBA[i % 2]))
            body = self.call(pb.createMultiBody, baseMass=PANEL_MASS,
                             baseCollisionShapeIndex=col, baseVisualShapeIndex=vis,
                             basePosition=self.stacked(i), baseOrientation=_flat())
            self.call(pb.changeDynamics, body, -1, lateralFriction=0.9)
            self._bodies[panel] = body
            self.panels[panel] = body
        self.roadmap = {}

    # -- panels -------------------------------------------------------------------

    @staticmethod
    def stacked(index: int) -> list[float]:
        """Where the ``index``-th panel lies on the pallet (flat, one on another)."""
        return [PALLET[0], PALLET[1], PALLET_TOP + PANEL_THICKNESS * (index + 0.5) + 1e-3]

    @staticmethod
    def mount_pose(panel: str) -> tuple[list[float], tuple[float, ...]]:
        """A mounted panel's centre and orientation (upright, its front facing south)."""
        return [panel_x(panel), PANEL_Y, PANEL_Z], (0.0, 0.0, 0.0, 1.0)

    def mount(self, panel: str) -> None:
        """Put a panel in its place on the frame and tack it there (a scenario's start)."""
        pos, orn = self.mount_pose(panel)
        self.call(pb.resetBasePositionAndOrientation, self.panels[panel], pos, orn)
        self.tack(panel)

    def lift(self, panel: str, at: list[float], orientation: tuple[float, ...]) -> None:
        """Hold a panel by a constraint whose pivot the carriers move (see :meth:`carry_to`)."""
        body = self.panels[panel]
        self.release_tack(panel)
        self.carried[panel] = self.call(
            pb.createConstraint, body, -1, -1, -1, pb.JOINT_FIXED, [0, 0, 0], [0, 0, 0], at,
            childFrameOrientation=orientation)
        self.call(pb.changeConstraint, self.carried[panel], at, orientation, maxForce=2000)

    def carry_to(self, panel: str, at: list[float], orientation: tuple[float, ...],
                 kinematic: bool = False) -> None:
        """Move the carrying pivot: physics brings the panel along as it steps, or, with
        ``kinematic``, the panel is put there at once (a walk across open ground)."""
        self.call(pb.changeConstraint, self.carried[panel], at, orientation, maxForce=2000)
        if kinematic:
            body = self.panels[panel]
            self.call(pb.resetBasePositionAndOrientation, body, at, orientation)
            self.call(pb.resetBaseVelocity, body, [0, 0, 0], [0, 0, 0])

    def put_down(self, panel: str) -> None:
        """The carriers let go: the panel is left to physics (and falls unless tacked)."""
        cid = self.carried.pop(panel, None)
        if cid is not None:
            self.call(pb.removeConstraint, cid)

    def lay_down(self, panel: str, x: float, y: float) -> None:
        """Carriers who stop lay the panel they hold flat on the ground at (x, y) and let
        go: it rests there, where whoever carries it next finds it (let go in mid-air it
        would float, as physics steps only while something is carried onto the frame)."""
        self.put_down(panel)
        body = self.panels[panel]
        self.call(pb.resetBasePositionAndOrientation, body, [x, y, PANEL_THICKNESS / 2 + 1e-3],
                  _flat())
        self.call(pb.resetBaseVelocity, body, [0, 0, 0], [0, 0, 0])

    def tack(self, panel: str) -> None:
        """Tack-weld a panel to the frame where it is: a fixed constraint to the frame."""
        if panel in self.tacks:
            return
        pos, orn = self.call(pb.getBasePositionAndOrientation, self.panels[panel])
        frame = self.body("frame")
        self.tacks[panel] = self.call(pb.createConstraint, frame, -1, self.panels[panel], -1,
                                      pb.JOINT_FIXED, [0, 0, 0], list(pos), [0, 0, 0],
                                      parentFrameOrientation=orn)
        self.put_down(panel)

    def release_tack(self, panel: str) -> None:
        cid = self.tacks.pop(panel, None)
        if cid is not None:
            self.call(pb.removeConstraint, cid)

    def mounted(self, panel: str, tolerance: float = 0.03) -> bool:
        """Whether a panel is tacked in its place on the frame."""
        pos, _ = self.call(pb.getBasePositionAndOrientation, self.panels[panel])
        return panel in self.tacks and math.dist(pos, self.mount_pose(panel)[0]) <= tolerance

    # -- seams --------------------------------------------------------------------

    def seam_points(self, seam: str, count: int = 3) -> list[tuple[float, float, float]]:
        """Points along a seam on the panels' front faces, bottom to top."""
        x = seam_x(seam)
        y = PANEL_Y - PANEL_THICKNESS / 2 - SEAM_BEAD
        bottom, top = PANEL_Z - PANEL_HEIGHT / 2 + 0.1, PANEL_Z + PANEL_HEIGHT / 2 - 0.1
        return [(x, y, bottom + (top - bottom) * i / (count - 1)) for i in range(count)]

    def lay_bead(self, seam: str, quality: float, upto: float = 1.0) -> None:
        """The weld bead along ``seam`` up to a fraction ``upto`` of its length (the torch's
        progress), coloured by its quality: bright and even when sound, dark when not."""
        old = self.beads.pop(seam, None)
        if old is not None:
            self.call(pb.removeBody, old.body)
        length = PANEL_HEIGHT * max(0.02, min(1.0, upto))
        x = seam_x(seam)
        y = PANEL_Y - PANEL_THICKNESS / 2 - SEAM_BEAD / 2
        z = PANEL_Z - PANEL_HEIGHT / 2 + length / 2
        mix = max(0.0, min(1.0, quality))
        rgba = [b + (g - b) * mix for g, b in zip(GOOD_BEAD, BAD_BEAD, strict=True)]
        vis = self.call(pb.createVisualShape, pb.GEOM_BOX,
                        halfExtents=[SEAM_BEAD, SEAM_BEAD / 2, length / 2], rgbaColor=rgba)
        body = self.call(pb.createMultiBody, baseMass=0, baseVisualShapeIndex=vis,
                         basePosition=[x, y, z])
        self.beads[seam] = Bead(body, quality)

    def grind(self, seam: str) -> None:
        """Remove a seam's bead (a failed weld ground off before it is welded again)."""
        old = self.beads.pop(seam, None)
        if old is not None:
            self.call(pb.removeBody, old.body)

    # -- light ----------------------------------------------------------------------

    def shine(self, light: str, origin: Vec3, direction: Vec3,
              reach: float = 12.0) -> Vec3 | None:
        """Cast a spotlight's beam (a ray from ``origin`` along ``direction``) and put its
        disc of light where it meets the first body; that point, or None if it meets
        nothing within ``reach`` metres (the disc is then taken away)."""
        end = [o + reach * d for o, d in zip(origin, direction, strict=True)]
        hit = self.call(pb.rayTest, list(origin), end)[0]
        old = self.spots.pop(light, None)
        if old is not None:
            self.call(pb.removeBody, old)
        if hit[0] < 0:
            return None
        point, normal = tuple(hit[3]), hit[4]
        vis = self.call(pb.createVisualShape, pb.GEOM_CYLINDER, radius=SPOT_RADIUS,
                        length=0.004, rgbaColor=list(SPOT_RGBA))
        # the disc lies on the surface: its axis (z) along the surface's normal
        orn = _z_towards(normal)
        at = [p + 0.003 * n for p, n in zip(point, normal, strict=True)]
        self.spots[light] = self.call(pb.createMultiBody, baseMass=0,
                                      baseVisualShapeIndex=vis, basePosition=at,
                                      baseOrientation=orn)
        return point


def _z_towards(normal: Vec3) -> tuple[float, ...]:
    """A quaternion turning +z onto ``normal``."""
    nx, ny, nz = normal
    axis = (-ny, nx, 0.0)  # z x normal
    s = math.hypot(*axis)
    angle = math.atan2(s, nz)
    if s < 1e-9:
        return (0.0, 0.0, 0.0, 1.0) if nz > 0 else (1.0, 0.0, 0.0, 0.0)
    k = math.sin(angle / 2) / s
    return (axis[0] * k, axis[1] * k, 0.0, math.cos(angle / 2))


def _flat() -> tuple[float, ...]:
    """A panel lying flat: its face turned up."""
    return tuple(pb.getQuaternionFromEuler([math.pi / 2, 0.0, 0.0]))


def _truss() -> list[Part]:
    """The frame: five posts and two beams (boxes, static)."""
    parts = []
    for i in range(5):
        parts.append(Part((0.04, 0.04, 0.85), (float(i), 0.0, 0.85), FRAME_RGBA))
    for z in (0.55, 1.55):
        parts.append(Part((2.04, 0.04, 0.04), (2.0, 0.0, z), FRAME_RGBA))
    return parts

