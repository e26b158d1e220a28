"""``shary export`` read by Foxglove's own MCAP reader, in node.

``tests/foxglove/check_mcap.cjs`` opens the file with ``@mcap/core`` (the
TypeScript reader Foxglove's app uses), zstd chunks decompressed by
``@foxglove/wasm-zstd`` (what ``@mcap/support`` hands Foxglove), and validates
every message against its channel's schema, and the ``foxglove.*`` channels
against the JSON Schemas Foxglove publishes (``@foxglove/schemas``).  The node
packages live outside the repository (``.ci/run`` installs them with
``npm install --prefix ~/.cache/shary-node …``; ``SHARY_NODE_MODULES`` names
another folder); without node or them, the tests skip and say so.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
from hostile import run_inprocess
from test_console import write_run
from test_console_plan import write_plan_run

CHECK = Path(__file__).parent / "foxglove" / "check_mcap.cjs"
MODULES = Path(os.environ.get("SHARY_NODE_MODULES",
                              Path.home() / ".cache" / "shary-node" / "node_modules"))
PACKAGES = ("@mcap/core", "@foxglove/wasm-zstd", "@foxglove/schemas", "ajv")
NODE = shutil.which("node")
if NODE is None:
    pytest.skip("no node: Foxglove's MCAP reader runs in node (apt-get install nodejs)",
                allow_module_level=True)
missing = [p for p in PACKAGES if not (MODULES / p / "package.json").exists()]
if missing:
    pytest.skip(f"{', '.join(missing)} not in {MODULES}: npm install --prefix "
                f"{MODULES.parent} @mcap/core@2.2.2 @foxglove/wasm-zstd@1.0.1 "
                "@foxglove/schemas@2.1.0 ajv@8.20.0 (as .ci/run does)", allow_module_level=True)


def foxglove_reads(path: Path) -> dict[str, Any]:
    done = subprocess.run([NODE, str(CHECK), str(MODULES), str(path)], capture_output=True,
                          text=True, timeout=120)
    assert done.stdout, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


@pytest.mark.parametrize("write", [write_run, write_plan_run], ids=["give-object", "plan"])
def test_foxglove_reads_every_message_and_its_schemas_hold(write: Any, tmp_path: Path):
    write(tmp_path)
    out = tmp_path / "run.mcap"
    exported = run_inprocess("export", tmp_path / "log.sqlite", "--mcap", out, "--json")
    assert exported.status == 0, exported.err
    counts = json.loads(exported.out.splitlines()[-1])["channels"]
    read = foxglove_reads(out)
    assert read["problems"] == []
    assert {topic: c["messages"] for topic, c in read["channels"].items()} == counts
    assert read["messages"] == sum(counts.values()) and read["chunks"] >= 1
    assert read["channels"]["/log"]["foxglove_schema"]
    assert read["channels"]["/snapshots"]["foxglove_schema"]
    assert read["channels"]["/snapshots"]["messages"] == 1
    if write is write_plan_run:
        assert read["channels"]["/plan-tasks"]["messages"] > 0
        assert read["channels"]["/recognitions"]["messages"] == 2


def test_the_check_sees_a_message_foxglove_cannot_show(tmp_path: Path):
    """A foxglove.Log whose level is not one of Foxglove's, and a message that breaks its
    own channel's schema: both are reported (the check can fail)."""
    from mcap.writer import CompressionType, Writer

    from shary.console.export import SCHEMAS

    out = tmp_path / "bad.mcap"
    with out.open("wb") as stream:
        writer = Writer(stream, compression=CompressionType.ZSTD)
        writer.start(profile="", library="test")
        ids = {}
        for topic in ("/log", "/acts"):
            name, schema = SCHEMAS[topic]
            schema_id = writer.register_schema(name=name, encoding="jsonschema",
                                               data=json.dumps(schema).encode())
            ids[topic] = writer.register_channel(topic=topic, message_encoding="json",
                                                 schema_id=schema_id)
        for topic, message in (("/log", {"timestamp": {"sec": 0, "nsec": 0}, "level": 9,
                                         "message": "x", "name": "n", "file": "f", "line": 0}),
                               ("/acts", {"time": "soon", "direction": "sideways"})):
            writer.add_message(ids[topic], log_time=0, publish_time=0,
                               data=json.dumps(message).encode())
        writer.finish()
    problems = foxglove_reads(out)["problems"]
    assert any(p.startswith("/log #0 against Foxglove's schema") for p in problems), problems
    assert any(p.startswith("/acts #0 against its own schema") for p in problems), problems
