"""Recognition in a PyBullet run: a person picks a bottle and places it under a flickering hold."""

from __future__ import annotations

import json
import sqlite3

from sim.run import run_scenario

SCENARIO = """\
scenario: carry-recognized
doc: Alice takes the yellow bottle and carries it to the store table; her hold flickers.
robot: {name: jido, at: store-area}
people:
  alice:
    at: sofa-seat
    profile:
      script:
        - {at: 0.5s, walk: coffee-east}
        - {after: 0.5s, take: yellow-bottle}
        - {after: 0.5s, walk: store-side}
        - {after: 0.5s, put: yellow-bottle, on: store-table}
action-models: [living-room]
noise:
  hold: 0s
  flicker: {isHolding: 0.5}
timeout: 30s
expect:
  facts: [[yellow-bottle, isOn, store-table]]
"""


def test_a_pick_and_one_place_are_recognized_while_the_hold_flickers(tmp_path):
    path = tmp_path / "carry.yaml"
    path.write_text(SCENARIO)
    result = run_scenario(path, out=tmp_path / "out")
    assert result.passed, result.differences
    with sqlite3.connect(tmp_path / "out" / "log.sqlite") as db:
        rows = db.execute("SELECT kind, agent, data FROM events WHERE kind IN "
                          "('recognition', 'fact-added', 'fact-removed') ORDER BY seq").fetchall()
    holds = [kind for kind, _, data in rows
             if kind.startswith("fact-") and json.loads(data)["p"] == "isHolding"]
    assert len(holds) >= 10, "the hold did not flicker: the test would prove nothing"
    seen = [(json.loads(data)["state"], json.loads(data)["action"], agent)
            for kind, agent, data in rows if kind == "recognition"]
    assert [s for s in seen if s[0] == "achieved"] == [("achieved", "pick", "alice"),
                                                        ("achieved", "place", "alice")]
    assert ("started", "place", "alice") in seen and ("progressing", "place", "alice") in seen
    placed = [json.loads(data) for kind, _, data in rows if kind == "recognition"][-1]
    assert placed["params"] == {"Pickable": "yellow-bottle", "Support": "store-table"}
