"""``shary ros BINDING``: a bad binding is refused with positioned errors; the node runs
until Ctrl-C and then stops cleanly (no traceback, exit 0)."""

from __future__ import annotations

import signal

import pytest
from conftest import problems
from rosfixtures import needs_ros

BINDING = "shary/ros/bindings/jido-sim.yaml"


def test_a_bad_binding_is_refused_with_its_position(shary, write):
    path = write("bad.yaml", "binding: bad\nrobot: jido\ntasks:\n  fly: {topic: /f, type: x}\n")
    status, _, err = shary("ros", path)
    assert status == 2
    assert [(m["line"], m["col"]) for m in problems(err)] == [("4", "26")]


@needs_ros
def test_the_node_stops_cleanly_on_ctrl_c(spawn):
    process = spawn("-m", "shary", "ros", BINDING)
    process.wait_for("shary is node /shary on robot jido (jido-sim); Ctrl-C stops it")
    process.popen.send_signal(signal.SIGINT)
    assert process.exit_status(20) == 0
    process._reader.join(5)
    assert process.lines[-1] == "shary stopped"
    assert not any("Traceback" in line for line in process.lines)


@needs_ros
def test_the_node_plans_the_recipes_that_need_the_planner(spawn, tmp_path):
    """``shary ros`` carries the planner of every domain its recipes name: a planned
    recipe (fetch) is planned from what the robot knows (here nothing, so no plan),
    instead of failing for want of a planner once the person has said yes."""
    from shary.log.contextlog import read_events

    log = tmp_path / "log.sqlite"
    process = spawn("-m", "shary", "ros", BINDING, "--task", "fetch",
                    "--with", "object=yellow-bottle", "--seconds", "2", "--log", str(log))
    assert process.exit_status(30) == 0
    reasons = [row.data["reason"] for row in read_events(log, kind="recipe-failed")]
    assert reasons and not any("needs a planner" in reason for reason in reasons)
    assert any("plan" in reason for reason in reasons)


@pytest.mark.parametrize("args, said", [
    (["--log", "EXISTING"], "the file exists (the context log is written to a new file"),
    (["--with", "object=bottle"], "--with gives a parameter of --task, which is not given"),
    (["--task", "give-object", "--with", "object=bottle"],
     "--task give-object takes object, partner (--with PARAM=VALUE each); missing: partner"),
    (["--task", "fly"], "no task 'fly' (known: "),
    (["--with", "object"], "--with 'object': write PARAM=VALUE"),
    (["--node-name", "bad name"], "--node-name 'bad name' is not a ROS node name"),
])
def test_every_misuse_is_a_clean_error(shary, tmp_path, args, said):
    existing = tmp_path / "old.sqlite"
    existing.write_text("a log of another run")
    status, out, err = shary("ros", BINDING, *[str(existing) if a == "EXISTING" else a
                                               for a in args])
    assert status == 2
    assert said in " ".join(err.split()) and "Traceback" not in err + out


def test_a_negative_duration_is_refused_by_the_parser():
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "shary", "ros", BINDING, "--seconds", "-1"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "argument --seconds: '-1': a duration is 0 s or more" in done.stderr
