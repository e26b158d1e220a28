"""Physics after a let-go (sim/settling.py): real contact until everything is at rest,
robots and held objects standing still, resting objects asleep but knocked when hit;
and the stack perception's facts following the objects when they move."""

from __future__ import annotations

import math

import pytest

from shary.facts.database import FactDatabase
from shary.kernel.loop import EventLoop
from sim.objects import new_object
from sim.settling import held_still
from sim.simulation import SETTLE_SECONDS, Simulation
from sim.stack.world import StackPerception
from sim.world import LivingRoom, pb

CUBE = 0.05


@pytest.fixture
def sim():
    """The PR2 at the coffee table, and four cubes on the table's far side."""
    with LivingRoom(robot=None) as world:
        world.add_robot("pr2", "pr2like", "coffee-area")
        top = world.top("coffee-table")
        for i, name in enumerate(["a", "b", "c", "d"]):
            spec = {"shape": "box", "size": [CUBE] * 3, "colour": "red"}
            if name == "d":
                spec["mass"] = 2.0  # a heavy one, to knock others over
            world.add_object(new_object(name, spec), -0.3 + 0.2 * i, 0.15, top)
        yield Simulation(world, EventLoop(), "pr2")


def _resting_z(sim: Simulation) -> float:
    return sim.world.top("coffee-table") + CUBE / 2


def test_a_cube_let_go_just_above_the_table_rests_and_stepping_stops_early(sim):
    top = sim.world.top("coffee-table")
    sim.settle("a", at=(-0.3, 0.15, top + CUBE / 2 + 0.003))
    assert 0 < sim.physics_steps < round(SETTLE_SECONDS * 240) / 4
    assert sim.world.position("a")[2] == pytest.approx(_resting_z(sim), abs=0.002)


def test_a_cube_let_go_from_high_up_falls_all_the_way_before_stepping_stops(sim):
    sim.settle("a", at=(-0.3, 0.15, sim.world.top("coffee-table") + 0.3))
    assert sim.physics_steps > 0.24 * 240  # falling 0.3 m takes about a quarter second
    assert sim.world.position("a")[2] == pytest.approx(_resting_z(sim), abs=0.002)


def test_an_outstretched_arm_does_not_sag_while_an_object_settles(sim):
    world = sim.world
    pr2 = world.robot("pr2")
    world.set_joints("pr2", {pr2.joint("r_shoulder_pan_joint"): 0.0,
                             pr2.joint("r_shoulder_lift_joint"): 0.0,
                             pr2.joint("r_upper_arm_roll_joint"): 0.0,
                             pr2.joint("r_elbow_flex_joint"): -0.2})
    before = world.gripper("pr2")
    sim.settle("a", at=(-0.3, 0.15, world.top("coffee-table") + 0.3))
    assert math.dist(before, world.gripper("pr2")) < 1e-4


def test_an_object_held_stays_in_the_hand_while_another_settles(sim):
    sim.attach("b", "pr2")
    before = sim.world.position("b")
    sim.settle("a", at=(-0.3, 0.15, sim.world.top("coffee-table") + 0.3))
    assert math.dist(before, sim.world.position("b")) < 1e-6


def test_an_object_let_go_leaves_the_hand_where_the_hand_is_now(sim):
    world = sim.world
    pr2 = world.robot("pr2")
    sim.attach("a", "pr2")  # in the tucked hand, beside the table
    world.set_joints("pr2", {pr2.joint("r_shoulder_pan_joint"): 0.0,  # over the table now,
                             pr2.joint("r_shoulder_lift_joint"): 0.0,  # and no tick has
                             pr2.joint("r_upper_arm_roll_joint"): 0.0,  # carried the cube
                             pr2.joint("r_elbow_flex_joint"): -0.2})
    hand = world.gripper("pr2")
    sim.settle("a")
    x, y, z = world.position("a")
    assert math.dist((x, y), hand[:2]) < 0.03
    assert z == pytest.approx(_resting_z(sim), abs=0.003)  # on the table, not the floor


def test_masses_and_motors_are_back_after_settling(sim):
    world = sim.world
    body = world.body("pr2")
    links = range(-1, world.call(pb.getNumJoints, body))
    before = [world.call(pb.getDynamicsInfo, body, link) for link in links]
    cube = world.call(pb.getDynamicsInfo, world.body("b"), -1)
    with held_still(world, ["pr2", "b"]):
        assert world.call(pb.getDynamicsInfo, world.body("b"), -1)[0] == 0.0
    assert [world.call(pb.getDynamicsInfo, body, link) for link in links] == before
    assert world.call(pb.getDynamicsInfo, world.body("b"), -1) == cube
    joints = world.joint_positions("pr2")
    world.step(0.5)  # the motors hold the tucked arms as before
    after = world.joint_positions("pr2")
    assert max(abs(joints[j] - after[j]) for j in joints) < 1e-3


def test_a_cube_left_on_a_cube_picked_away_falls_at_the_next_let_go(sim):
    world = sim.world
    top = world.top("coffee-table")
    sim.settle("a", at=(-0.3, 0.15, top + CUBE / 2 + 0.001))
    sim.settle("b", at=(-0.3, 0.15, top + 1.5 * CUBE + 0.002))
    assert world.position("b")[2] == pytest.approx(top + 1.5 * CUBE, abs=0.003)
    sim.attach("a", "pr2")  # picked from under b, which is now in the air
    sim.settle("c")  # a let-go elsewhere on the table
    x, y, z = world.position("b")
    assert z == pytest.approx(_resting_z(sim), abs=0.003)
    assert math.dist((x, y), (-0.3, 0.15)) < 0.05


def test_a_resting_cube_is_knocked_by_a_cube_dropped_on_its_edge(sim):
    world = sim.world
    top = world.top("coffee-table")
    sim.settle("a", at=(-0.3, 0.15, top + CUBE / 2 + 0.001))
    sim.settle("c")  # a second let-go: a is left at rest, and starts this one asleep
    before = world.position("a")
    sim.settle("d", at=(-0.3 + CUBE * 0.6, 0.15, top + 0.4))
    assert math.dist(before, world.position("a")) > 0.01


def test_stack_perception_sees_a_cube_put_on_another_and_taken_off(sim):
    world = sim.world
    top = world.top("coffee-table")
    facts = FactDatabase()
    perception = StackPerception(sim, facts)
    perception.start()
    assert not facts.holds("b", "isOn", "a")
    world.call(pb.resetBasePositionAndOrientation, world.body("b"),
               [-0.3, 0.15, top + 1.5 * CUBE + 0.001], [0, 0, 0, 1])
    perception.update()
    assert facts.holds("b", "isOn", "a")
    perception.update()  # nothing moved: the same facts
    assert facts.holds("b", "isOn", "a")
    world.call(pb.resetBasePositionAndOrientation, world.body("b"),
               [-0.1, 0.15, top + CUBE / 2 + 0.001], [0, 0, 0, 1])
    for _ in range(10):  # a fact that disappears is removed after the hold time
        sim.loop.advance(0.1)
        perception.update()
    assert not facts.holds("b", "isOn", "a")
    assert facts.holds("b", "isOn", "coffee-table")
