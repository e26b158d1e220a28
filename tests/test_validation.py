"""What ``shary validate`` checks: the meaning of scheme files (each mistake named, placed,
and all reported at once), and which files it checks by default."""

from __future__ import annotations

import textwrap

from conftest import problems


def _messages(shary, path) -> list[tuple[int, int, str]]:
    status, _, err = shary("validate", path)
    assert status == 2, err
    assert "Traceback" not in err
    return [(int(m["line"]), int(m["col"]), m["message"]) for m in problems(err)]


GOOD = """\
    scheme: t
    initial: ask
    states:
      ask:
        act: ASK-TASK
        on: {H-AGREE: done, H-DISAGREE: done}
      done: {final: true}
    """


def test_builtin_files_are_valid(shary):
    status, out, err = shary("validate")
    assert status == 0, err
    assert "give-object.yaml" in out and "acts.yaml" in out


def test_a_builtin_recipe_file_given_by_its_relative_path(shary, monkeypatch):
    """The built-in library is loaded under every recipe file checked; the same file
    named again by a relative path is that file, not a second declaration of its tasks."""
    from shary.io.recipes import builtin_library_files

    files = builtin_library_files()  # in the checkout, or in the installed package
    folder = files[0].parent
    monkeypatch.chdir(folder.parent)
    named = [f"{folder.name}/{f.name}" for f in files]
    status, out, err = shary("validate", *named)
    assert status == 0, err
    assert "declared twice" not in err and f"ok    {named[0]}" in out


def test_builtin_files_come_from_the_file_kinds():
    """``shary validate`` alone checks what each registered kind lists as shipped: the
    engine's kinds and those sim registers by entry point (scenarios, profiles)."""
    from shary.io.filekinds import kinds, shipped_files

    with_files = {kind.name for kind in kinds() if kind.shipped is not None and kind.shipped()}
    assert {"scheme", "recipes", "domain", "problem", "scenario", "profile"} <= with_files
    assert "acts" in {path.stem for path in shipped_files()}


def test_simulated_robot_performs_the_builtin_atomic_tasks():
    """Scenarios are refused when their recipes declare an atomic task beyond the
    built-in ones (sim/scenario.py): that holds while each built-in one has an executor."""
    from shary.io.recipes import load_library
    from sim.executors import RobotExecutors

    for name in set(load_library().atomic) - {"say"}:  # the engine makes a say a speak
        assert callable(getattr(RobotExecutors, "_" + name.replace("-", "_"), None)), name


def test_a_good_file_passes(shary, write):
    status, out, _ = shary("validate", write("good.yaml", GOOD))
    assert status == 0
    assert out.startswith("ok")


def test_unknown_key_with_did_you_mean(shary, write):
    path = write("k.yaml", GOOD.replace("act: ASK-TASK", "act: ASK-TASK\n        initail: x"))
    ((line, col, msg),) = _messages(shary, path)
    assert (line, col) == (6, 5)
    assert "unknown key 'initail'" in msg and "did you mean 'initial'" in msg


def test_a_key_under_the_wrong_parent_is_said_to_be_there(shary, write):
    """An event beside ``on:`` instead of under it, or a state's key at the top level, is
    not a typo of a look-alike key ('done' is not 'on'): the message says where it fits."""
    beside = write("beside.yaml", GOOD.replace("        on: {H-AGREE: done, H-DISAGREE: done}",
                                                "        on: {H-AGREE: done}\n"
                                                "        H-DISAGREE: done"))
    ((line, col, msg),) = _messages(shary, beside)
    assert (line, col) == (7, 5) and "did you mean" not in msg
    assert msg == ("'H-DISAGREE' is not a key here: it reads as an entry of 'on' (indented "
                   "under the wrong parent?)")
    done = write("done.yaml", GOOD.replace("H-DISAGREE: done}", "H-DISAGREE: done}\n"
                                           "        done: ask"))
    ((_, _, msg),) = _messages(shary, done)
    assert "did you mean 'on'" not in msg and "an entry of 'on'" in msg
    top = write("top.yaml", GOOD + "final: true\n")
    ((line, col, msg),) = _messages(shary, top)
    assert (line, col) == (8, 1)
    assert msg == ("'final' is not a key here: it is a key of a state (indented under the "
                   "wrong parent?)")


def test_unknown_act_and_act_word(shary, write):
    path = write("a.yaml", GOOD.replace("ASK-TASK", "ASK-TASKS").replace("H-AGREE", "H-AGRE"))
    found = _messages(shary, path)
    assert any("unknown act 'ASK-TASKS'" in m and "did you mean 'ASK-TASK'" in m
               for _, _, m in found)
    assert any("unknown act 'H-AGRE'" in m and "did you mean 'H-AGREE'" in m
               for _, _, m in found)


def test_dangling_target(shary, write):
    path = write("t.yaml", GOOD.replace("H-DISAGREE: done", "H-DISAGREE: dne"))
    ((line, col, msg),) = _messages(shary, path)
    assert (line, col) == (6, 37)
    assert "unknown target state 'dne'" in msg and "did you mean 'done'" in msg


def test_unreachable_state(shary, write):
    path = write("u.yaml", GOOD + "  lost: {}\n")
    ((line, col, msg),) = _messages(shary, path)
    assert (line, col) == (8, 3)
    assert "'lost' is unreachable" in msg


def test_missing_initial_state(shary, write):
    path = write("i.yaml", GOOD.replace("    initial: ask\n", ""))
    ((line, _, msg),) = _messages(shary, path)
    assert "no 'initial'" in msg and "ask, done" in msg


def test_initial_naming_no_child(shary, write):
    path = write("i2.yaml", GOOD.replace("initial: ask", "initial: asc"))
    found = _messages(shary, path)
    assert any("initial state 'asc' does not exist" in m and "'ask'" in m for _, _, m in found)


def test_two_unguarded_transitions_on_one_event(shary, write):
    path = write("s.yaml", """\
        scheme: t
        initial: a
        states:
          a:
            on:
              go: b
              go.now: c
              other:
                - b
                - c
          b: {}
          c: {}
        """)
    found = _messages(shary, path)
    assert len(found) == 2
    assert "'go.now' is never taken" in found[0][2] and "line 6" in found[0][2]
    assert "'other' is never taken" in found[1][2]


def test_guarded_transitions_on_one_event_are_fine(shary, write):
    # guards must name registered conditions; none is registered in this environment
    path = write("g.yaml", """\
        scheme: t
        initial: a
        states:
          a:
            on:
              go: [{target: b, guard: ready}, c]
          b: {}
          c: {}
        """)
    ((_, _, msg),) = _messages(shary, path)
    assert "unknown condition 'ready'" in msg


def test_all_problems_of_a_file_at_once(shary, write):
    path = write("many.yaml", """\
        scheme: t
        initial: ask
        roles: {robot: robot, partner: human}
        states:
          ask:
            act: ASK-TSK
            by: parner
            on: {H-AGREE: nowhere, after 10: ask}
          ask: {}
          lost: {history: deep}
          orphan: {}
        """)
    messages = " | ".join(m for _, _, m in _messages(shary, path))
    for expected in ("duplicate key 'ask'", "unknown act 'ASK-TSK'", "unknown role 'parner'",
                     "unknown target state 'nowhere'", "'10' is not a duration",
                     "history state belongs", "'orphan' is unreachable"):
        assert expected in messages, messages


def test_schema_errors_read_well(shary, write):
    path = write("types.yaml", """\
        scheme: t
        initial: [a, 3]
        states:
          a: {final: yes, on: {go: {target: a, guard: "x y"}}}
        """)
    found = _messages(shary, path)
    text = " | ".join(m for _, _, m in found)
    assert "expected a string here, got a number (3)" in text
    assert "guard names a registered condition" in text


def test_acts_file_extends_the_acts_of_schemes(shary, write):
    acts = write("acts.yaml", "acts:\n  HAND-OVER: {doc: Hands an object over., "
                 "answers: [AGREE]}\n")
    scheme = write("s.yaml", GOOD.replace("ASK-TASK", "HAND-OVER"))
    assert shary("validate", scheme)[0] == 2
    status, _, err = shary("validate", acts, scheme)
    assert status == 0, err


def test_acts_declared_inside_a_scheme(shary, write):
    path = write("own.yaml", "acts:\n  WAVE: {doc: Waves.}\n"
                 + textwrap.dedent(GOOD).replace("ASK-TASK", "WAVE"))
    assert shary("validate", path)[0] == 0


def test_act_types_are_not_act_names(shary, write):
    ((_, _, msg),) = _messages(shary, write("bad-acts.yaml", "acts:\n  H-AGREE: {}\n"))
    assert "is an act type" in msg


def test_missing_file_is_a_clean_error(shary, tmp_path):
    ((_, _, msg),) = _messages(shary, tmp_path / "absent.yaml")
    assert "cannot read file" in msg


def test_reading_a_scenario_loads_no_physics():
    """Validating a scenario reads the room's data, not the PyBullet world (the imports
    were most of the time of a refusal)."""
    import subprocess
    import sys
    from pathlib import Path

    scenario = Path(__file__).resolve().parents[1] / "sim" / "scenarios" / "give-bottle.yaml"
    code = ("import sys\nfrom shary.cli import main\n"
            f"assert main(['validate', {str(scenario)!r}]) == 0\n"
            "print(sorted(m for m in ('pybullet', 'numpy') if m in sys.modules))\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip().endswith("[]"), done.stdout + done.stderr
