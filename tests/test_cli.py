"""The shary command as a newcomer uses it."""

from __future__ import annotations

import subprocess
import sys
import zipfile

from conftest import REPO


def test_schemes_lists_the_builtins(shary):
    status, out, _ = shary("schemes")
    assert status == 0
    names = [line.split()[0] for line in out.splitlines()]
    assert names == ["ask-help", "give-object-attentive", "give-object", "perform", "robot-task"]


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
    names = set(zipfile.ZipFile(wheel).namelist())
    for expected in ("shary/builtin/schemes/give-object.yaml", "shary/builtin/schemes/acts.yaml",
                     "shary/builtin/recipes/core.yaml", "userfiles/yamlsafe.py",
                     "shary/schemas/scheme.schema.json", "shary/schemas/acts.schema.json"):
        assert expected in names
