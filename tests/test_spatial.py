"""The spatial reasoning agent on hand-made poses: ego, referent and exo frames, the
speaker's perspective, and questions back for ambiguous references."""

from __future__ import annotations

import math

import pytest

from shary.facts.database import FactDatabase
from shary.team.spatial import Question, Resolved, SpatialError, SpatialReasoner, parse

FACING_SOUTH = -math.pi / 2
FACING_NORTH = math.pi / 2


def _put(facts: FactDatabase, name: str, kind: str, x: float, y: float, z: float,
         yaw: float | None, **size: float) -> None:
    facts.add(name, "type", kind)
    for predicate, value in {"x": x, "y": y, "z": z, **size}.items():
        facts.add(name, predicate, float(value))
    if yaw is not None:
        facts.add(name, "yaw", float(yaw))


@pytest.fixture
def site() -> SpatialReasoner:
    """Four panels in a row along x, their fronts facing south (-y); EVA1 south of P3
    facing north, K-10 north of the frame facing south, EVA2 east of the row; box-1,
    which has no front, just ahead of EVA1."""
    facts = FactDatabase()
    for i in range(1, 5):
        _put(facts, f"P{i}", "Panel", i - 0.5, 0.0, 1.0, FACING_SOUTH,
             width=1.0, height=1.0, thickness=0.02)
    _put(facts, "EVA1", "Human", 2.5, -2.0, 0.0, FACING_NORTH)
    _put(facts, "K-10", "Robot", 2.5, 2.0, 0.0, FACING_SOUTH)
    _put(facts, "EVA2", "Human", 7.0, 0.0, 0.0, math.pi)
    _put(facts, "box-1", "Box", 2.5, -1.0, 0.0, None, width=0.4)
    return SpatialReasoner(facts)


def _resolved(answer: Resolved | Question) -> Resolved:
    assert isinstance(answer, Resolved), answer
    return answer


def test_the_papers_request_is_read_as_its_parameter_set() -> None:
    request = parse("Point the light at the bottom right corner of panel P3", "EVA1", "K-10")
    assert (request.speaker, request.addressee, request.command) == ("EVA1", "K-10",
                                                                      "point-light")
    assert (request.referent, request.kind, request.relation) == ("P3", "panel", "corner")
    assert (request.vertical, request.side, request.perspective) == ("bottom", "right",
                                                                      "speaker")


def test_a_corner_from_the_speakers_perspective(site: SpatialReasoner) -> None:
    answer = _resolved(site.understand("point the light at the bottom right corner of panel P3",
                                       "EVA1", "K-10"))
    # EVA1 faces north: its right is east, so the corner is P3's east end, at the bottom,
    # on the south face that EVA1 sees
    assert answer.point == pytest.approx((2.97, -0.015, 0.53))
    assert (answer.referent, answer.frame, answer.perspective) == ("P3", "referent", "EVA1")
    assert answer.local[0] > 0  # on EVA1's right
    assert "EVA1's point of view" in answer.says


def test_right_for_the_speaker_is_left_for_the_rover_facing_it(site: SpatialReasoner) -> None:
    said = "point the light at the bottom right corner of panel P3"
    speaker = _resolved(site.understand(said, "EVA1", "K-10"))
    # the same corner in K-10's own frame is on its left: it faces the other way
    dx, dy = speaker.point[0] - 2.5, speaker.point[1] - 2.0
    k10_right = (math.sin(FACING_SOUTH), -math.cos(FACING_SOUTH))
    assert dx * k10_right[0] + dy * k10_right[1] < 0
    # and "as you see it" resolves from the rover: the other end, on the north face
    rover = _resolved(site.understand(said + " as you see it", "EVA1", "K-10"))
    assert rover.point == pytest.approx((2.03, 0.015, 0.53))
    assert rover.perspective == "K-10"
    assert rover.local[0] > 0


def test_edge_on_speaker_is_asked_which_corner(site: SpatialReasoner) -> None:
    answer = site.understand("point the light at the bottom right corner of P4", "EVA2", "K-10")
    assert isinstance(answer, Question)
    assert answer.to == "EVA2" and answer.kind == "multiple-choice"
    assert set(answer.choices) == {"the bottom east corner", "the bottom west corner"}
    # on the panel's own front, since EVA2 sees neither face; corners are 3 cm inside
    assert answer.answers["the bottom east corner"] == pytest.approx((3.97, -0.015, 0.53))
    assert "edge-on" in answer.text


def test_an_unnamed_panel_is_the_one_looked_at_or_a_question(site: SpatialReasoner) -> None:
    said = "point the light at the top left corner of the panel"
    asked = site.understand(said, "EVA1", "K-10")
    assert isinstance(asked, Question)
    assert asked.choices[0] == "P3"  # nearest first
    assert set(asked.choices) == {"P1", "P2", "P3", "P4"}
    site.facts.add("EVA1", "looksAt", "P2")
    answer = _resolved(site.understand(said, "EVA1", "K-10"))
    assert answer.referent == "P2"
    assert answer.point == pytest.approx((1.03, -0.015, 1.47))


def test_an_unknown_name_gets_a_question_naming_the_choices(site: SpatialReasoner) -> None:
    asked = site.understand("point the light at the bottom left corner of panel P9", "EVA1",
                            "K-10")
    assert isinstance(asked, Question)
    assert "P9" in asked.text and "P3" in asked.choices


def test_left_of_an_object_without_a_front_uses_the_referent_frame(
        site: SpatialReasoner) -> None:
    # box-1 is straight ahead of EVA1: "left of box-1" is on EVA1's left, 0.7 m from it
    answer = _resolved(site.understand("move to the left of box-1", "EVA1", "robonaut"))
    assert answer.frame == "referent" and answer.perspective == "EVA1"
    assert answer.point == pytest.approx((1.8, -1.0, 0.0))
    assert answer.local == pytest.approx((-0.7, 1.0, 0.0))
    # K-10 looks at box-1 from the north: its left is the other side
    theirs = _resolved(site.understand("move to the left of box-1 as you see it", "EVA1",
                                       "K-10"))
    assert theirs.point == pytest.approx((3.2, -1.0, 0.0))
    front = _resolved(site.understand("move in front of box-1", "EVA1", "robonaut"))
    # in front of the box as EVA1 sees it: between the box and EVA1
    assert math.dist(front.point[:2], (2.5, -2.0)) < math.dist((0.0, -3.0), (2.5, -2.0))


def test_ego_frames_of_speaker_addressee_and_object(site: SpatialReasoner) -> None:
    mine = _resolved(site.understand("move to my left", "EVA1", "K-10"))
    assert mine.frame == "ego" and mine.point[0] < 2.5  # EVA1 faces north: left is west
    yours = _resolved(site.understand("move to your left", "EVA1", "K-10"))
    assert yours.perspective == "K-10" and yours.point[0] > 2.5  # K-10 faces south
    its = _resolved(site.understand("go to K-10's right", "EVA1", "robonaut"))
    assert its.perspective == "K-10" and its.point[0] < 2.5


def test_exo_frame_uses_the_world_axes(site: SpatialReasoner) -> None:
    east = _resolved(site.understand("point the light at the bottom east corner of P3",
                                     "EVA2", "K-10"))
    assert east.frame == "exo" and east.point[0] == pytest.approx(2.97)
    north = _resolved(site.understand("move to the north side of box-1", "EVA1", "K-10"))
    assert north.point[:2] == pytest.approx((2.5, -0.3))


def test_words_it_cannot_read_get_a_free_text_question(site: SpatialReasoner) -> None:
    with pytest.raises(SpatialError, match="two words"):
        parse("point the light at the right corner of P3", "EVA1", "K-10")
    asked = site.understand("sing a song", "EVA1", "K-10")
    assert isinstance(asked, Question) and asked.kind == "free-text"
    unknown = site.understand("move to my left", "nobody", "K-10")
    assert isinstance(unknown, Question) and "where are you" in unknown.text


def test_the_service_answers_a_point_or_a_question(site: SpatialReasoner) -> None:
    said = "point the light at the bottom right corner of panel P3"
    answer = site.service({"words": said, "speaker": "EVA1", "addressee": "K-10"})
    assert answer["point"] == pytest.approx([2.97, -0.015, 0.53])
    assert answer["frame"] == "referent" and answer["perspective"] == "EVA1"
    asked = site.service({"words": said.replace("P3", "P4"), "speaker": "EVA2",
                          "addressee": "K-10"})
    assert asked["to"] == "EVA2" and len(asked["choices"]) == 2 and "point" not in asked
    corner = asked["answers"][asked["choices"][0]]
    assert len(corner) == 3  # a choice of corner is its point
    which = site.service({"words": "point the light at the top left corner of the panel",
                          "speaker": "EVA1", "addressee": "K-10"})
    assert which["answers"]["P2"] == "P2"  # a choice of panel names it
    chosen = site.service({"words": "point the light at the top left corner of the panel",
                           "speaker": "EVA1", "addressee": "K-10", "referent": "P2"})
    assert chosen["referent"] == "P2" and chosen["point"] == pytest.approx([1.03, -0.015, 1.47])
