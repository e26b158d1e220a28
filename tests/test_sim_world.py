"""The PyBullet living room: models, scene, kinematics, snapshots, isolation.

All headless (DIRECT), a few seconds for the file: a world builds in tens of
milliseconds, so tests that move things get a fresh one and read-only tests
share one.
"""

from __future__ import annotations

import math
import os
import sys
import xml.etree.ElementTree as ET
from collections import deque

import numpy as np
import pytest

from sim.kinematics import reach, set_arm, set_gripper
from sim.png import SIGNATURE, encode_png, read_png
from sim.quiet import captured, silenced
from sim.robots import MODELS_DIR
from sim.world import BOTTLE_HEIGHT, LivingRoom, pb

FURNITURE = ["coffee-table", "store-table", "trash", "sofa", "chair-1", "chair-2"]
BOTTLES = ["yellow-bottle", "green-bottle", "orange-bottle", "blue-bottle"]


@pytest.fixture(scope="module")
def room():
    """A world shared by the tests that only look."""
    with LivingRoom() as world:
        yield world


@pytest.fixture
def fresh():
    """A world of one's own, for tests that move things."""
    with LivingRoom() as world:
        yield world


# ----------------------------------------------------------------- the models

def _urdf_masses(path) -> dict[str, float]:
    root = ET.parse(path).getroot()
    return {link.get("name"): float(link.find("inertial/mass").get("value"))
            for link in root.findall("link")}


@pytest.mark.parametrize("model", ["jido.urdf", "pr2like.urdf"])
def test_models_load_silently_with_their_own_masses(model):
    path = MODELS_DIR / model
    client = pb.connect(pb.DIRECT)
    try:
        with captured() as out:
            body = pb.loadURDF(str(path), useFixedBase=False,
                               flags=pb.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
        assert body >= 0
        assert "inertial" not in out.text.lower(), out.text
        assert "warning" not in out.text.lower(), out.text
        masses = _urdf_masses(path)
        seen = {pb.getBodyInfo(body, physicsClientId=client)[0].decode():
                pb.getDynamicsInfo(body, -1, physicsClientId=client)[0]}
        for i in range(pb.getNumJoints(body, physicsClientId=client)):
            name = pb.getJointInfo(body, i, physicsClientId=client)[12].decode()
            seen[name] = pb.getDynamicsInfo(body, i, physicsClientId=client)[0]
        assert seen == pytest.approx(masses)
        assert all(m > 0 for m in seen.values())
    finally:
        pb.disconnect(physicsClientId=client)


def test_captured_really_sees_pybullet_warnings(tmp_path):
    """The silence checked above is not an artefact of the capture missing C output."""
    bare = tmp_path / "bare.urdf"
    bare.write_text('<robot name="bare"><link name="a"/><link name="b"/>'
                    '<joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint>'
                    "</robot>")
    client = pb.connect(pb.DIRECT)
    try:
        with captured() as out:
            pb.loadURDF(str(bare), physicsClientId=client)
        assert "No inertial data" in out.text
    finally:
        pb.disconnect(physicsClientId=client)


@pytest.mark.parametrize("model", ["jido.urdf", "pr2like.urdf"])
def test_every_moving_joint_has_limits_effort_and_velocity(model):
    root = ET.parse(MODELS_DIR / model).getroot()
    moving = [j for j in root.findall("joint") if j.get("type") in ("revolute", "prismatic")]
    assert moving
    for joint in moving:
        limit = joint.find("limit")
        assert limit is not None, joint.get("name")
        assert float(limit.get("lower")) < float(limit.get("upper")), joint.get("name")
        assert float(limit.get("effort")) > 0 and float(limit.get("velocity")) > 0


def test_jido_has_a_seven_joint_arm_a_two_finger_gripper_and_a_pan_tilt_head(room):
    jido = room.robot("jido")
    kinds = {i: pb.getJointInfo(jido.body, i, physicsClientId=room.client)[2]
             for i in range(pb.getNumJoints(jido.body, physicsClientId=room.client))}
    assert list(jido.arms) == ["arm"]
    arm = jido.arm()
    assert len(arm.joints) == 7
    assert all(kinds[j] == pb.JOINT_REVOLUTE for j in arm.joints)
    assert len(arm.fingers) == 2
    assert all(kinds[j] == pb.JOINT_PRISMATIC for j in arm.fingers)
    assert kinds[jido.joint("head_pan_joint")] == pb.JOINT_REVOLUTE
    assert kinds[jido.joint("head_tilt_joint")] == pb.JOINT_REVOLUTE
    assert arm.gripper_link == jido.link("gripper_link")
    assert "camera_link" in jido.links
    # nothing else moves: arm, fingers, pan, tilt
    assert sorted(jido.movable) == sorted([*arm.joints, *arm.fingers,
                                           jido.joint("head_pan_joint"),
                                           jido.joint("head_tilt_joint")])


def test_pr2like_has_two_arms_and_a_torso_shared_by_neither():
    with LivingRoom(robot=None) as world:
        pr2 = world.add_robot("pr2", "pr2like", "coffee-area")
        assert set(pr2.arms) == {"left", "right"}
        for side, link in (("left", "l_gripper_link"), ("right", "r_gripper_link")):
            arm = pr2.arm(side)
            assert arm.gripper_link == pr2.link(link)
            assert len(arm.joints) == 7 and len(arm.fingers) == 2
        torso = pr2.joint("torso_lift_joint")
        assert torso not in pr2.arm("left").joints + pr2.arm("right").joints
        assert "camera_link" in pr2.links
        assert world.collisions("pr2") == []
        top = world.top("coffee-table")
        for side in ("left", "right"):
            _, error = reach(world, "pr2", (0.1 if side == "right" else -0.1, -0.2, top + 0.15),
                             arm=side)
            assert error <= 0.005


# ----------------------------------------------------------------- the scene

def test_world_is_headless_and_has_every_named_object(room):
    assert pb.getConnectionInfo(physicsClientId=room.client)["connectionMethod"] == pb.DIRECT
    for name in [*FURNITURE, *BOTTLES, "cupboard", "floor", "jido"]:
        assert room.body(name) >= 0
        assert len(room.position(name)) == 3
    assert sorted(room.bottles) == sorted(BOTTLES)
    with pytest.raises(KeyError, match="no body named 'piano'"):
        room.body("piano")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="X displays are a Linux matter")
def test_gui_without_a_display_is_an_error_not_a_silent_exit(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    with pytest.raises(RuntimeError, match="X display"):
        LivingRoom(gui=True)


def test_bottles_start_on_the_coffee_table(room):
    table = room.footprints["coffee-table"]
    for name in BOTTLES:
        x, y, z = room.position(name)
        assert table.contains(x, y)
        assert z == pytest.approx(room.top("coffee-table") + BOTTLE_HEIGHT / 2, abs=1e-3)


def test_places_are_clear_and_the_roadmap_joins_them_all(fresh):
    assert {"base", "coffee-area", "store-area", "trash-area", "sofa-area"} <= set(fresh.places)
    for place, (x, y, yaw) in fresh.places.items():
        fresh.set_base_pose("jido", x, y, yaw)
        assert fresh.collisions("jido") == [], place
    seen, todo = {"base"}, deque(["base"])
    while todo:
        for other in fresh.roadmap[todo.popleft()]:
            if other not in seen:
                seen.add(other)
                todo.append(other)
    assert seen == set(fresh.places)
    assert "coffee-area" in fresh.roadmap["trash-area"]
    # a straight line through the coffee table is not an edge
    assert not fresh.segment_clear((0.0, -1.2), (0.0, 1.0))


def test_base_pose_round_trips_and_carries_the_arm(fresh):
    before = fresh.link_position("jido", "gripper_link")
    x0, y0, _ = fresh.base_pose("jido")
    fresh.set_base_pose("jido", *fresh.places["coffee-area"])
    assert fresh.base_pose("jido") == pytest.approx(fresh.places["coffee-area"], abs=1e-6)
    assert fresh.position("jido")[2] == pytest.approx(0.0, abs=1e-6)
    after = fresh.link_position("jido", "gripper_link")
    assert after[2] == pytest.approx(before[2], abs=1e-6)   # same height, moved along
    assert math.dist(after[:2], before[:2]) == pytest.approx(math.dist((x0, y0), (0, -0.7)),
                                                             abs=0.5)


def test_bottles_rest_on_the_coffee_table_after_a_second(fresh):
    start = {name: fresh.position(name) for name in BOTTLES}
    assert fresh.step(1.0) == 240
    assert fresh.time == pytest.approx(1.0)
    top = fresh.top("coffee-table")
    for name in BOTTLES:
        x, y, z = fresh.position(name)
        assert math.dist((x, y), start[name][:2]) < 0.005, name
        assert z == pytest.approx(top + BOTTLE_HEIGHT / 2, abs=0.005), name
        _, orn = fresh.pose(name)
        assert abs(orn[3]) == pytest.approx(1.0, abs=1e-3), name   # still upright
        assert "coffee-table" in fresh.collisions(name, margin=0.002)


def test_a_robot_holds_its_arm_while_physics_runs(fresh):
    before = fresh.joint_positions("jido")
    fresh.step(0.5)
    after = fresh.joint_positions("jido")
    assert max(abs(before[j] - after[j]) for j in before) < 1e-3


# ----------------------------------------------------------------- kinematics

def test_reach_gets_the_gripper_within_5_mm_beside_a_bottle(fresh):
    fresh.set_base_pose("jido", *fresh.places["coffee-area"])
    jido = fresh.robot("jido")
    start = fresh.joint_positions("jido")
    x, y, _ = fresh.position("orange-bottle")
    target = (x + 0.08, y, fresh.top("coffee-table") + 0.1)
    joints, error = reach(fresh, "jido", target)
    assert error <= 0.005
    assert len(joints) == 7
    for j, value in zip(jido.arm().joints, joints, strict=True):
        lo, hi = jido.limits[j]
        assert lo <= value <= hi
    assert fresh.joint_positions("jido") == start          # a query: the arm did not move
    set_arm(fresh, "jido", joints)
    assert math.dist(fresh.link_position("jido", "gripper_link"), target) <= 0.005


def test_reach_can_be_tight_and_can_keep_its_answer(fresh):
    fresh.set_base_pose("jido", *fresh.places["coffee-area"])
    x, y, _ = fresh.position("yellow-bottle")
    target = (x, y - 0.09, fresh.top("coffee-table") + 0.12)
    _, error = reach(fresh, "jido", target, tolerance=0.0005, keep=True)
    assert error <= 0.0005
    assert math.dist(fresh.link_position("jido", "gripper_link"), target) <= 0.0005


def test_reach_reports_a_large_error_for_a_point_three_metres_away(fresh):
    fresh.set_base_pose("jido", *fresh.places["coffee-area"])
    bx, by, _ = fresh.base_pose("jido")
    joints, error = reach(fresh, "jido", (bx, by + 3.0, 0.8))
    assert error > 1.5
    jido = fresh.robot("jido")
    for j, value in zip(jido.arm().joints, joints, strict=True):
        lo, hi = jido.limits[j]
        assert lo <= value <= hi


def test_reach_with_an_orientation(fresh):
    fresh.set_base_pose("jido", *fresh.places["coffee-area"])
    down = pb.getQuaternionFromEuler([math.pi, 0, 0])     # grasp axis pointing at the floor
    x, y, _ = fresh.position("green-bottle")
    target = (x, y, fresh.top("coffee-table") + 0.35)
    _, error = reach(fresh, "jido", target, target_orientation=down, keep=True)
    assert error <= 0.005
    _, orn = fresh.link_pose("jido", "gripper_link")
    assert abs(sum(a * b for a, b in zip(orn, down, strict=True))) > math.cos(0.02 / 2)


def test_set_arm_refuses_positions_outside_the_limits_and_wrong_lengths(fresh):
    with pytest.raises(ValueError, match="outside"):
        set_arm(fresh, "jido", [0, 3.0, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="7 joints"):
        set_arm(fresh, "jido", [0, 0, 0])
    set_arm(fresh, "jido", {"arm_joint_4": 1.0})
    assert fresh.joint_positions("jido")[fresh.robot("jido").joint("arm_joint_4")] == 1.0


def test_set_gripper_opens_both_fingers_within_limits(fresh):
    set_gripper(fresh, "jido", 0.03)
    fingers = fresh.robot("jido").arm().fingers
    assert [fresh.joint_positions("jido")[j] for j in fingers] == pytest.approx([0.03, 0.03])
    set_gripper(fresh, "jido", 1.0)
    assert [fresh.joint_positions("jido")[j] for j in fingers] == pytest.approx([0.04, 0.04])


# ----------------------------------------------------------------- images

@pytest.mark.parametrize("camera", ["overview", "jido"])
def test_snapshot_writes_a_png_with_many_colours(room, tmp_path, camera):
    path = room.snapshot(tmp_path / "shots" / f"{camera}.png", camera=camera)
    data = path.read_bytes()
    assert data.startswith(SIGNATURE)
    width, height, channels, pixels = read_png(path)
    assert (width, height, channels) == (320, 240, 3)
    colours = np.unique(np.frombuffer(pixels, dtype=np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > 50


def _count(pixels: bytes, colour, tol=40) -> int:
    rgb = np.frombuffer(pixels, dtype=np.uint8).reshape(-1, 3).astype(int)
    return int((np.abs(rgb - np.array(colour)).max(axis=1) <= tol).sum())


# Nothing else in the room is this yellow, green or blue (orange is also Jido's arm).
YELLOW, GREEN, BLUE = (240, 210, 25), (40, 165, 50), (30, 75, 230)


def test_the_overview_shows_the_bottles(room, tmp_path):
    _, _, _, pixels = read_png(room.snapshot(tmp_path / "o.png", 640, 480))
    assert all(_count(pixels, c) > 10 for c in (YELLOW, GREEN, BLUE))


def test_jido_sees_the_bottles_from_the_coffee_area(fresh):
    fresh.set_base_pose("jido", *fresh.places["coffee-area"])
    pixels = fresh.image(camera="jido")
    assert all(_count(pixels, c) > 100 for c in (YELLOW, GREEN, BLUE))


def test_unknown_camera_names_the_cameras(room, tmp_path):
    with pytest.raises(KeyError, match="overview"):
        room.snapshot(tmp_path / "x.png", camera="ceiling")


def test_png_reader_reads_what_the_writer_wrote(tmp_path):
    pixels = bytes((x * 7 + y * 13 + c * 50) % 256 for y in range(9) for x in range(11)
                   for c in range(3))
    path = tmp_path / "p.png"
    path.write_bytes(encode_png(11, 9, pixels))
    assert read_png(path) == (11, 9, 3, pixels)


# ----------------------------------------------------------------- isolation

def test_two_worlds_do_not_interfere():
    with LivingRoom() as a, LivingRoom() as b:
        assert a.client != b.client
        a.set_base_pose("jido", *a.places["trash-area"])
        assert b.base_pose("jido") == pytest.approx(b.places["base"], abs=1e-6)
        # knock a bottle off the table in a only
        yellow = a.body("yellow-bottle")
        pb.resetBasePositionAndOrientation(yellow, [0.8, -1.0, 1.0], [0, 0, 0, 1],
                                           physicsClientId=a.client)
        a.step(1.0)
        assert a.position("yellow-bottle")[2] < 0.2
        b_yellow = b.position("yellow-bottle")
        b.step(0.5)
        assert b.position("yellow-bottle") == pytest.approx(b_yellow, abs=1e-3)
        assert b.time == pytest.approx(0.5) and a.time == pytest.approx(1.0)
        a.close()
        b.step(0.1)                       # b lives on after a is gone
        assert b.position("yellow-bottle")[2] > 0.5
    a.close()                             # closing twice is harmless


# ----------------------------------------------------------------- quiet

def test_silenced_and_captured_work_at_the_file_descriptor_level(capfd):
    with silenced():
        os.write(1, b"lost stdout\n")
        os.write(2, b"lost stderr\n")
    with captured(stderr=False) as out:
        os.write(1, b"kept\n")
    assert out.text == "kept\n"
    print("after")
    seen = capfd.readouterr()
    assert seen.out == "after\n" and seen.err == ""


def test_building_a_world_prints_nothing(capfd, tmp_path):
    with LivingRoom() as world:
        world.add_robot("pr2", "pr2like", "store-area")
        world.snapshot(tmp_path / "quiet.png")
    seen = capfd.readouterr()
    assert seen.out == "" and seen.err == ""
