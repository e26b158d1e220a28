"""Arm kinematics on a :class:`~sim.world.LivingRoom`: iterated IK and arm placement.

One ``calculateInverseKinematics`` call linearises around the current joint
positions and misses by several centimetres; PyBullet does not iterate to
convergence by itself.  :func:`reach` therefore sets the joints to the answer,
measures where the grasp link really is, and solves again from there, which
gets within a fraction of a millimetre in a few rounds when the point is
reachable.  When it is not, the error stays large, and that error is what tells
a pick executor (and perception's "reachable" facts) that the object is out of
reach.

:func:`reach` is a query: it leaves the arm where it found it unless asked to
keep the solution.  Executors move the arm with :func:`set_arm` (or animate
towards the answer over simulated time).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from .world import LivingRoom, pb

# Damping for joints that must not take part in a solution (another arm's,
# the head's, a torso lift shared by both arms): large enough that the solver
# prefers the arm's own joints.
_FROZEN_DAMPING = 100.0
_ARM_DAMPING = 0.01
IK_ITERATIONS = 20
"""PyBullet's own iterations in one IK call.  Its answer is only a step of :func:`reach`,
which measures where the grasp link really is and solves again; 100 iterations cost
three times as much and reach the target in as many of those rounds (stack-nominal:
40 IK calls either way, 7.6 ms against 24.5 ms of CPU)."""


def _angle_between(q1: Sequence[float], q2: Sequence[float]) -> float:
    dot = abs(float(np.dot(q1, q2)))
    return 2.0 * math.acos(min(1.0, dot))


def reach(world: LivingRoom, robot: str, target_xyz: Sequence[float],
          target_orientation: Sequence[float] | None = None, tolerance: float = 0.005,
          max_iterations: int = 20, arm: str | None = None, keep: bool = False,
          angle_tolerance: float = 0.02, restarts: int = 3,
          ) -> tuple[tuple[float, ...], float]:
    """Joint positions that bring a gripper link to ``target_xyz``, and the distance left.

    ``target_orientation`` is a world quaternion (x, y, z, w) for the grasp
    link, or None to let the wrist turn freely.  Each round solves IK from the
    best configuration so far (once with PyBullet's joint-limit null space,
    once without), clips the answers to the joint limits, applies them and
    measures where the grasp link really is.  The search stops when the grasp
    link is within ``tolerance`` metres (and, with an orientation, within
    ``angle_tolerance`` radians), after ``max_iterations`` rounds, or when
    rounds stop improving.  If the start configuration leads nowhere, up to
    ``restarts`` further starts are tried (straight up, then pseudo-random
    configurations from a fixed seed), so the answer is the same on every run.

    Returns ``(joint_positions, error_m)``: the arm's joint positions, root to
    tip, of the best configuration found, always within the joint limits, and
    the distance in metres from its grasp link to the target.  The arm is put
    back where it was unless ``keep`` is true.
    """
    r = world.robot(robot)
    a = r.arm(arm)
    target = np.asarray(target_xyz, dtype=float)
    arm_joints = list(a.joints)
    dof_index = {j: i for i, j in enumerate(r.movable)}
    lower = np.array([r.limits[j][0] for j in arm_joints])
    upper = np.array([r.limits[j][1] for j in arm_joints])
    damping = [_ARM_DAMPING if j in a.joints else _FROZEN_DAMPING for j in r.movable]
    start = world.joint_positions(robot)
    start_arm = np.array([start[j] for j in arm_joints])
    all_lower = [r.limits[j][0] for j in r.movable]
    all_upper = [r.limits[j][1] for j in r.movable]
    all_ranges = [hi - lo for lo, hi in zip(all_lower, all_upper, strict=True)]
    orientation = {} if target_orientation is None else {
        "targetOrientation": list(target_orientation)}

    def place(q: np.ndarray) -> None:
        for j, value in zip(arm_joints, q, strict=True):
            world.call(pb.resetJointState, r.body, j, float(value), 0.0)

    def errors() -> tuple[float, float]:
        pos, orn = world.link_pose(robot, a.gripper_link)
        dist = float(np.linalg.norm(np.asarray(pos) - target))
        angle = 0.0 if target_orientation is None else _angle_between(orn, target_orientation)
        return dist, angle

    def good(dist: float, angle: float) -> bool:
        return dist <= tolerance and (target_orientation is None or angle <= angle_tolerance)

    def solve(with_limits: bool) -> np.ndarray:
        """One IK call from the current joints; the arm's answer, clipped to its limits."""
        options: dict = dict(orientation, jointDamping=damping, maxNumIterations=IK_ITERATIONS,
                             residualThreshold=1e-6)
        if with_limits:
            current = world.joint_positions(robot)
            options.update(lowerLimits=all_lower, upperLimits=all_upper,
                           jointRanges=all_ranges, restPoses=[current[j] for j in r.movable])
        solution = world.call(pb.calculateInverseKinematics, r.body, a.gripper_link,
                              target.tolist(), **options)
        return np.clip([solution[dof_index[j]] for j in arm_joints], lower, upper)

    def score(dist: float, angle: float) -> float:
        return dist + 0.1 * angle

    def descend(q0: np.ndarray) -> tuple[np.ndarray, float, float]:
        place(q0)
        best_q, (best_d, best_a) = q0, errors()
        stale = 0
        for _ in range(max_iterations):
            if good(best_d, best_a):
                break
            improved = False
            for with_limits in (True, False):
                q = solve(with_limits)
                place(q)
                d, ang = errors()
                if score(d, ang) < score(best_d, best_a) - 1e-6:
                    best_q, best_d, best_a, improved = q, d, ang, True
                place(best_q)
                if good(best_d, best_a):
                    break
            stale = 0 if improved else stale + 1
            if stale >= 2:
                break
        return best_q, best_d, best_a

    # PyBullet's solver with joint limits (null-space) keeps answers inside the
    # limits but crawls, or stalls, on some arms; without limits it often lands
    # in one call but may leave the limits, where clipping spoils the answer.
    # Each round tries both from the best configuration so far.  If that
    # stalls, other starts are tried.
    rng = np.random.default_rng(0)
    starts = [start_arm, np.zeros(len(arm_joints))]
    starts += [rng.uniform(lower, upper) * 0.8 for _ in range(max(0, restarts - 1))]
    best: tuple[np.ndarray, float, float] | None = None
    for q0 in starts[: 1 + max(0, restarts)]:
        q, d, ang = descend(np.clip(q0, lower, upper))
        if best is None or score(d, ang) < score(best[1], best[2]):
            best = (q, d, ang)
        if good(d, ang):
            break
    assert best is not None
    q, d, _ = best
    if keep:
        set_arm(world, robot, q, arm=a.name)
    else:
        place(start_arm)
    return tuple(float(v) for v in q), d


def set_arm(world: LivingRoom, robot: str,
            joint_positions: Sequence[float] | Mapping[str, float],
            arm: str | None = None) -> None:
    """Put an arm's joints at the given positions and make the motors hold them.

    ``joint_positions`` is either the arm's positions root to tip (as
    :func:`reach` returns them) or a mapping from joint name to position.
    Values outside a joint's limits are refused rather than clipped, since a
    caller asking for them has a bug.
    """
    r = world.robot(robot)
    a = r.arm(arm)
    if isinstance(joint_positions, Mapping):
        positions = {r.joint(name): float(v) for name, v in joint_positions.items()}
    else:
        values = list(joint_positions)
        if len(values) != len(a.joints):
            raise ValueError(f"arm {a.name!r} of {robot!r} has {len(a.joints)} joints, "
                             f"got {len(values)} positions")
        positions = {j: float(v) for j, v in zip(a.joints, values, strict=True)}
    for j, v in positions.items():
        lo, hi = r.limits[j]
        if not lo - 1e-9 <= v <= hi + 1e-9:
            raise ValueError(f"joint {j} of {robot!r}: {v:.4f} outside [{lo:.4f}, {hi:.4f}]")
    world.set_joints(robot, positions)


def set_gripper(world: LivingRoom, robot: str, opening: float, arm: str | None = None) -> None:
    """Set each finger of a gripper to ``opening`` metres (0 closed, clipped to limits)."""
    r = world.robot(robot)
    a = r.arm(arm)
    world.set_joints(robot, {j: min(max(opening, r.limits[j][0]), r.limits[j][1])
                             for j in a.fingers})
