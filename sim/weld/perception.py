"""What the team perceives of the seam-welding site, as facts.

After every tick, :class:`SitePerception` writes into the fact base (the
``robot`` perspective the team's robots share) where each agent and panel is
— ``x``, ``y``, ``z`` and ``yaw`` (where its front faces), rounded to a
centimetre and a hundredth of a radian so that standing still changes nothing
— whether each panel is ``mounted`` and each seam ``welded``.  The spatial
reasoning agent (:mod:`shary.team.spatial`) reasons on these facts only, and the
team keeps its agents' positions (the Resource Manager's distance criterion)
from their ``x`` and ``y``.

Before the run, the kinds of things and the panels' sizes are stated once.
"""

from __future__ import annotations

import math
from typing import Any

from ..world import pb
from .layout import PANEL_HEIGHT, PANEL_THICKNESS, PANEL_WIDTH, PANELS, SEAMS
from .site import WeldSite


class SitePerception:
    """Poses and states of the site, published as facts when they change."""

    def __init__(self, site: WeldSite, people: dict[str, Any], facts: Any,
                 perspective: str = "robot"):
        self.site = site
        self.people = people
        self.facts = facts
        self.perspective = perspective
        self._published: dict[tuple[str, str], Any] = {}
        """What was last written for each (subject, predicate): only changes are written."""

    def a_priori(self) -> None:
        """Kinds and sizes: what does not change."""
        add = self.facts.add
        for robot in self.site.robots:
            add(robot, "type", "Robot", self.perspective)
            add(robot, "type", "Agent", self.perspective)
        for person in self.people:
            add(person, "type", "Human", self.perspective)
            add(person, "type", "Agent", self.perspective)
        for panel in PANELS:
            add(panel, "type", "Panel", self.perspective)
            for predicate, value in (("width", PANEL_WIDTH), ("height", PANEL_HEIGHT),
                                     ("thickness", PANEL_THICKNESS)):
                add(panel, predicate, value, self.perspective)
        for seam in SEAMS:
            add(seam, "type", "Seam", self.perspective)

    def update(self) -> None:
        """Publish what changed since the last look."""
        site = self.site
        for robot in site.robots:
            x, y, yaw = site.base_pose(robot)
            self._pose(robot, x, y, 0.0, yaw)
        for name, avatar in self.people.items():
            self._pose(name, avatar.x, avatar.y, 0.0, avatar.yaw)
        for panel, body in site.panels.items():
            pos, orn = site.call(pb.getBasePositionAndOrientation, body)
            m = pb.getMatrixFromQuaternion(orn)
            front = (-m[1], -m[4])  # the body's -y axis: the panel's front face
            facing = math.atan2(front[1], front[0]) if math.hypot(*front) > 0.5 else None
            self._pose(panel, pos[0], pos[1], pos[2], facing)
            self._set(panel, "mounted", site.mounted(panel))
        for seam in SEAMS:
            self._set(seam, "welded", seam in site.beads)

    def _pose(self, name: str, x: float, y: float, z: float, yaw: float | None) -> None:
        for predicate, value in (("x", x), ("y", y), ("z", z)):
            self._set(name, predicate, round(value, 2))
        if yaw is not None:
            self._set(name, "yaw", round(math.atan2(math.sin(yaw), math.cos(yaw)), 2))

    def _set(self, s: str, p: str, o: Any) -> None:
        key = (s, p)
        if key not in self._published or self._published[key] != o:
            self._published[key] = o
            self.facts.set(s, p, o, self.perspective)
