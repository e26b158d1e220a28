"""The shary command as a newcomer uses it."""

from __future__ import annotations

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from conftest import REPO, problems

from shary.cli import main


def test_schemes_lists_the_builtins(shary):
    status, out, _ = shary("schemes")
    assert status == 0
    names = [line.split()[0] for line in out.splitlines()]
    assert names == ["announce", "ask-help", "disambiguate", "give-object-attentive",
                     "give-object", "inform", "perform", "plan-requested", "robot-task",
                     "session", "shared-plan-task", "task-requested"]


@pytest.mark.parametrize("command", ["schemes", "scenarios"])
def test_a_listing_keeps_its_columns_whatever_the_names(shary, command):
    """Every summary starts in one column, after the longest name (stack-human-leaves-
    it-to-robot is longer than the column these listings used to have)."""
    status, out, _ = shary(command)
    assert status == 0
    lines = out.splitlines()
    starts = {len(line) - len(line[len(line.split()[0]):].lstrip()) for line in lines}
    assert len(starts) == 1, out
    assert starts.pop() == max(len(line.split()[0]) for line in lines) + 1


def test_simulate_runs_a_script_of_events_and_waits(shary):
    status, out, _ = shary("simulate", "give-object-attentive", "H-AGREE", "reached",
                           "attention-lost", "10s", "attention-back", "done", "done")
    assert status == 0
    assert "enter  suspended  WAIT-ATTENTION (R-ACT)" in out
    assert "12.00s" not in out and "10.00s  <- attention-back" in out
    assert out.strip().endswith("configuration: ended")


def test_simulate_an_unknown_scheme_is_a_clean_error(shary):
    status, _, err = shary("simulate", "give-objet")
    assert status == 2
    assert "did you mean 'give-object'" in err


def test_wheel_carries_the_builtin_yaml_and_schemas(tmp_path):
    """A plain (non-editable) install must find the built-in files."""
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                    "-q", "-w", str(tmp_path), str(REPO)], check=True, capture_output=True)
    (wheel,) = tmp_path.glob("shary-*.whl")
    archive = zipfile.ZipFile(wheel)
    names = set(archive.namelist())
    for expected in ("shary/builtin/schemes/give-object.yaml", "shary/builtin/schemes/acts.yaml",
                     "shary/builtin/recipes/core.yaml", "userfiles/yamlsafe.py",
                     "shary/schemas/scheme.schema.json", "shary/schemas/acts.schema.json",
                     "shary/commands/plan.py", "sim/cli.py"):
        assert expected in names
    (entry_points,) = [n for n in names if n.endswith(".dist-info/entry_points.txt")]
    text = archive.read(entry_points).decode()
    assert "[shary.commands]" in text and "run = sim.cli:add_run" in text


# -- the command registry ------------------------------------------------------

NO_SIM = """
import contextlib, io, json, sys

class NoSim:
    '''Behave as if the simulator package were not installed.'''
    def find_spec(self, name, path=None, target=None):
        if name == "sim" or name.startswith("sim."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)

sys.meta_path.insert(0, NoSim())
from shary.cli import main

results = []
for argv in json.loads(sys.argv[1]):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            status = main(argv)
        except SystemExit as exit_:
            status = exit_.code
    results.append([status, out.getvalue(), err.getvalue()])
results.append(sorted(m for m in sys.modules if m == "sim" or m.startswith(("sim.", "pybullet"))))
print(json.dumps(results))
"""


def _without_sim(tmp_path, *commands):
    """Run shary commands in a child where ``import sim`` fails; (status, out, err) each."""
    import os

    done = subprocess.run([sys.executable, "-c", NO_SIM, json.dumps(commands)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120,
                          env=dict(os.environ, COLUMNS="200"))
    assert done.returncode == 0, done.stderr
    *results, imported = json.loads(done.stdout)
    assert imported == []
    return results


def test_the_engine_works_without_the_simulator(tmp_path):
    scheme = REPO / "docs" / "tutorial" / "ask-then-do.yaml"
    problem = REPO / "planner" / "problems" / "fig6.yaml"
    helped, validated, shipped, listed, simulated, rendered, planned, ran, ran_json, scenario = (
        _without_sim(tmp_path, ["--help"], ["validate", str(scheme)], ["validate"], ["schemes"],
                     ["simulate", "give-object", "H-AGREE"],
                     ["render", "scheme", "give-object", "-o", "g.dot"],
                     ["plan", "fig6", str(problem)], ["run", "give-bottle"],
                     ["run", "give-bottle", "--json"],
                     ["validate", str(REPO / "docs" / "tutorial" / "tidy-table.yaml")]))
    assert helped[0] == 0 and "simulate" in helped[1]
    assert "run" in helped[1] and "unavailable" in helped[1]
    for status, _, err in (validated, shipped, listed, simulated, rendered, planned):
        assert status == 0, err
    assert "give-object.yaml" in shipped[1] and "scenarios" not in shipped[1]
    assert (tmp_path / "g.dot").is_file()
    status, out, err = ran
    assert status == 2 and out == ""
    assert err.strip().splitlines() == [
        "error: 'shary run' is unavailable: the package 'sim' that provides it is not installed "
        "(entry point 'run = sim.cli:add_run')"]
    status, out, err = ran_json
    assert status == 2 and "not installed" in json.loads(out)["error"]
    status, out, err = scenario
    assert status == 2
    (problem_line,) = problems(err)
    assert problem_line["line"] == "2"
    assert "the kinds of files of 'sim' are unavailable (package 'sim' is not installed)" in err


def _plugin(tmp_path, monkeypatch, entries: str) -> None:
    """Install (on sys.path) a distribution that registers these ``shary.commands``."""
    info = tmp_path / "plugin" / "shary_plugin-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: shary-plugin\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[shary.commands]\n{entries}\n")
    (tmp_path / "plugin" / "shary_plugin.py").write_text(
        "def add_hello(sub):\n"
        "    p = sub.add_parser('hello', help='say hello')\n"
        "    p.set_defaults(func=lambda args: print('hello from a plugin'))\n"
        "def add_nothing(sub):\n"
        "    pass\n"
        "def add_badly(sub):\n"
        "    sub.add_parser('badly')\n"
        "    raise ValueError('oops')\n")
    monkeypatch.syspath_prepend(str(tmp_path / "plugin"))


def test_a_package_adds_its_own_command(tmp_path, monkeypatch, shary):
    _plugin(tmp_path, monkeypatch, "hello = shary_plugin:add_hello")
    assert shary("hello") == (0, "hello from a plugin\n", "")


def test_a_broken_entry_point_is_one_line_and_the_others_still_work(tmp_path, monkeypatch,
                                                                     shary, capsys):
    _plugin(tmp_path, monkeypatch, "broken = no_such_module:add\n"
            "typo = shary_plugin:add_helo\nnothing = shary_plugin:add_nothing\n"
            "badly = shary_plugin:add_badly\nschemes = shary_plugin:add_hello")
    with pytest.raises(SystemExit):
        main(["--help"])
    helped = capsys.readouterr().out
    assert "broken" in helped and "unavailable" in helped
    status, out, err = shary("broken", "--some", "args")
    assert status == 2 and out == ""
    assert err.splitlines() == ["error: 'shary broken' is unavailable: the package "
                                "'no_such_module' that provides it is not installed "
                                "(entry point 'broken = no_such_module:add')"]
    for name, why in [("typo", "failed to load: AttributeError"),
                      ("nothing", "did not add a command named 'nothing'"),
                      ("badly", "failed to add the command: ValueError: oops"),
                      ("schemes", "two packages register it")]:
        status, _, err = shary(name)
        assert status == 2 and len(err.splitlines()) == 1 and why in err, err
    assert shary("simulate", "give-object")[0] == 0


def test_version_is_the_installed_one(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out == f"shary {version('shary')}\n"


# -- --json: one document on standard output ------------------------------------


def _json(shary, *args, status=0):
    code, out, err = shary(*args)
    assert code == status, err
    return json.loads(out)


def test_json_schemes_and_scenarios(shary):
    schemes = _json(shary, "schemes", "--json")["schemes"]
    assert [s["name"] for s in schemes][:3] == ["announce", "ask-help", "disambiguate"]
    assert set(schemes[0]) == {"name", "summary", "doc", "file"}
    scenarios = _json(shary, "scenarios", "--json")["scenarios"]
    assert "give-bottle" in [s["name"] for s in scenarios]
    assert all(s["summary"].endswith(".") for s in scenarios)


def test_json_simulate_gives_the_trace(shary):
    doc = _json(shary, "simulate", "give-object", "H-AGREE", "2s", "done", "--json")
    assert doc["scheme"] == "give-object" and doc["configuration"] == ["end"]
    assert doc["trace"][0] == {"time": 0.0, "kind": "enter", "state": "ask",
                               "act": "ASK-TASK", "act_type": "R-ACT"}
    assert {"time": 0.0, "kind": "wait", "wait": "2s"} in doc["trace"]
    assert {"time": 2.0, "kind": "event", "event": "done"} in doc["trace"]


def test_json_validate_names_every_problem(shary, write):
    good = REPO / "docs" / "tutorial" / "ask-then-do.yaml"
    bad = write("bad.yaml", "scheme: bad\ninitial: nowhere\nstates:\n  a: {act: ASK-TASK}\n")
    doc = _json(shary, "validate", str(good), str(bad), "--json", status=2)
    first, second = doc["files"]
    assert first == {"file": str(good), "kind": "scheme", "ok": True, "depends_on": [],
                     "problems": []}
    assert second["file"] == str(bad) and not second["ok"] and second["problems"]
    assert all(set(p) == {"file", "line", "col", "message"} and p["file"] == str(bad)
               for p in second["problems"])


def test_json_a_refused_file_still_exits_2_with_its_problems(shary, write):
    bad = write("bad.yaml", "scheme: [unclosed\n")
    status, out, err = shary("simulate", str(bad), "--json")
    assert status == 2 and problems(err)
    (problem,) = json.loads(out)["problems"]
    (line,) = problems(err)
    assert [problem["file"], problem["line"], problem["col"], problem["message"]] == [
        line["file"], int(line["line"]), int(line["col"]), line["message"]]


def test_json_conformance(shary, tmp_path):
    (tmp_path / "pair.scxml").write_text(
        '<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="a">'
        '<state id="a"><transition event="t" target="b"/></state><state id="b"/></scxml>')
    (tmp_path / "pair.json").write_text(json.dumps({
        "initialConfiguration": ["a"], "events": [{"event": {"name": "t"},
                                                   "nextConfiguration": ["a"]}]}))
    doc = _json(shary, "conformance", str(tmp_path), "--json", status=1)
    assert doc["passed"] == 0 and doc["failed"] == 1
    (test,) = doc["tests"]
    assert test["name"] == "pair.scxml" and not test["passed"] and "b" in test["reason"]


def test_json_run_and_the_default_folder_is_named_after_the_scenario(shary, tmp_path,
                                                                      monkeypatch):
    text = (REPO / "sim" / "scenarios" / "give-bottle.yaml").read_text()
    (tmp_path / "mine.yaml").write_text(text.replace("scenario: give-bottle",
                                                     "scenario: my-bottle"))
    monkeypatch.chdir(tmp_path)
    doc = _json(shary, "run", "mine.yaml", "--json")
    assert doc["outcome"] == "passed" and doc["scenario"] == "my-bottle"
    assert doc["out"] == str(Path("runs") / "my-bottle")
    assert (tmp_path / "runs" / "my-bottle" / "log.sqlite").is_file()
    assert _json(shary, "run", "give-botle", "--json", status=2)["error"].startswith(
        "no scenario named 'give-botle'")


def test_no_registered_command_says_to_reinstall(monkeypatch, shary):
    from importlib import metadata

    monkeypatch.setattr(metadata, "entry_points", lambda **_: [])
    status, out, err = shary("schemes")
    assert status == 2 and out == ""
    assert "no shary commands are registered" in err and "pip install -e ." in err


def test_json_a_wrong_command_line_is_a_document_too(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["schemes", "--json", "--bogus"])
    assert exit_.value.code == 2
    captured = capsys.readouterr()
    assert json.loads(captured.out) == {"error": "unrecognized arguments: --bogus"}
    assert "unrecognized arguments: --bogus" in captured.err


def test_json_an_output_that_cannot_be_written_is_a_document_too(shary, tmp_path):
    (tmp_path / "a-file").write_text("not a folder")
    out = tmp_path / "a-file" / "plan.svg"
    doc = _json(shary, "plan", "fig6", str(REPO / "planner" / "problems" / "fig6.yaml"),
                "--render", "tree", "-o", str(out), "--json", status=2)
    assert doc["error"].startswith(f"{out}: ")


def test_json_simulate_an_event_no_state_takes(shary):
    doc = _json(shary, "simulate", "give-object", "H-AGRE", "--json", status=2)
    assert doc == {"error": "no state of give-object takes the event 'H-AGRE' "
                            "(did you mean 'H-AGREE'?)"}


# -- slips a newcomer met ----------------------------------------------------------


def test_validate_a_folder_checks_the_files_in_it(shary, tmp_path):
    """Before: "FOLDER:1:1: error: cannot read file: Is a directory"."""
    folder = tmp_path / "mine"
    (folder / "below").mkdir(parents=True)
    good = REPO / "docs" / "tutorial" / "ask-then-do.yaml"
    (folder / "ask.yaml").write_text(good.read_text(encoding="utf-8"), encoding="utf-8")
    (folder / "bad.yml").write_text("scheme: bad\ninitial: nowhere\n"
                                    "states:\n  a: {act: ASK-TASK}\n")
    (folder / "notes.txt").write_text("not a file of shary's")
    (folder / "below" / "deep.yaml").write_text("scheme: [unclosed\n")
    status, out, err = shary("validate", folder)
    assert status == 2
    assert out.split() == ["ok", str(folder / "ask.yaml")]
    assert {m["file"] for m in problems(err)} == {str(folder / "bad.yml")}
    assert "Is a directory" not in err


def test_validate_a_folder_without_files_says_what_to_give(shary, tmp_path):
    (tmp_path / "below").mkdir()
    (tmp_path / "below" / "deep.yaml").write_text("acts: {}\n")
    status, _, err = shary("validate", tmp_path)
    assert status == 2
    (problem,) = problems(err)
    assert problem["file"] == str(tmp_path) and problem["message"] == (
        "a folder with no .yaml, .yml or .ttl file in it (shary validate reads the files "
        "directly in a folder, not those in folders below): name the files or folders to check")


def test_world_without_ros_on_a_living_room_scenario_says_to_add_ros(shary):
    status, _, err = shary("world", "give-bottle")
    assert status == 2
    assert "not a seam-welding scenario" in err
    assert "'shary world --ros give-bottle' (docs/ros2.md)" in err


LOG = REPO / "tests" / "hostile" / "log" / "node-of-an-unknown-kind.sqlite"


SCHEME = ["render", "scheme", "give-object"]
TREE = ["render", "tree", str(LOG)]
PLAN = ["plan", "fig6", str(REPO / "planner" / "problems" / "fig6.yaml"), "--render", "tree"]
DOT = ".svg, .png, .dot, .gv"


@pytest.mark.parametrize("argv, name, what, allowed", [
    (SCHEME, "out.gif", "a .gif file", f"{DOT}, .mmd, .mermaid, .md"),
    (TREE, "out.gif", "a .gif file", DOT), (TREE, "out.mmd", "a .mmd file", DOT),
    (TREE, "tree", "a file without a suffix", DOT), (PLAN, "out.gif", "a .gif file", DOT),
    (PLAN, "out.mmd", "a .mmd file", DOT)],
    ids=["scheme-gif", "tree-gif", "tree-mermaid", "tree-no-suffix", "plan-gif",
         "plan-mermaid"])
def test_a_drawing_to_a_suffix_it_cannot_take_is_refused_before_the_work(
        argv, name, what, allowed, shary, tmp_path):
    """Before: exit 1 (the status of a run whose expectation failed), after the work."""
    out = tmp_path / name
    status, stdout, err = shary(*argv, "-o", out)
    assert status == 2 and stdout == ""
    assert err == f"{out}: error: cannot draw to {what} (use one of {allowed})\n"
    assert not out.exists()


def test_render_scheme_says_what_its_output_may_be(capsys):
    with pytest.raises(SystemExit):
        main(["render", "scheme", "--help"])
    helped = " ".join(capsys.readouterr().out.split())
    assert "-o OUT, --output OUT the file to draw; its suffix says how: .svg or .png" in helped


def test_conformance_on_a_missing_folder_points_to_the_external_suites(shary, tmp_path):
    status, out, err = shary("conformance", tmp_path / "suites" / "scion")
    assert status == 2 and out == ""
    assert f"{tmp_path / 'suites' / 'scion'}: no such folder" in err
    assert "the README's section 'External suites' says how to clone it" in err


@pytest.mark.parametrize("command", ["run", "serve"])
def test_the_seed_says_its_default(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    helped = " ".join(capsys.readouterr().out.split())
    assert "--seed SEED seed of the people's random choices (default 0)" in helped


def test_run_quiet_prints_the_verdict_alone(shary, tmp_path):
    """Before: the verdict, then "wrote DIR/: log.sqlite, …"."""
    status, out, err = shary("run", "give-bottle", "--quiet", "--out", tmp_path)
    assert status == 0 and err == ""
    (line,) = out.splitlines()
    assert line.startswith("PASSED give-bottle: ") and line.endswith(", seed 0")
    assert (tmp_path / "summary.json").is_file()


def test_run_quiet_says_why_a_run_failed(shary, tmp_path):
    scenario = (REPO / "sim" / "scenarios" / "give-bottle.yaml").read_text(encoding="utf-8")
    bad = tmp_path / "unmet.yaml"
    bad.write_text(scenario.replace("tasks: {give-object: done}",
                                    "tasks: {give-object: failed}"), encoding="utf-8")
    status, out, _ = shary("run", bad, "--quiet", "--out", tmp_path / "out")
    assert status == 1
    verdict, *why = out.splitlines()
    assert verdict.startswith("FAILED give-bottle: ") and why and "wrote" not in out
