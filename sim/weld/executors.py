"""What the site's robots and astronauts do, over simulated time.

The robots' atomic tasks reach the site through the engine's executor port
(:class:`shary.kernel.executors.Executor`): ``drive`` (to a site place), ``weld`` (a
seam: Robonaut-B's left arm follows it, the bead grows as the torch goes),
``inspect`` (a seam: K-10 aims its camera and light at it and reads the weld),
``point-light`` (K-10's spotlight at a point) and ``snapshot`` (a picture from
K-10's camera).  The astronauts' work — carrying a panel from the pallet to
the frame and tacking it — is :meth:`SiteActions.mount`, which the run starts
when a person accepts that task.

Motion reuses :mod:`sim.motion`'s kinematic activities (bases at a bounded
speed, joints at a bounded speed) on the clock of :class:`sim.simulation.Simulation`;
physics steps only where it decides something (a carried panel follows its
constraint, a tacked panel stays put).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from shary.kernel.executors import Reporter, Request
from userfiles.outputs import write_output

from ..avatar import Avatar
from ..kinematics import reach
from ..motion import BaseMotion, Instant, JointMotion, Lazy, Sequence, Wait, wrap
from ..simulation import Simulation, Walk
from ..world import pb
from .layout import PANEL_HEIGHT, PANEL_Y, PANEL_Z, PANELS, panel_x, seam_x
from .site import WeldSite

WELDER_ARM = "left"
SOUND, BAD = 0.8, 0.4
"""A bead read at or above SOUND is good, below BAD is bad; between, K-10 is unsure."""
WALK_SPEED = 0.5
"""Suited astronauts carrying a panel, m/s."""
CARRY_HALF_SPAN = 0.9
"""Carriers stand this far either side of a panel's centre (beyond its ends: a spotlight
aimed at the panel's corner passes between them)."""
ARMS = 0.3
"""How far in front of its carriers a panel is held, in metres."""
SET_DOWN_BESIDE = 0.4
"""How far behind its carriers (away from the frame) a panel they stop carrying is laid."""
INSPECT_SECONDS = 2.0
WELD_SECONDS_PER_POINT = 2.0
LANE_Y = -1.6
"""Robots drive along this line south of the frame, then turn in to their spot."""
AIM_ROUNDS = 3


class SiteActions:
    """The robots' executors and the astronauts' work on one :class:`WeldSite`."""

    def __init__(self, site: WeldSite, sim: Simulation, *,
                 qualities: dict[str, list[float]] | None = None,
                 snapshot_dir: Path | None = None,
                 tell: Callable[[str, str, str], None] = lambda who, kind, text: None):
        self.site = site
        self.sim = sim
        self.qualities = {seam: list(q) for seam, q in (qualities or {}).items()}
        """Seam -> the quality of each successive weld of it (the last one repeats)."""
        self.snapshot_dir = snapshot_dir
        self.snapshots: list[str] = []
        self.tell = tell
        self.running: dict[str, int] = {}  # request id -> activity handle
        self.people: dict[str, Avatar] = {}

    # -- the executor port ------------------------------------------------------------

    def start(self, request: Request, reporter: Reporter) -> None:
        act = getattr(self, "_" + request.atomic.replace("-", "_"), None)
        if act is None:
            reporter.failed(request, f"the site cannot perform {request.atomic!r}")
            return
        try:
            activity, finish = act(request)
        except (KeyError, ValueError) as err:
            reporter.failed(request, str(err.args[0]) if err.args else str(err))
            return

        def over() -> None:
            self.running.pop(request.id, None)
            outcome = finish()
            if isinstance(outcome, str):
                reporter.failed(request, outcome)
            else:
                reporter.done(request, **outcome)

        self.running[request.id] = self.sim.start(activity, over)

    def cancel(self, request: Request) -> None:
        handle = self.running.pop(request.id, None)
        if handle is not None:
            self.sim.stop(handle)

    # -- robots ---------------------------------------------------------------------

    def _drive(self, request: Request) -> tuple[Any, Callable[[], Any]]:
        robot, place = request.agent, request.args["place"]
        if place not in self.site.places:
            raise KeyError(f"no place {place!r} on the site (places: "
                           f"{', '.join(self.site.places)})")
        x, y, yaw = self.site.places[place]
        cx, cy, _ = self.site.base_pose(robot)
        waypoints = [(cx, LANE_Y), (x, LANE_Y), (x, y)] if abs(cx - x) > 0.05 else [(x, y)]
        return BaseMotion(self.site, robot, waypoints, yaw), lambda: {"place": place}

    def _weld(self, request: Request) -> tuple[Any, Callable[[], Any]]:
        robot, seam = request.agent, request.args["seam"]
        points = self.site.seam_points(seam)
        quality = self._next_quality(seam)
        parts: list[Any] = [Instant(lambda: self.site.grind(seam), "grind")]
        arm = self.site.robot(robot).arm(WELDER_ARM)

        for i, point in enumerate(points):
            def move(point: tuple[float, float, float] = point) -> JointMotion:
                q, _ = reach(self.site, robot, point, arm=WELDER_ARM)
                return JointMotion(self.site, robot, dict(zip(arm.joints, q, strict=True)))

            parts += [Lazy(move, "reach"), Wait(WELD_SECONDS_PER_POINT, label="weld"),
                      Instant(lambda i=i: self.site.lay_bead(seam, quality,
                                                               (i + 1) / len(points)))]
        home = {j: self.site.robot(robot).home.get(j, 0.0) for j in arm.joints}
        parts.append(JointMotion(self.site, robot, home))

        def finish() -> dict[str, Any] | str:
            bead = self.site.beads.get(seam)
            return {"seam": seam} if bead is not None else f"no bead along {seam}"

        return Sequence(parts, "weld"), finish

    def _next_quality(self, seam: str) -> float:
        left = self.qualities.get(seam) or [0.95]
        return left.pop(0) if len(left) > 1 else left[0]

    def _inspect(self, request: Request) -> tuple[Any, Callable[[], Any]]:
        robot, seam = request.agent, request.args["seam"]
        centre = (seam_x(seam), self.site.seam_points(seam)[0][1], PANEL_Z)
        aim = Lazy(lambda: self.aim(robot, centre, "camera_link"), "aim")

        def finish() -> dict[str, Any] | str:
            bead = self.site.beads.get(seam)
            quality = bead.quality if bead is not None else 0.0
            verdict = ("sound" if quality >= SOUND else "bad" if quality < BAD else "unsure")
            self.tell(robot, "inspect", f"{seam}: {verdict} (bead read {quality:.2f})")
            if verdict == "bad":
                return f"the weld of {seam} is bad"
            return {"seam": seam, "verdict": verdict, "quality": round(quality, 2)}

        return Sequence([aim, Wait(INSPECT_SECONDS, label="inspect")], "inspect"), finish

    def _aim(self, request: Request) -> tuple[Any, Callable[[], Any]]:
        robot, target = request.agent, str(request.args["target"])
        if target in PANELS:
            point = (panel_x(target), PANEL_Y, PANEL_Z)
        else:
            point = (seam_x(target), PANEL_Y, PANEL_Z)  # ValueError names the seams
        return Lazy(lambda: self.aim(robot, point), "aim"), lambda: {"target": target}

    def _point_light(self, request: Request) -> tuple[Any, Callable[[], Any]]:
        robot = request.agent
        point = tuple(float(request.args[k]) for k in ("x", "y", "z"))

        def finish() -> dict[str, Any]:
            lit = self.shine(robot)
            result: dict[str, Any] = {"at": [round(v, 3) for v in point]}
            if lit is not None:
                result["lit"] = [round(v, 3) for v in lit]
                result["off_by_m"] = round(math.dist(lit, point), 3)
            return result

        return Lazy(lambda: self.aim(robot, point), "aim"), finish

    def _snapshot(self, request: Request) -> tuple[Any, Callable[[], Any]]:
        robot = request.agent
        label = str(request.args.get("label", "view"))
        image: list[str] = []
        return (Instant(lambda: image.append(self.snapshot(robot, label, label) or "")),
                lambda: {"image": image[0]} if image and image[0] else {})

    def aim(self, robot: str, point: tuple[float, float, float],
            device: str = "spotlight_link") -> JointMotion:
        """K-10's head turned so that ``device`` (its spotlight or its camera) looks at a
        point in the world."""
        pan, tilt = self.pan_tilt(robot, point, device)
        r = self.site.robot(robot)
        return JointMotion(self.site, robot, {r.joint("light_pan_joint"): pan,
                                              r.joint("light_tilt_joint"): tilt}, speed=1.5)

    def pan_tilt(self, robot: str, point: tuple[float, float, float],
                 device: str = "spotlight_link") -> tuple[float, float]:
        """The head's (pan, tilt) that make ``device`` look at ``point``.

        The spotlight and the camera sit beside the head's axes, so the direction from
        the head's centre misses by centimetres; as for an arm's IK, the answer is
        refined from where the device really is (three rounds get within a millimetre),
        and the head is put back where it was.
        """
        r = self.site.robot(robot)
        joints = (r.joint("light_pan_joint"), r.joint("light_tilt_joint"))
        before = self.site.joint_positions(robot, joints)
        _, _, yaw = self.site.base_pose(robot)
        lo, hi = r.limits[joints[1]]
        pan = tilt = 0.0
        for _ in range(AIM_ROUNDS):
            origin = self.site.link_position(robot, device)
            dx, dy, dz = (p - o for p, o in zip(point, origin, strict=True))
            pan = wrap(pan + wrap(math.atan2(dy, dx) - yaw - self._heading(robot, device)))
            tilt = max(lo, min(hi, tilt + math.atan2(dz, math.hypot(dx, dy))
                               - self._elevation(robot, device)))
            for j, v in zip(joints, (pan, tilt), strict=True):
                self.site.call(pb.resetJointState, r.body, j, v, 0.0)
        for j, v in before.items():
            self.site.call(pb.resetJointState, r.body, j, v, 0.0)
        return pan, tilt

    def _heading(self, robot: str, device: str) -> float:
        """Where ``device`` looks now, relative to the robot's base heading."""
        _, orn = self.site.link_pose(robot, device)
        m = pb.getMatrixFromQuaternion(orn)
        _, _, yaw = self.site.base_pose(robot)
        return wrap(math.atan2(m[3], m[0]) - yaw)

    def _elevation(self, robot: str, device: str) -> float:
        _, orn = self.site.link_pose(robot, device)
        m = pb.getMatrixFromQuaternion(orn)
        return math.atan2(m[6], math.hypot(m[0], m[3]))

    def shine(self, robot: str) -> tuple[float, float, float] | None:
        """Switch ``robot``'s spotlight on where it points now: the point its beam lights."""
        origin, orn = self.site.link_pose(robot, "spotlight_link")
        m = pb.getMatrixFromQuaternion(orn)
        ahead = (origin[0] + 0.05 * m[0], origin[1] + 0.05 * m[3], origin[2] + 0.05 * m[6])
        return self.site.shine(robot, ahead, (m[0], m[3], m[6]))

    def snapshot(self, robot: str, label: str, caption: str) -> str | None:
        """A PNG of what ``robot``'s camera sees, named after the time and ``label``;
        its path, or None when the run writes no files."""
        return self.keep(robot, label, self.picture(robot, caption)) \
            if self.snapshot_dir is not None else None

    def picture(self, robot: str, caption: str) -> bytes:
        """The PNG bytes of what ``robot``'s camera sees now, captioned with the time."""
        return self.site.picture(480, 360, robot, [f"{self.sim.loop.now():.1f} s   {caption}"])

    def keep(self, robot: str, label: str, png: bytes) -> str | None:
        """Write a picture into the run's folder, named after the time and ``label``; its
        path, or None when the run writes no files."""
        if self.snapshot_dir is None:
            return None
        name = (f"{robot.lower()}-{len(self.snapshots) + 1:02d}-"
                f"{self.sim.loop.now():06.1f}s-{label}.png")
        path = self.snapshot_dir / name
        write_output(path, png)
        self.snapshots.append(name)
        return str(path)

    # -- astronauts -----------------------------------------------------------------

    def add_person(self, name: str, x: float, y: float, yaw: float,
                   suit: tuple[float, float, float, float] = (0.95, 0.95, 0.93, 1.0)) -> Avatar:
        avatar = Avatar(self.site, name, x, y, yaw, suit)
        self.people[name] = avatar
        self.sim.people[name] = avatar
        return avatar

    def mount(self, panel: str, carriers: list[str], done: Callable[[], Any]) -> int:
        """Carriers walk to the pallet, lift ``panel``, carry it to its place on the frame,
        hold it there and tack it (the panel follows a constraint; physics carries it)."""
        if panel not in PANELS:
            raise KeyError(f"no panel {panel!r} (panels: {', '.join(PANELS)})")
        site = self.site
        body = site.panels[panel]
        pallet, _ = site.call(pb.getBasePositionAndOrientation, body)
        mount_at, upright = site.mount_pose(panel)
        people = [self.people[c] for c in carriers]
        # one at each end of the panel, the first (whose task it is) at its west end
        sides = [-(-1) ** i for i in range(len(people))]

        def to(ax: float, ay: float, facing: float) -> list[Walk]:
            return [Walk(p, [(ax + s * CARRY_HALF_SPAN, ay)], WALK_SPEED, final_yaw=facing)
                    for p, s in zip(people, sides, strict=True)]

        # the panel is held at arm's length, north of its carriers: on the frame it slides
        # the last stretch on its own, clear of whoever mounts the next panel
        carry_y = -0.6
        lift_at = [pallet[0], pallet[1], PANEL_Z]
        parts: list[Any] = [_Together(to(pallet[0], pallet[1] - ARMS, math.pi / 2)),
                            Instant(lambda: site.lift(panel, list(pallet), upright)),
                            _Carry(site, panel, list(pallet), lift_at, 0.4, upright)]
        shift = -sum(sides) / len(sides) * CARRY_HALF_SPAN  # one carrier: at the west end
        carry = _Together(to(mount_at[0], carry_y - ARMS, math.pi / 2),
                          follow=lambda: self._held(panel, people, shift, upright))
        parts += [carry,
                  _Carry(site, panel, None, mount_at, 0.3, upright, physics=True),
                  Wait(1.0, label="align"),
                  Instant(lambda: site.tack(panel), "tack")]
        return self.sim.start(Sequence(parts, "mount"), done)

    def set_down(self, panel: str, carriers: list[str]) -> bool:
        """Carriers who stop (one of them left) put down the panel they hold: flat on the
        ground beside them, on the side away from the frame.  False when they held
        nothing: it was still on the pallet, or already tacked to the frame."""
        site = self.site
        if panel not in site.carried:
            return False
        people = [self.people[c] for c in carriers]
        x = sum(p.x for p in people) / len(people)
        y = sum(p.y for p in people) / len(people) - SET_DOWN_BESIDE - PANEL_HEIGHT / 2
        site.lay_down(panel, x, y)
        return True

    def _held(self, panel: str, people: list[Avatar], shift: float,
              orientation: tuple[float, ...]) -> None:
        """The carried panel in its carriers' hands: between them, at arm's length."""
        x = sum(p.x for p in people) / len(people) + shift
        y = sum(p.y for p in people) / len(people) + ARMS
        self.site.carry_to(panel, [x, y, PANEL_Z], orientation, kinematic=True)


class _Together:
    """Several activities advanced side by side; over when all are (``follow`` after each
    tick: the carried panel follows the carriers)."""

    def __init__(self, parts: list[Any], follow: Callable[[], Any] | None = None):
        self.parts = list(parts)
        self.follow = follow
        self.label = "together"

    def advance(self, dt: float) -> bool:
        self.parts = [p for p in self.parts if not p.advance(dt)]
        if self.follow is not None:
            self.follow()
        return not self.parts


class _Carry:
    """A held panel moved in a straight line at a bounded speed.  ``physics``: PyBullet steps
    as it goes (the panel follows its constraint, and meets the frame as physics says);
    otherwise it is moved kinematically (a walk across open ground decides nothing)."""

    label = "carry"

    def __init__(self, site: WeldSite, panel: str, start: list[float] | None,
                 goal: list[float], speed: float, orientation: tuple[float, ...],
                 physics: bool = False):
        self.site, self.panel = site, panel
        self.start, self.goal = start, goal
        self.speed, self.orientation = speed, orientation
        self.physics = physics
        self.at: list[float] | None = None

    def advance(self, dt: float) -> bool:
        if self.at is None:
            pos = self.start or list(self.site.call(
                pb.getBasePositionAndOrientation, self.site.panels[self.panel])[0])
            self.at = list(pos)
        left = math.dist(self.at, self.goal)
        step = min(left, self.speed * dt)
        if left > 1e-9:
            self.at = [a + (g - a) * step / left for a, g in zip(self.at, self.goal, strict=True)]
        self.site.carry_to(self.panel, self.at, self.orientation, kinematic=not self.physics)
        if self.physics:
            self.site.step(dt)
        return step >= left - 1e-9
