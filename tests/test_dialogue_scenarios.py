"""The dialogue scenarios as a newcomer runs them: the story ``shary run`` tells, and the
sessions in the log (the outcomes themselves are judged in tests/test_scenarios.py)."""

from __future__ import annotations

import subprocess
import sys

from shary.log.contextlog import read_events
from sim.run import run_scenario
from sim.scenario import builtin_scenarios


def test_shary_run_request_ambiguous_cube_tells_the_question_and_the_hand_over(tmp_path):
    # the console story as printed (rich writes to the process's own stdout)
    out = subprocess.run([sys.executable, "-m", "shary", "run", "request-ambiguous-cube",
                          "--out", str(tmp_path / "run")], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    story = out.stdout
    question = ("Do you mean the green cube on the store table or the one on the coffee "
                "table?")
    assert question in story
    assert story.index(question) < story.index("The one on the store table.")
    assert "All right, the green cube on the store table." in story
    assert "give green-cube to alice" in story
    assert "I gave you the green cube." in story
    assert "PASSED request-ambiguous-cube" in story


def test_a_session_is_in_the_log_from_greeting_to_farewell(tmp_path):
    result = run_scenario(builtin_scenarios()["session-greeting-farewell"], out=tmp_path)
    assert result.passed, result.differences
    events = list(read_events(tmp_path / "log.sqlite"))
    kinds = [e.kind for e in events if e.kind in ("session-open", "session-close")]
    assert kinds == ["session-open", "session-close"]
    opened = next(e for e in events if e.kind == "session-open")
    assert opened.agent == "bob" and opened.data["greeted"] is True
    acts = [e.data["act"] for e in events if e.kind == "act" and e.task == "n1"]
    assert acts == ["GREET", "INTERACT", "FAREWELL"]
    timeline = (tmp_path / "timeline.svg").read_text()
    for act in ("GREET", "INTERACT", "FAREWELL"):
        assert f'data-act="{act}"' in timeline
