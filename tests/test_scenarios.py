"""The scenarios of SHARY section 3 on the simulated Jido, end to end, and their files."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from shary.cli import main
from shary.log.contextlog import read_events
from sim.run import run_scenario
from sim.scenario import builtin_scenarios, load_scenario
from userfiles.errors import FileError

SCENARIOS = sorted(builtin_scenarios())


def test_every_scenario_of_the_issue_is_shipped():
    assert {"give-bottle", "give-bottle-refused", "give-bottle-distracted",
            "give-bottle-abandoned", "clean-up", "clean-up-unreachable",
            "serve-drink-initiative", "explore-new-objects", "give-bottle-noisy"} <= set(SCENARIOS)


STORIES: dict[str, list[tuple[float, str, str, str]]] = {}
"""What each run of the ``runs`` fixture told its console: (t, who, kind, text)."""


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Each built-in scenario run once, with its files, shared by the tests below."""
    out = tmp_path_factory.mktemp("runs")
    found = {}
    for name in SCENARIOS:
        story = STORIES[name] = []
        found[name] = (run_scenario(builtin_scenarios()[name], out=out / name,
                                    report=lambda *line, story=story: story.append(line)),
                       out / name)
    return found


def _told(name, kind, who=None):
    return [text for _, w, k, text in STORIES[name] if k == kind and who in (None, w)]


def test_the_console_tells_the_new_plan_after_a_failure(runs):
    plans = _told("clean-up-unreachable", "plan")
    assert any(p.startswith("plan, 4 actions") for p in plans)
    assert any(p.startswith("new plan, 5 actions, since 2-pick failed") for p in plans)
    # the new plan's streams, one line per agent: Alice picks and gives, Jido dumps
    assert any("Pick(yellow-bottle" in p and "Give(jido" in p
               for p in _told("clean-up-unreachable", "plan", "alice"))


def test_the_console_tells_what_people_do_and_where_they_look(runs):
    assert "give yellow-bottle to jido" in _told("clean-up-unreachable", "person", "alice")
    assert "place blue-bottle on coffee-table" in _told("explore-new-objects", "person", "bob")
    attention = _told("give-bottle-distracted", "attention", "alice")
    away = next(i for i, text in enumerate(attention) if text.startswith("looks away from jido"))
    assert "looks back at jido" in attention[away + 1:]
    assert not any("looks away" in text for text in _told("give-bottle", "attention"))


def test_end_task_says_what_happened(runs):
    def said(name):
        return _told(name, "speech", "jido")

    assert said("give-bottle")[-1] == "I gave you the yellow bottle."
    assert said("give-bottle-refused")[-1] == "I will not give you the yellow bottle."
    assert "I have finished." not in said("give-bottle-refused")
    assert said("give-bottle-abandoned")[-1].startswith("You are busy, so I will not give you")
    assert said("give-bottle-unanswered")[-1] == ("You did not answer, so I will not give you "
                                                  "the yellow bottle.")
    assert "Thank you for the yellow bottle." in said("clean-up-unreachable")
    assert said("explore-new-objects")[-1] == "I explored the coffee area."


@pytest.mark.parametrize("name", SCENARIOS)
def test_scenario_meets_its_expected_outcome(runs, name):
    result, _ = runs[name]
    assert result.passed, result.differences
    assert result.simulated_seconds > 0


def _events(runs, name, kind=None):
    _, out = runs[name]
    return [e for e in read_events(out / "log.sqlite") if kind is None or e.kind == kind]


def _actions(runs, name):
    """(atomic, status) in order of the results, for the robot."""
    events = _events(runs, name)
    atomic = {e.data["request"]: e.data["atomic"] for e in events if e.kind == "exec-request"}
    return [(atomic[e.data["request"]], e.data["status"]) for e in events
            if e.kind == "exec-result"]


def test_distracted_stops_the_arm_waits_and_resumes_the_motion(runs):
    actions = _actions(runs, "give-bottle-distracted")
    arm = [status for atomic, status in actions if atomic == "move-arm"]
    assert arm == ["cancelled", "done"]  # stopped mid-way, then finished
    acts = [e.data["act"] for e in _events(runs, "give-bottle-distracted", "act")]
    assert acts.index("WAIT-ATTENTION") < acts.index("END-TASK")
    # the resumed motion starts where the arm stopped: together, the two moves take as
    # long as the undisturbed one of give-bottle (at 0.1 s ticks)

    def arm_time(name):
        start = {e.data["request"]: e.time for e in _events(runs, name, "exec-request")
                 if e.data["atomic"] == "move-arm"}
        return sum(e.time - start[e.data["request"]]
                   for e in _events(runs, name, "exec-result") if e.data["request"] in start)

    assert arm_time("give-bottle-distracted") == pytest.approx(arm_time("give-bottle"), abs=0.25)


def test_refused_never_moves(runs):
    actions = {atomic for atomic, _ in _actions(runs, "give-bottle-refused")}
    assert actions <= {"look-at", "speak"}


def test_abandoned_gives_up_after_the_timeout_and_puts_the_bottle_back(runs):
    acts = [(e.time, e.data["act"]) for e in _events(runs, "give-bottle-abandoned", "act")]
    wait = next(t for t, a in acts if a == "WAIT-ATTENTION")
    give_up = next(t for t, a in acts if a == "GIVE-UP")
    assert give_up - wait == pytest.approx(30.0, abs=0.01)
    assert ("put-back", "done") in _actions(runs, "give-bottle-abandoned")


def test_unreachable_pick_fails_with_its_reason_and_the_plan_asks_alice(runs):
    results = [e.data for e in _events(runs, "clean-up-unreachable", "exec-result")]
    assert any(d["status"] == "failed" and "out of reach" in d.get("reason", "")
               for d in results), results
    plans = _events(runs, "clean-up-unreachable", "plan")
    assert any(step.endswith("askhelp") for step in plans[-1].data["steps"])
    speech = [e.data["text"] for e in _events(runs, "clean-up-unreachable", "speech")]
    assert "Can you give me the yellow bottle?" in speech
    # Alice's own stream, as in Fig. 10: she fetches the bottle and hands it over
    alice = [e.data["atomic"] for e in _events(runs, "clean-up-unreachable", "person-action")]
    assert alice == ["walk", "pick", "walk", "give"]
    assert 'data-atomic="pick"' in (runs["clean-up-unreachable"][1] / "timeline.svg").read_text()


def test_initiative_comes_from_the_chronicle_not_a_request(runs):
    goals = _events(runs, "serve-drink-initiative", "goal-added")
    assert [g.data["source"] for g in goals] == ["chronicle:offer-a-drink"]
    assert _events(runs, "serve-drink-initiative", "chronicle")


def test_exploring_changes_what_the_robot_believes_about_the_table(runs):
    events = _events(runs, "explore-new-objects")
    went = next(e.time for e in events if e.kind == "exec-request"
                and e.data["atomic"] == "navigate")
    seen = [e.time for e in events if e.kind == "fact-added"
            and (e.data["s"], e.data["p"], e.data["o"]) == ("blue-bottle", "isOn", "coffee-table")]
    assert seen and min(seen) > went  # Bob's bottle is known only once Jido looked


def test_noise_is_filtered_out(runs):
    result, _ = runs["give-bottle-noisy"]
    assert result.noise_misses > 20  # the detector did miss, often
    flickers = [e for e in _events(runs, "give-bottle-noisy", "fact-removed")
                if e.data["p"] == "looksAt" and e.data["s"] == "alice"]
    assert not flickers  # 20% misses per tick never last the 0.8 s hold


def test_outputs_are_written_and_readable(runs):
    result, out = runs["give-bottle"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["outcome"] == "passed" and summary["real_time_factor"] > 1
    assert summary["simulated_seconds"] == pytest.approx(result.simulated_seconds, abs=0.01)
    for svg in ("tree.svg", "timeline.svg"):
        ET.parse(out / svg)  # well-formed
    assert "alice" in (out / "timeline.svg").read_text()


def test_same_seed_same_run_in_another_process(tmp_path):
    """Same seed, same log, event for event, whatever the process's string hashing."""
    path = builtin_scenarios()["give-bottle-noisy"]
    script = ("import sys; from sim.run import run_scenario; "
              "sys.exit(0 if run_scenario(sys.argv[1], seed=3, out=sys.argv[2]).passed else 1)")
    logs = []
    for hashing in ("1", "2"):
        out = tmp_path / hashing
        subprocess.run([sys.executable, "-c", script, str(path), str(out)], check=True,
                       env={**os.environ, "PYTHONHASHSEED": hashing})
        logs.append([(e.time, e.kind, e.task, e.agent, e.data)
                     for e in read_events(out / "log.sqlite")])
    assert logs[0] == logs[1]


def test_snapshots_are_large_captioned_pngs_framing_robot_and_partner(tmp_path):
    from sim.png import CAPTION_BACKGROUND, read_png
    from sim.run import SNAPSHOT_SIZE

    result = run_scenario(builtin_scenarios()["give-bottle-refused"], out=tmp_path,
                          snapshots=True)
    shots = sorted(tmp_path.glob("snapshot-*.png"))
    assert len(shots) >= 3 and shots[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert result.outputs["snapshots"]
    width, height, channels, pixels = read_png(shots[0])
    assert (width, height) == SNAPSHOT_SIZE and width >= 800
    rgb = np.frombuffer(pixels, dtype=np.uint8).reshape(height, width, channels)
    band = rgb[-height // 12:]  # the caption strip: dark, with light text on it
    background = (np.abs(band.astype(int) - CAPTION_BACKGROUND).max(axis=2) <= 8).mean()
    ink = (band.min(axis=2) > 150).sum()
    assert background > 0.6 and ink > 200
    # Alice (her blue shirt) is large in the picture, not a few pixels far away
    scene = rgb[:-height // 12].reshape(-1, 3).astype(int)
    shirt = (np.abs(scene - (40, 90, 200)).max(axis=1) <= 45).sum()
    assert shirt > 2000


def test_the_framing_camera_keeps_everyone_in_view():
    from sim.world import framing

    camera = framing([(0.0, -1.0, 0.6), (-2.0, 1.5, 1.2)], 4 / 3)
    eye, target = np.array(camera.eye), np.array(camera.target)
    assert target[:2] == pytest.approx([-1.0, 0.25])
    forward = (target - eye) / np.linalg.norm(target - eye)
    for point in [(0.0, -1.0, 0.6), (-2.0, 1.5, 1.2)]:
        to = np.array(point) - eye
        angle = np.degrees(np.arccos(to @ forward / np.linalg.norm(to)))
        assert angle < camera.fov / 2
    # it looks across the line from the robot to the partner, not along it
    line = np.array([-2.0, 2.5]) / np.linalg.norm([-2.0, 2.5])
    assert abs(forward[:2] @ line) < 1e-6


def test_a_failed_expectation_says_what_differed_and_exits_1(tmp_path, capsys):
    text = builtin_scenarios()["give-bottle-refused"].read_text()
    bad = tmp_path / "wrong.yaml"
    bad.write_text(text.replace("no-acts: [REALIZE-TASK, GIVE-UP]",
                                "no-acts: [GIVE-UP]\n  actions: [give]"))
    assert main(["run", str(bad), "--out", str(tmp_path / "o"), "--quiet"]) == 1
    out = capsys.readouterr().out
    assert "FAILED" in out and "expected the action give done" in out


BAD = """\
scenario: bad
robot: {name: jido, at: kitchen}
people:
  alice: {at: sofa-seat, profile: grumpy}
objects:
  purple-bottle: {on: coffee-table}
goals:
  - {task: give-objekt, with: {object: yellow-bottle}}
expect:
  acts: [ASK-TASKS]
  actions: [fly]
"""


def test_bad_scenarios_are_refused_with_every_position(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text(BAD)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    for line, col, words in [(2, 25, "unknown place 'kitchen'"), (4, 35, "unknown profile"),
                             (6, 3, "unknown object 'purple-bottle'"),
                             (8, 12, "did you mean 'give-object'"), (10, 10, "ASK-TASKS"),
                             (11, 13, "unknown atomic task 'fly'")]:
        assert f"{path}:{line}:{col}: error:" in err and words in err, (line, err)
    assert "Traceback" not in err


def test_schema_errors_are_positioned(tmp_path):
    path = tmp_path / "typo.yaml"
    path.write_text("scenario: typo\nexpect: {}\ntimout: 10s\n")
    with pytest.raises(FileError) as info:
        load_scenario(path)
    assert "typo.yaml:3:1: error: unknown key 'timout' (did you mean 'timeout'?)" in str(
        info.value)


def test_shary_scenarios_lists_them(capsys):
    assert main(["scenarios"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in SCENARIOS)


def test_unknown_scenario_names_the_choices(capsys):
    assert main(["run", "give-botle"]) == 2
    assert "did you mean 'give-bottle'" in capsys.readouterr().err


def test_scenario_files_ship_with_the_package():
    assert all(Path(p).is_file() for p in builtin_scenarios().values())


def test_the_pr2_like_robot_runs_the_same_scenario(tmp_path):
    text = builtin_scenarios()["give-bottle"].read_text()
    path = tmp_path / "pr2.yaml"
    path.write_text(text.replace("robot: {name: jido, at: base}",
                                 "robot: {name: jido, model: pr2like, at: base}"))
    result = run_scenario(path)
    assert result.passed, result.differences


def test_the_tutorial_scenario_runs():
    tutorial = Path(__file__).resolve().parent.parent / "docs" / "tutorial" / "tidy-table.yaml"
    result = run_scenario(tutorial)
    assert result.passed, result.differences


def test_the_tutorial_shows_what_its_run_prints(tmp_path, capsys):
    """docs/tutorial.md's sample output is the run's, line for line (the INTERACT session
    included), up to the wall time."""
    docs = Path(__file__).resolve().parent.parent / "docs"
    text = (docs / "tutorial.md").read_text(encoding="utf-8")
    sample = text[text.index("## 4. Run it"):].split("```")[3]
    assert main(["run", str(docs / "tutorial" / "tidy-table.yaml"), "--out",
                 str(tmp_path)]) == 0
    printed = capsys.readouterr().out

    def story(output: str) -> list[str]:
        return [line.rstrip() for line in output.splitlines() if line[:9].strip()
                .endswith("s") and line[:9].strip()[:-1].replace(".", "").isdigit()]

    assert story(sample) == story(printed) and "[INTERACT] session" in sample
    assert sample.splitlines()[-2].split(" in ")[0] == printed.splitlines()[-2].split(" in ")[0]


def test_an_injected_fault_is_recovered_from(tmp_path):
    text = builtin_scenarios()["give-bottle"].read_text()
    path = tmp_path / "slip.yaml"
    path.write_text(text.replace("goals:", "faults:\n  - {action: pick, reason: the bottle "
                                 "slipped}\ngoals:").replace("expect:", "expect:\n  "
                                                            "failed-actions: [pick]"))
    result = run_scenario(path, out=tmp_path / "out")
    assert result.passed, result.differences
    reasons = [e.data.get("reason") for e in read_events(tmp_path / "out" / "log.sqlite")
               if e.kind == "exec-result" and e.data["status"] == "failed"]
    assert reasons == ["the bottle slipped"]


def test_a_person_helps_then_goes_back_to_their_script(tmp_path):
    text = builtin_scenarios()["clean-up-unreachable"].read_text()
    path = tmp_path / "busy.yaml"
    path.write_text(text.replace(
        "alice: {at: sofa-seat, profile: cooperative}",
        "alice:\n    at: sofa-seat\n    profile:\n      answers: {ASK-HELP: {reply: H-AGREE}}"
        "\n      script:\n        - {at: 3s, walk: corridor}\n        - {walk: door}"))
    result = run_scenario(path)
    assert result.passed, result.differences  # helped, and the run did not hang


def test_bad_profile_names_are_refused(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("scenario: p\npeople:\n  alice:\n    at: sofa-seat\n    profile:\n"
                    "      attention: nobody\n      answers: {ASK-TAKS: {reply: H-AGRE}}\n"
                    "expect: {}\n")
    assert main(["run", str(path)]) == 2


def test_bare_numbers_and_spaces_are_durations(tmp_path):
    text = builtin_scenarios()["give-bottle-refused"].read_text()
    path = tmp_path / "n.yaml"
    path.write_text(text.replace("within: 20s", "within: 20").replace(
        "goals:", 'timeout: "60 s"\ngoals:'))
    assert run_scenario(path).passed


def test_shary_validate_checks_scenarios_and_profiles(tmp_path, capsys):
    profile = tmp_path / "p.yaml"
    profile.write_text("profile: p\nanswers: {ASK-TAKS: {reply: H-AGREE}}\n")
    assert main(["validate", str(profile), str(builtin_scenarios()["give-bottle"])]) == 2
    captured = capsys.readouterr()
    assert f"{profile}:2:11: error: unknown act 'ASK-TAKS'" in captured.err
    assert "ok    " in captured.out and "give-bottle.yaml" in captured.out


OBJECTS_HEAD = """\
scenario: objects
robot: {name: jido, at: base}
people:
  alice: {at: sofa-seat}
goals:
  - {task: give-object, with: {object: red-cup, partner: alice}}
expect: {tasks: {give-object: done}}
objects:
"""


@pytest.mark.parametrize("entry, at, message", [
    ("  red-cup: {shape: cylinder, colour: red, size: [0.07, 0.1], on: kitchen-table}",
     "kitchen-table", r"unknown furniture 'kitchen-table'"),
    ("  yellow-bottle: {shape: box, colour: red, size: [0.1, 0.1, 0.1]}",
     "yellow-bottle", r"'yellow-bottle' already names something in the room"),
    ("  sofa: {shape: sphere, colour: red, size: [0.1]}", "sofa", r"'sofa' already names"),
    ("  red-cup: {shape: cylinder, colour: red, size: [0.07, 2.5]}",
     "2.5", r"the height must be from 0.02 to 0.6 m, not 2.5"),
    ("  red-cup: {shape: cylinder, colour: red, size: [.nan, 0.1]}",
     ".nan", r"'\.nan' is not a finite number"),
    ("  red-cup: {shape: cylinder, colour: red, size: [0.07, 0.1, 0.2]}",
     "[0.07", r"a cylinder's size is \[diameter, height\] in metres: 2 numbers, not 3"),
    ("  red-cup: {shape: cylinder, colour: mauve, size: [0.07, 0.1]}",
     "mauve", r"unknown colour 'mauve'"),
    ("  red-cup: {shape: cylinder, colour: [1, 0, 3], size: [0.07, 0.1]}",
     "3]", r"the colour component must be from 0 to 1, not 3"),
    ("  red-cup: {shape: cylinder, colour: red, size: [0.07, 0.1], mass: -1}",
     "-1", r"the mass must be from 0.01 to 5 kg, not -1"),
    ("  red-cup: {shape: pyramid, colour: red, size: [0.07, 0.1]}",
     "pyramid", r"'pyramid' is not one of: box, cylinder, sphere"),
    ("  red-cup: {colour: red, size: [0.07, 0.1]}", "red-cup",
     r"'red-cup' is not one of the room's bottles, so it is a new object: it needs a shape"),
    ("  red-cup: {shape: box, colour: red, on: store-table, at: [9, 9]}", "red-cup",
     r"it needs a size"),
])
def test_bad_new_objects_are_refused_where_they_are(tmp_path, entry, at, message):
    from hostile import assert_refused, run_inprocess

    path = tmp_path / "objects.yaml"
    path.write_text(OBJECTS_HEAD + entry + "\n")
    outcome = run_inprocess("run", path, "--out", tmp_path / "out")
    assert_refused(outcome, path, message=message)
    line = OBJECTS_HEAD.count("\n") + 1
    assert f"{path}:{line}:{entry.index(at) + 1}: error:" in outcome.err, outcome.err


def test_a_new_object_is_built_seen_and_handed_over(runs):
    result, out = runs["give-red-cup"]
    assert result.passed, result.differences
    said = _told("give-red-cup", "speech", "jido")
    assert "I gave you the cup." in said  # the only cup on the scene: no colour needed
    failed = _told("give-red-cup", "failed", "jido")
    assert any("wooden-box is too big to grasp: 15 cm wide, the gripper opens to 8 cm" in f
               for f in failed)


def _tutorial_with_profile(folder: Path, profile: str) -> Path:
    """The tutorial's scenario copied into ``folder``, Alice with ``profile``."""
    import shutil

    shutil.copytree(Path(__file__).resolve().parent.parent / "docs" / "tutorial", folder)
    scenario = folder / "tidy-table.yaml"
    scenario.write_text(scenario.read_text(encoding="utf-8").replace(
        "profile: cooperative", f"profile: {profile}"), encoding="utf-8")
    return scenario


def test_a_scenario_names_a_profile_file_of_its_own(tmp_path, shary):
    """``profile: my-partner.yaml`` is a file below the scenario's folder, as ``recipes:``
    files are: read, checked, run with."""
    scenario = _tutorial_with_profile(tmp_path / "mine", "people/my-partner.yaml")
    (tmp_path / "mine" / "people").mkdir()
    (tmp_path / "mine" / "people" / "my-partner.yaml").write_text(
        "profile: my-partner\ndoc: Agrees at once.\n"
        "answers:\n  ASK-TASK: {reply: H-AGREE, after: 0.5s}\nattention: robot\n",
        encoding="utf-8")
    assert shary("validate", scenario)[0] == 0
    loaded = load_scenario(scenario)
    assert loaded.people[0].profile.answers["ASK-TASK"][0].reply == "H-AGREE"
    assert run_scenario(scenario).passed


def test_a_scenarios_profile_file_is_confined_and_checked(tmp_path, shary):
    outside = tmp_path / "elsewhere.yaml"
    outside.write_text("profile: x\ndoc: x.\n", encoding="utf-8")
    scenario = _tutorial_with_profile(tmp_path / "mine", "../elsewhere.yaml")
    status, _, err = shary("validate", scenario)
    assert status == 2 and "'../elsewhere.yaml' is outside the folder of tidy-table.yaml" in err
    scenario = _tutorial_with_profile(tmp_path / "bad", "bad.yaml")
    (tmp_path / "bad" / "bad.yaml").write_text("profile: bad\ndoc: x.\nanswers:\n"
                                               "  ASK-TASSK: {reply: H-AGREE}\n",
                                               encoding="utf-8")
    status, _, err = shary("validate", scenario)
    assert status == 2
    assert "bad.yaml:4:3: error: unknown act 'ASK-TASSK' (did you mean 'ASK-TASK'?)" in err
    assert "tidy-table.yaml:6:35: error: depends on" in err and "bad.yaml, which has errors" in err


def test_files_given_together_are_checked_as_one_set(write, shary):
    """A profile answering an act that a scheme declares is checked with that scheme."""
    scheme = write("offer.yaml", """\
        scheme: offer
        acts:
          OFFER: {doc: Offers something., answers: [AGREE, DISAGREE]}
        initial: offer
        states:
          offer:
            act: OFFER
            on: {H-AGREE: end, H-DISAGREE: end}
          end: {act: END-TASK, final: true}
        """)
    profile = write("taker.yaml", """\
        profile: taker
        doc: Takes every offer.
        answers:
          OFFER: {reply: H-AGREE, after: 1s}
        """)
    status, out, err = shary("validate", scheme, profile)
    assert status == 0, err
    status, _, err = shary("validate", profile)
    assert status == 2
    assert "unknown act 'OFFER' (declared by a scheme or acts file of yours? check them " \
           "together: shary validate SCHEME.yaml PROFILE.yaml)" in err


def test_run_and_serve_say_when_they_replace_an_earlier_run(tmp_path, shary, monkeypatch):
    """Both write runs/SCENARIO by default, the latest run of a scenario in one known
    place; both say so before an earlier run's files there are replaced."""
    out = tmp_path / "refused"
    status, first, _ = shary("run", "give-bottle-refused", "--out", out)
    assert status == 0 and "earlier run" not in first
    status, again, _ = shary("run", "give-bottle-refused", "--out", out)
    assert status == 0
    assert again.splitlines()[0].startswith(f"{out}/ holds an earlier run (of ")
    assert again.splitlines()[0].endswith("this run replaces its files (--out DIR keeps "
                                          "runs apart)")
    assert shary("run", "give-bottle-refused", "--out", out, "--json")[1].find(
        '"replaced_earlier_run": true') > 0

    served = []
    monkeypatch.setattr("shary.console.server.serve",
                        lambda live, host, port: served.append(live.folder) or 0)
    status, said, _ = shary("serve", "give-bottle-refused", "--out", out)
    assert status == 0 and served == [out]
    assert said.startswith(f"{out}/ holds an earlier run (of ")
