"""The robot binding file: ``shary validate`` checks its shape and meaning, positioned,
and notes interface types that are not installed here without refusing the file."""

from __future__ import annotations

import json

from conftest import problems

from shary.ros.binding import load_binding, shipped_bindings


def test_the_shipped_bindings_are_valid(shary):
    status, out, err = shary("validate", *shipped_bindings())
    assert status == 0, err
    assert out.count("ok") == 2
    # nav2_msgs, tts_msgs and hri_msgs are not on PyPI: named, as notes, not errors
    assert "nav2_msgs/action/NavigateToPose is not installed here" in err
    assert "hri_msgs/msg/LiveSpeech is not installed here" in err
    assert not problems(err)


def test_a_binding_is_loaded_with_its_deadlines_and_templates():
    jido = load_binding(next(p for p in shipped_bindings() if p.name == "jido-sim.yaml"))
    navigate = jido.tasks["navigate"]
    assert (navigate.kind, navigate.name, navigate.type) == (
        "action", "/jido/navigate", "test_msgs/action/NestedMessage")
    assert navigate.deadlines["exec"] == 60 and navigate.deadlines["ack"] == 1
    assert navigate.goal == {"nested_field.int32_value": "{code:place}"}
    assert jido.tasks["speak"].kind == "topic"
    assert jido.codes["coffee-area"] == 2 and not jido.notes


def test_meaning_errors_are_positioned(shary, write):
    path = write("robot.yaml", """\
        binding: bad
        robot: jido
        tasks:
          navigate:
            action: /nav
            type: test_msgs/action/Fibonacci
            goal: {order: "{where}", nothing: 3}
            deadlines: {exec: 3s}
          fly:
            action: /fly
            type: test_msgs/action/Fibonacci
          speak:
            topic: /say
            type: std_msgs/srv/String
            feedback: "{data}"
        facts:
          - topic: /people
            type: std_msgs/msg/String
            facts: [["{item}", type, Human]]
        """)
    status, _, err = shary("validate", path)
    assert status == 2
    found = {(int(m["line"]), int(m["col"])): m["message"] for m in problems(err)}
    assert "'where', which is not a parameter of the task (place)" in found[(7, 19)]
    assert "no goal field 'nothing'" in found[(7, 30)]
    assert "'fly' is not an atomic task" in found[(9, 3)]
    assert "std_msgs/srv/String is not a msg type" in found[(14, 11)]
    assert "a topic has no feedback" in found[(15, 5)]
    assert "needs 'each:'" in found[(19, 14)]
    report = json.loads(_json_line(shary, path))
    assert report["files"][0]["ok"] is False


def test_alive_names_the_binding_s_tasks_and_a_lease(shary, write):
    path = write("robot.yaml", """\
        binding: alive
        robot: jido
        tasks:
          navigate: {action: /nav, type: test_msgs/action/Fibonacci}
        alive:
          - {topic: /nav/alive, type: std_msgs/msg/Empty, lease: 0s, tasks: [navigate, fly]}
          - {topic: /arm/alive, type: std_msgs/msg/Empty, lease: 500ms}
        """)
    status, _, err = shary("validate", path)
    assert status == 2
    found = {(int(m["line"]), int(m["col"])): m["message"] for m in problems(err)}
    assert found == {(6, 58): "a lease must be longer than 0 s",
                     (6, 80): "'fly' is not a task of this binding (navigate)"}
    path.write_text(path.read_text().replace("0s, tasks: [navigate, fly]", "2s"))
    binding = load_binding(path)
    assert [(a.topic, a.lease, a.tasks) for a in binding.alive] == [
        ("/nav/alive", 2.0, ("navigate",)), ("/arm/alive", 0.5, ("navigate",))]


def test_a_schema_error_is_positioned(shary, write):
    path = write("robot.yaml", """\
        binding: bad
        robot: jido
        tasks:
          navigate: {action: /nav, type: test_msgs/action/Fibonacci, deadlines: {exec: forever}}
        """)
    status, _, err = shary("validate", path)
    assert status == 2
    [found] = problems(err)
    assert (found["line"], found["col"]) == ("4", "80") and "a duration" in found["message"]


def test_a_type_that_is_not_installed_is_a_note(shary, write):
    path = write("robot.yaml", """\
        binding: hri
        robot: jido
        tasks:
          speak:
            action: /tts
            type: tts_msgs/action/TTS
            goal: {input: "{text}"}
        """)
    status, out, err = shary("validate", path)
    assert status == 0, err
    assert f"{path}:6:11: note: tts_msgs/action/TTS is not installed here" in err.replace(
        "\n", "")


def _json_line(shary, path) -> str:
    return shary("validate", path, "--json")[1]


def test_a_name_rclpy_would_refuse_is_refused_when_validated(shary, write):
    path = write("robot.yaml", """\
        binding: bad
        robot: jido
        tasks:
          navigate: {action: "/nav//to", type: test_msgs/action/Fibonacci}
        speech:
          - {topic: "/humans/{id}/speech", type: std_msgs/msg/String, text: data}
        """)
    status, _, err = shary("validate", path)
    assert status == 2
    assert [(m["line"], m["col"]) for m in problems(err)] == [("4", "22"), ("6", "13")]


def test_each_task_uses_parts_of_the_robot_by_default_or_as_the_binding_says(write):
    binding = load_binding(write("robot.yaml", """\
        binding: parts
        robot: jido
        tasks:
          navigate: {action: /nav, type: test_msgs/action/Fibonacci}
          look-at: {action: /head, type: test_msgs/action/Fibonacci, resources: [head, base]}
          give: {action: /arm, type: test_msgs/action/Fibonacci}
          speak: {topic: /say, type: std_msgs/msg/String, goal: {data: "{text}"}}
        """))
    assert {name: task.resources for name, task in binding.tasks.items()} == {
        "navigate": ("base",), "look-at": ("head", "base"), "give": ("arm",),
        "speak": ("voice",)}


def test_a_type_an_installed_package_lacks_is_an_error_with_the_closest(shary, write):
    path = write("robot.yaml", """\
        binding: typo
        robot: jido
        tasks:
          navigate:
            action: /nav
            type: test_msgs/action/Fibonaci
          look-at:
            action: /look
            type: std_msgs/action/Look
          speak: {topic: /say, type: std_msgs/msg/Strin}
        """)
    status, _, err = shary("validate", path)
    assert status == 2
    found = {(int(m["line"]), int(m["col"])): m["message"] for m in problems(err)}
    assert found[(6, 11)] == ("test_msgs has no action type 'Fibonaci' (Fibonacci, "
                              "NestedMessage) (did you mean 'Fibonacci'?)")
    assert found[(9, 11)] == "std_msgs has no action type 'Look' (it has no action types)"
    assert found[(10, 30)] == "std_msgs has no msg type 'Strin' (did you mean 'String'?)"


def test_goal_fields_are_checked_against_the_installed_type(shary, write):
    path = write("robot.yaml", """\
        binding: fields
        robot: jido
        tasks:
          navigate:
            action: /nav
            type: test_msgs/action/NestedMessage
            goal:
              nested_field.int32_valu: 3
              nested_field: 4
              nested_field.int64_value: many
        """)
    status, _, err = shary("validate", path)
    assert status == 2
    found = {(int(m["line"]), int(m["col"])): m["message"] for m in problems(err)}
    assert found[(8, 7)] == ("test_msgs/action/NestedMessage has no goal field "
                             "'nested_field.int32_valu' (did you mean 'int32_value'?)")
    assert found[(9, 7)].startswith("nested_field is a message (test_msgs/")
    assert found[(10, 33)] == "'many' is not a int64 (the type of nested_field.int64_value)"
    assert len(found) == 3


def test_shary_ros_warns_of_types_not_installed_as_it_starts(write):
    import subprocess
    import sys

    path = write("robot.yaml", """\
        binding: absent
        robot: jido
        tasks:
          navigate: {action: /nav, type: nav2_msgs/action/NavigateToPose}
        """)
    done = subprocess.run([sys.executable, "-m", "shary", "ros", str(path), "--seconds", "0"],
                          capture_output=True, text=True, timeout=120)
    assert f"{path}:4:34: warning: nav2_msgs/action/NavigateToPose is not installed here" in \
        done.stdout.replace("\n", ""), done.stdout + done.stderr
