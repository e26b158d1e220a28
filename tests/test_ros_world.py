"""A scenario with the robot reached only through ROS 2: ``shary world --ros SCENARIO``
in one process (the PyBullet living room serving the Jido binding), ``shary run SCENARIO
--ros`` in another (the supervisor), judged with the scenario's own expectations.  Each
scenario takes its simulated duration in wall time (25-35 s each: give-bottle, the same
with the goal cancelled and resumed, clean-up-unreachable, and stack-nominal, whose
partner follows the supervisor's shared plan as ``/shary/plan`` tells it)."""

from __future__ import annotations

import json
import signal
import time

import pytest
from rosfixtures import needs_ros

from shary.log.contextlog import read_events


def over_ros(spawn, tmp_path, scenario: str) -> dict:
    world = spawn("-m", "shary", "world", "--ros", scenario, "--quiet")
    run = spawn("-m", "shary", "run", scenario, "--ros", "--out", str(tmp_path / "run"),
                "--quiet")
    status = run.popen.wait(200)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert status == (0 if summary["passed"] else 1), run.lines
    # served to the end, and that one run only: it stops once the supervisor has left
    assert world.popen.wait(30) == 0, world.lines
    assert world.lines[-2:] == [
        f"the supervisor left: this world served its run (for another, start 'shary world "
        f"--ros {scenario}' again)", "the world stopped"], world.lines
    return summary


@needs_ros
@pytest.mark.parametrize("scenario", ["give-bottle", "give-bottle-distracted",
                                      "clean-up-unreachable", "stack-nominal"])
def test_a_scenario_passes_with_its_world_in_another_process(spawn, tmp_path, scenario):
    summary = over_ros(spawn, tmp_path, scenario)
    assert summary["differences"] == []
    assert summary["passed"] and summary["over"] == "ros2"
    rows = [(e.kind, e.data) for e in read_events(tmp_path / "run" / "log.sqlite")]
    assert any(kind == "ros-goal" and data["interface"] == "/jido/give"
               and data["outcome"] == "succeeded" for kind, data in rows) \
        or scenario in ("clean-up-unreachable", "stack-nominal")
    cancels = [data["action"] for kind, data in rows
               if kind == "ros-cancel" and data["state"] == "confirmed"]
    # Alice's phone call stops the arm: its goal is cancelled at the world's server
    assert cancels == (["/jido/move_arm"] if scenario == "give-bottle-distracted" else [])


@needs_ros
def test_a_world_killed_mid_run_fails_the_run_at_once(spawn, tmp_path):
    """The robot's driver dies (SIGKILL) while the robot navigates: its liveliness lapses,
    the goal in flight fails naming the node, and the run ends failed, saying why,
    instead of waiting for the scenario's timeout (its servers would look ready for
    20 s more)."""
    world = spawn("-m", "shary", "world", "--ros", "give-bottle")
    run = spawn("-m", "shary", "run", "give-bottle", "--ros", "--out", str(tmp_path / "run"),
                "--json")
    end = time.monotonic() + 120
    while not any("navigate coffee-area" in line for line in world.lines):
        assert time.monotonic() < end and world.popen.poll() is None, world.lines
        time.sleep(0.05)
    world.popen.send_signal(signal.SIGKILL)
    assert run.popen.wait(60) == 1, run.lines
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    gone = "the robot's node /jido_sim is gone (its liveliness on /jido/facts lapsed: lease 1 s)"
    assert summary["outcome"] == "failed"
    assert any(d.startswith(f"{gone}: the run ended at") for d in summary["differences"])
    assert not any("timeout" in d for d in summary["differences"]), summary
    rows = [(e.kind, e.data) for e in read_events(tmp_path / "run" / "log.sqlite")]
    assert ("ros-alive", {"topic": "/jido/facts", "nodes": ["/jido_sim"], "state": "gone",
                          "reason": gone}) in rows
    assert any(kind == "ros-goal" and data["interface"] == "/jido/navigate"
               and data["outcome"] == "node gone" and data["reason"] == f"node gone: {gone}"
               for kind, data in rows), rows


@needs_ros
def test_the_supervisor_says_when_no_robot_answers(spawn, tmp_path):
    run = spawn("-m", "shary", "run", "give-bottle", "--ros", "--wait", "1", "--out",
                str(tmp_path / "run"))
    assert run.popen.wait(60) == 1
    assert any("no simulated robot answered on ROS 2 within 1 s" in line
               and "shary world --ros give-bottle" in line for line in run.lines), run.lines


@pytest.mark.parametrize("command", [["world", "--ros"], ["run", "--ros", "--world"]])
def test_a_team_scenario_is_refused_behind_ros(command, tmp_path, capsys):
    from shary.cli import main

    status = main([command[0], "weld-nominal", *command[1:], *(
        ["--out", str(tmp_path)] if command[0] == "run" else [])])
    assert status == 2
    assert "weld-nominal: a seam-welding scenario runs as a team over Zenoh" in \
        capsys.readouterr().err


def _children(pid: int) -> list[int]:
    path = f"/proc/{pid}/task/{pid}/children"
    with open(path) as f:
        return [int(p) for p in f.read().split()]


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/status") as f:
            return not any(line.startswith("State:") and "Z" in line.split()[1] for line in f)
    except FileNotFoundError:
        return False


def _navigating(log) -> bool:
    try:
        return any(e.data.get("atomic") == "navigate" for e in read_events(log,
                                                                         kind="exec-request"))
    except Exception:  # not written yet
        return False


@needs_ros
@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGINT])
def test_the_world_and_the_supervisor_end_with_their_parent(spawn, tmp_path, how):
    """``shary run --ros --world`` SIGKILLed or interrupted while the robot navigates:
    neither child is left running, and the supervisor stopped safely (its goal in
    flight cancelled at the world's server, the task ended)."""
    run = spawn("-m", "shary", "run", "give-bottle", "--ros", "--world", "--quiet", "--out",
                str(tmp_path / "run"))
    end = time.monotonic() + 120
    while not _navigating(tmp_path / "run" / "log.sqlite"):
        assert time.monotonic() < end and run.popen.poll() is None, run.lines
        time.sleep(0.2)
    children = _children(run.popen.pid)
    assert len(children) == 2
    run.popen.send_signal(how)
    end = time.monotonic() + 60
    while any(_alive(pid) for pid in children):
        assert time.monotonic() < end, f"left running: {children}"
        time.sleep(0.1)
    [stop] = [e.data for e in read_events(tmp_path / "run" / "log.sqlite", kind="ros-stop")]
    assert not stop.get("left") and stop["tasks"]
    assert all(g.endswith(": confirmed") or g.endswith(": ended") for g in stop["goals"])
    assert any(e.data["outcome"] == "cancelled"
               for e in read_events(tmp_path / "run" / "log.sqlite", kind="task-end"))
