"""Bad domain and problem files: FILE:LINE:COL, exit status 2; and `shary plan`."""

from __future__ import annotations

import json
from pathlib import Path

from conftest import problems

ROOT = Path(__file__).resolve().parents[1] / "planner"
DOMAIN = """\
domain: d
types:
  Place: {}
  Agent: {agent: true, static: {kind: string}, dynamic: {at: Place}}
actions:
  Move:
    params: {ag: Agent, to: Place}
    agent: ag
    pre: ag.at != to
    effects: [ag.at = to]
methods:
  Go:
    params: {ag: Agent, p: Place}
    decompositions:
      - {name: move, subtasks: ["Move(ag, p)"]}
"""


def _refused(shary, *args) -> list[tuple[str, int, int, str]]:
    status, _, err = shary("plan", *args)
    assert status == 2, err
    assert "Traceback" not in err
    return [(m["file"], int(m["line"]), int(m["col"]), m["message"]) for m in problems(err)]


def test_expression_errors_have_their_column(shary, write):
    domain = write("d.yaml", DOMAIN.replace("pre: ag.at != to", "pre: ag.att != to and (to")
                   .replace('["Move(ag, p)"]', '["Move(ag, p, p)", "Fly(ag)"]'))
    found = _refused(shary, domain, write("p.yaml", "problem: p\nentities: {}\ntasks: [x()]\n"))
    messages = {(line, col): msg for _, line, col, msg in found}
    assert any("att" in m and "did you mean 'at'" in m for m in messages.values())
    assert (9, 13) in messages
    assert any("takes 2 argument(s)" in m for m in messages.values())
    assert any("unknown task 'Fly'" in m for m in messages.values()) or len(found) >= 2


def test_problem_errors(shary, write):
    domain = write("d.yaml", DOMAIN)
    problem = write("p.yaml", """\
        problem: p
        entities:
          home: {type: Place}
          r: {type: Agnt, at: home}
          h: {type: Agent, kind: human, at: hme, colour: red}
        tasks: ["Go(h, nowhere)", "Jump(h)"]
        rules: {politeness: {penalty: 2}}
        """)
    text = " | ".join(m for *_, m in _refused(shary, domain, problem))
    for expected in ("unknown type 'Agnt' (did you mean 'Agent'?)", "unknown entity 'hme'",
                     "Agent has no attribute 'colour'", "unknown entity 'nowhere'",
                     "unknown task 'Jump'", "no rule 'politeness'"):
        assert expected in text, text


def test_schema_and_yaml_errors(shary, write):
    domain = write("d.yaml", DOMAIN.replace("methods:", "method:"))
    found = _refused(shary, domain, write("p.yaml", "problem: p\n"))
    assert any("unknown key 'method'" in m and "did you mean 'methods'" in m
               for *_, m in found)


def test_plan_command_text_and_json(shary):
    status, out, _ = shary("plan", "living-room", ROOT / "problems" / "serve-drink.yaml")
    assert status == 0
    assert "Give(jido, alice, orange-bottle)" in out and "validated" in out
    status, out, _ = shary("plan", "living-room", ROOT / "problems" / "serve-drink.yaml",
                           "--rules", "none", "--json")
    data = json.loads(out)
    assert data["found"] and data["valid"] and data["actions"][-1]["name"] == "Pick"
    assert data["criteria"]["cost"] == 7


def test_plan_command_explains_no_plan(shary, write):
    text = (ROOT / "problems" / "clean-up-unreachable.yaml").read_text().replace(
        "  alice: {type: Agent", "  # alice: {type: Agent")
    status, out, _ = shary("plan", "living-room", write("alone.yaml", text))
    assert status == 1 and "no plan" in out and "robot_reach" in out


def test_plan_command_renders(shary, tmp_path):
    for what in ("tree", "streams"):
        out = tmp_path / f"{what}.svg"
        status, _, err = shary("plan", "living-room", ROOT / "problems" /
                               "clean-up-unreachable.yaml", "--render", what, "-o", out)
        assert status == 0, err
        assert "<svg" in out.read_text()


def test_unknown_rule_on_the_command_line(shary):
    status, _, err = shary("plan", "living-room", ROOT / "problems" / "serve-drink.yaml",
                           "--rules", "politness")
    assert status == 2 and "no rule 'politness'" in err


def test_validate_checks_domains_and_problems(shary, write):
    status, out, _ = shary("validate")
    assert status == 0 and "living-room.yaml" in out and "fig6.yaml" in out
    domain = write("d.yaml", DOMAIN.replace("ag.at != to", "ag.at != too"))
    problem = write("p.yaml", "problem: p\ndomain: d.yaml\nentities: {}\ntasks: [Go()]\n")
    status, _, err = shary("validate", domain, problem)
    assert status == 2
    found = problems(err)
    assert any("unknown name 'too'" in m["message"] and m["line"] == "9" for m in found)
