"""The seam-welding case (HRI/OS Section 4) in PyBullet: the site's physics and devices,
and the six weld scenarios run end to end and judged, with what they show."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from shary.kernel.loop import EventLoop
from shary.log.timeline import collect
from sim.png import read_png
from sim.run import run_scenario
from sim.scenario import builtin_scenarios
from sim.weld.layout import PANEL_Y, PANEL_Z
from sim.world import pb

WELD_SCENARIOS = ("weld-nominal", "weld-robot-supports-human", "weld-human-supports-robot",
                  "weld-question-expires", "weld-control-authority", "weld-human-refuses")


# -- the site --------------------------------------------------------------------------

@pytest.fixture(scope="module")
def site():
    """One site for the module's physics checks: P1-P3 mounted, K-10 at its P1-P2 spot,
    Robonaut-B at the weld spot of P2-P3, two astronauts by the pallet."""
    from sim.simulation import Simulation
    from sim.weld.executors import SiteActions
    from sim.weld.site import WeldSite

    with WeldSite() as world:
        for panel in ("P1", "P2", "P3"):
            world.mount(panel)
        world.add_robot("K-10", "k10", "inspect-P1-P2")
        world.add_robot("Robonaut-B", "pr2like", "weld-P2-P3")
        loop = EventLoop(seed=0)
        sim = Simulation(world, loop, "K-10")
        actions = SiteActions(world, sim, qualities={"P2-P3": [0.6]})
        actions.add_person("EVA1", 4.5, -3.4, math.pi / 2)
        actions.add_person("EVA2", 6.5, -3.4, math.pi / 2)
        yield world, loop, actions


def _centre(world, panel: str) -> tuple[float, ...]:
    return world.call(pb.getBasePositionAndOrientation, world.panels[panel])[0]


def test_astronauts_carry_a_panel_and_tack_it_where_physics_holds_it(site) -> None:
    world, loop, actions = site
    done: list[float] = []
    actions.mount("P4", ["EVA1", "EVA2"], lambda: done.append(loop.now()))
    loop.advance(30.0)
    assert done and world.mounted("P4")
    assert _centre(world, "P4") == pytest.approx((3.5, PANEL_Y, PANEL_Z), abs=0.01)
    world.step(2.0)  # lunar gravity pulls; the tack holds
    assert _centre(world, "P4")[2] == pytest.approx(PANEL_Z, abs=0.01)
    # an untacked panel let go falls
    world.release_tack("P4")
    world.step(1.0)
    assert _centre(world, "P4")[2] < PANEL_Z - 0.1
    world.mount("P4")


def test_the_welder_reaches_the_seam_and_lays_a_bead(site) -> None:
    world, loop, actions = site
    from shary.kernel.executors import Reporter, Request

    outcomes = []
    reporter = Reporter(outcomes.append, loop.call_soon)
    actions.start(Request("w1", "weld", {"seam": "P2-P3"}, "Robonaut-B", "n"), reporter)
    loop.advance(20.0)
    assert [o.status for o in outcomes] == ["done"]
    assert world.beads["P2-P3"].quality == 0.6
    actions.start(Request("i1", "inspect", {"seam": "P2-P3"}, "K-10", "n"), reporter)
    loop.advance(10.0)
    assert outcomes[-1].status == "done" and outcomes[-1].result["verdict"] == "unsure"


def test_k10_points_its_light_at_a_point_and_its_beam_lights_it(site) -> None:
    world, loop, actions = site
    from shary.kernel.executors import Reporter, Request

    outcomes = []
    corner = (2.97, PANEL_Y - 0.02, 0.58)
    actions.start(Request("l1", "point-light", dict(zip("xyz", corner, strict=True)), "K-10",
                          "n"), Reporter(outcomes.append, loop.call_soon))
    loop.advance(5.0)
    assert outcomes[-1].status == "done"
    assert outcomes[-1].result["off_by_m"] < 0.02
    assert world.spots["K-10"] in (world.call(pb.getBodyUniqueId, i)
                                   for i in range(world.call(pb.getNumBodies)))


# -- the scenarios -----------------------------------------------------------------------

def test_the_weld_scenarios_are_listed() -> None:
    assert set(WELD_SCENARIOS) <= set(builtin_scenarios())


def _run(name: str, tmp_path: Path):
    result = run_scenario(builtin_scenarios()[name], out=tmp_path / name)
    assert result.passed, result.differences
    return result, collect(_events(tmp_path / name / "log.sqlite"))


def _events(path: Path):
    from shary.log.contextlog import read_events

    return read_events(path)


def _rows(tmp_path: Path, name: str, kind: str):
    return [e for e in _events(tmp_path / name / "log.sqlite") if e.kind == kind]


@pytest.mark.parametrize("name", ["weld-nominal", "weld-control-authority",
                                  "weld-human-refuses", "weld-question-expires"])
def test_scenario_passes_with_a_lane_per_agent(name: str, tmp_path: Path) -> None:
    result, timeline = _run(name, tmp_path)
    assert result.simulated_seconds < 120
    team_lanes = {"K-10", "Robonaut-B", "IVA"} | ({"EVA1", "EVA2"} if "refuses" in name
                                                  or "nominal" in name else set())
    assert set(timeline.agents) == team_lanes  # managers and software agents are not lanes


def test_human_supports_robot_asks_with_an_image_and_respawns_the_weld(tmp_path: Path) -> None:
    name = "weld-human-supports-robot"
    _, timeline = _run(name, tmp_path)
    question = _rows(tmp_path, name, "question")[0]
    assert question.agent == "K-10" and question.data["text"] == "Is this seam okay?"
    image = Path(question.data["data"]["image"])
    width, height, _, _ = read_png(image)
    assert (width, height) == (480, 360)
    routed = [e for e in _events(tmp_path / name / "log.sqlite")
              if e.kind == "message" and e.data.get("type") == "question"
              and e.data.get("to") == "IVA"]
    assert routed
    answer = _rows(tmp_path, name, "answer")[0]
    assert (answer.agent, answer.data["value"]) == ("IVA", "no")
    respawn = _rows(tmp_path, name, "respawn")[0]
    assert respawn.task == "weld-P2-P3" and respawn.time >= answer.time
    asked = [i for i in timeline.items if i.agent == "K-10" and "Is this seam okay?" in i.label]
    assert asked and f"image: {image}" in asked[0].tooltip
    assert any(i.agent == "IVA" and "no" in i.label for i in timeline.items)
    assert any(p.label == "respawn weld-P2-P3" for p in timeline.plans)


@pytest.mark.parametrize("name", ["weld-question-expires"])
def test_a_run_without_files_is_judged_as_one_with_them(name: str) -> None:
    """The Python entry point with no output folder (the benchmarks') gives the verdict
    ``shary run`` gives: the question's picture is taken either way."""
    result = run_scenario(builtin_scenarios()[name])
    assert result.passed, result.differences
    assert not result.outputs


def test_robot_supports_human_lights_the_corner_from_the_speakers_side(tmp_path: Path) -> None:
    name = "weld-robot-supports-human"
    _run(name, tmp_path)
    spatial = _rows(tmp_path, name, "spatial")[0]
    assert spatial.data["perspective"] == "EVA1" and spatial.data["referent"] == "P3"
    # EVA1 faces the frame from the south: its right is east, P3's east end at x = 3
    assert spatial.data["point"] == pytest.approx([2.97, PANEL_Y - 0.02, 0.58], abs=0.01)
    kinds = [e.kind for e in _events(tmp_path / name / "log.sqlite")
             if e.agent == "K-10" and e.kind in ("breakpoint", "associate", "release",
                                                 "goal-resumed")]
    assert kinds[:3] == ["breakpoint", "associate", "release"]
    assert "goal-resumed" in kinds[3:]
    assert list((tmp_path / name).glob("k-10-*light-for-EVA1.png"))


def test_an_ambiguous_request_is_asked_back_to_the_speaker(tmp_path: Path) -> None:
    """EVA1 says "the panel" and looks at none: K-10 asks EVA1 which one (nearest first),
    EVA1 picks the first choice, and K-10 lights that panel's corner."""
    import shutil

    source = builtin_scenarios()["weld-robot-supports-human"]
    shutil.copytree(source.parent / "weld", tmp_path / "weld")
    team = tmp_path / "weld" / "robot-supports-human.team.yaml"
    text = team.read_text("utf-8").replace("corner of panel P3", "corner of the panel")
    text = text.replace("""      questions: {reply: ignore}
      requests:""", """      questions: {reply: answer, after: 2s}
      requests:""")
    team.write_text(text, "utf-8")
    scenario = tmp_path / "ambiguous.yaml"
    scenario.write_text(source.read_text("utf-8").replace(
        "spatial by K-10,", "spatial by K-10, question by K-10, answer by EVA1, spatial by K-10,"),
        "utf-8")
    result = run_scenario(scenario, out=tmp_path / "out")
    assert result.passed, result.differences
    spatial = [e for e in _events(tmp_path / "out" / "log.sqlite") if e.kind == "spatial"]
    assert spatial[0].data["choices"][0] == "P3" and "which panel" in spatial[0].data["question"]
    assert spatial[1].data["referent"] == "P3"
    assert spatial[1].data["point"] == pytest.approx([2.97, PANEL_Y - 0.02, 0.58], abs=0.01)


def _mount_seconds(result, task: str) -> float:
    """How long the team's ``task`` ran: from its ``task-running`` row to its ``task-done``."""
    times = {kind: t for t, kind, name, _, _ in result.events
             if name == task and kind in ("task-running", "task-done")}
    return times["task-done"] - times["task-running"]


def test_how_long_a_person_works_is_how_long_the_site_takes_to_mount_their_panel(tmp_path):
    """``works:`` is the person's behaviour: a mount the world performs (carry, tack) is
    over no sooner than it says, not only when the physics is done."""
    from sim.weld.scenario import load_weld_scenario

    path = builtin_scenarios()["weld-nominal"]
    team = (path.parent / "weld" / "nominal.team.yaml").read_text()
    quick = run_scenario(load_weld_scenario(path))
    slow_team = team.replace("      assignments: {reply: accept, after: 1s}\n",
                             "      assignments: {reply: accept, after: 1s}\n"
                             "      works: {mount-panel: 90s}\n", 1)
    assert slow_team != team
    slow = run_scenario(load_weld_scenario(path, team_text=slow_team))
    assert _mount_seconds(quick, "mount-P3") < 60
    assert _mount_seconds(slow, "mount-P3") >= 90
    assert slow.passed, slow.differences
