"""Robot models in the simulated world: which URDF, the home posture, and the arms found.

:class:`sim.world.LivingRoom` loads robots by model name (``jido``,
``pr2like``, ``k10``); this module says what each model is and describes a
loaded body so that PyBullet calls are quick (joint and link indexes, limits,
the arms and their fingers).  It is its own module because robots change for
their own reasons (a new model, a new posture, another way to find arms in a
URDF), not when the room, its cameras or its queries do.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from .quiet import silenced

with silenced():  # the import prints a "pybullet build time" banner on stderr
    import pybullet as pb

MODELS_DIR = Path(__file__).resolve().parent / "models"


@dataclass(frozen=True)
class ModelSpec:
    """A robot model: its URDF file and its home (tucked) joint positions by name."""

    urdf: str
    home: Mapping[str, float] = field(default_factory=dict)


MODELS: dict[str, ModelSpec] = {
    "jido": ModelSpec("jido.urdf", {
        # folded back along the robot's right side, out of the head camera's view
        "arm_joint_1": -2.9, "arm_joint_2": -0.25, "arm_joint_4": 2.09, "arm_joint_6": 1.16,
        "head_tilt_joint": 0.8,  # looking at a table top in front of the robot
    }),
    "pr2like": ModelSpec("pr2like.urdf", {
        # the PR2's usual "tucked arms" posture
        "torso_lift_joint": 0.05,
        "l_shoulder_pan_joint": 0.06, "l_shoulder_lift_joint": 1.25,
        "l_upper_arm_roll_joint": 1.79, "l_elbow_flex_joint": -1.68,
        "l_forearm_roll_joint": -1.73, "l_wrist_flex_joint": -0.1, "l_wrist_roll_joint": -0.09,
        "r_shoulder_pan_joint": -0.02, "r_shoulder_lift_joint": 1.11,
        "r_upper_arm_roll_joint": -1.56, "r_elbow_flex_joint": -2.12,
        "r_forearm_roll_joint": -1.42, "r_wrist_flex_joint": -1.84, "r_wrist_roll_joint": 0.21,
        "head_tilt_joint": 0.6,
    }),
    "k10": ModelSpec("k10.urdf"),  # the seam-welding case's inspection rover (sim/weld)
}


@dataclass(frozen=True)
class Arm:
    """One arm of a robot: its joints root to tip, its grasp link and its fingers."""

    name: str
    joints: tuple[int, ...]
    gripper_link: int
    fingers: tuple[int, ...]


@dataclass
class Robot:
    """What the world knows of a loaded robot, indexed for quick PyBullet calls.

    Arms are found from the model, not hard-coded: each link named
    ``gripper_link`` or ``<prefix>_gripper_link`` ends an arm whose joints are
    the movable joints on its path from the base, minus those shared with
    another arm (a torso lift moves both arms of a PR2 and belongs to neither).
    Fingers are the movable joints below the arm's last joint that are not on
    the path to the grasp link.
    """

    name: str
    model: str
    body: int
    joints: dict[str, int]
    links: dict[str, int]
    limits: dict[int, tuple[float, float]]
    efforts: dict[int, float]
    movable: tuple[int, ...]  # PyBullet's degree-of-freedom order (IK results use it)
    arms: dict[str, Arm]
    home: dict[int, float]

    @property
    def default_arm(self) -> str:
        for name in ("arm", "right"):
            if name in self.arms:
                return name
        return next(iter(self.arms))

    def arm(self, name: str | None = None) -> Arm:
        name = self.default_arm if name is None else name
        try:
            return self.arms[name]
        except KeyError:
            raise KeyError(f"robot {self.name!r} has no arm {name!r} "
                           f"(arms: {', '.join(self.arms)})") from None

    def joint(self, name: str) -> int:
        try:
            return self.joints[name]
        except KeyError:
            raise KeyError(f"robot {self.name!r} has no joint {name!r}") from None

    def link(self, name: str) -> int:
        try:
            return self.links[name]
        except KeyError:
            raise KeyError(f"robot {self.name!r} has no link {name!r}") from None


def _arm_name(link_name: str) -> str | None:
    if link_name == "gripper_link":
        return "arm"
    if link_name.endswith("_gripper_link"):
        prefix = link_name[: -len("_gripper_link")]
        return {"l": "left", "r": "right"}.get(prefix, prefix)
    return None


def describe(name: str, model: str, body: int, client: int,
             home_by_name: Mapping[str, float]) -> Robot:
    """What the world needs to know of a loaded body: its joints, links, limits and arms."""
    joints, links, parents = {}, {}, {}
    limits, efforts, movable = {}, {}, []
    for i in range(pb.getNumJoints(body, physicsClientId=client)):
        info = pb.getJointInfo(body, i, physicsClientId=client)
        joints[info[1].decode()] = i
        links[info[12].decode()] = i
        parents[i] = info[16]
        if info[2] != pb.JOINT_FIXED:
            movable.append(i)
            limits[i] = (info[8], info[9])
            efforts[i] = info[10]

    def ancestors(link: int) -> list[int]:
        path = []
        while link != -1:
            path.append(link)
            link = parents[link]
        return path

    chains: dict[str, tuple[list[int], int]] = {}
    for link_name, index in links.items():
        arm_name = _arm_name(link_name)
        if arm_name is not None:
            path = [j for j in reversed(ancestors(index)) if j in limits]
            chains[arm_name] = (path, index)
    counts: dict[int, int] = {}
    for path, _ in chains.values():
        for j in path:
            counts[j] = counts.get(j, 0) + 1
    on_paths = {j for path, _ in chains.values() for j in path}
    arms = {}
    for arm_name, (path, gripper) in chains.items():
        own = tuple(j for j in path if counts[j] == 1)
        fingers = tuple(j for j in movable if j not in on_paths and own
                        and own[-1] in ancestors(j)[1:])
        arms[arm_name] = Arm(arm_name, own, gripper, fingers)
    home = {joints[n]: v for n, v in home_by_name.items()}
    return Robot(name, model, body, joints, links, limits, efforts, tuple(movable), arms, home)
