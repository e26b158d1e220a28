"""Behaviour campaigns (``shary fuzz``): the invariants on short campaigns of each family,
Hypothesis-drawn partners for the stack, and the violations campaigns found, each
kept as a scenario of its own (docs/fuzz.md)."""

from __future__ import annotations

import textwrap

import pytest
import yaml
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from sim.fuzz.behaviours import ROBOT_TASKS, draw, stack_partner
from sim.fuzz.campaign import campaign, command, judge, run_one
from sim.run import run_scenario
from sim.scenario import builtin_scenarios, load_scenario


def run_text(base: str, text: str, family: str = "living-room", seed: int = 0
             ) -> tuple[str | None, str, dict[str, str]]:
    """Run a scenario written here, read as if it were the built-in ``base``; judge it."""
    scenario = load_scenario(builtin_scenarios()[base], text=textwrap.dedent(text))
    return judge(family, scenario, run_scenario(scenario, seed=seed))


CAMPAIGNS = [("living-room", 30, 1), ("weld", 24, 1), ("stack", 24, 5), ("dialogue", 24, 1)]
"""(family, runs, first seed): a short campaign each, a few seconds a run at most."""


@pytest.mark.parametrize(("family", "runs", "seed"), CAMPAIGNS,
                         ids=[c[0] for c in CAMPAIGNS])
def test_a_short_campaign_violates_no_invariant(family, runs, seed):
    result = campaign(family, runs, seed)
    assert len(result.outcomes) == runs
    assert not result.violations, "\n".join(
        f"{command(family, o.seed)}: {name}: {what}" for o, name, what in result.violations)


def test_a_seed_draws_one_behaviour_a_user_could_write():
    """The same seed draws the same document, and the readers accept it as a file."""
    for family in ("stack", "living-room", "weld", "dialogue"):
        first, again = draw(family, 7), draw(family, 7)
        assert first.text() == again.text() and first.team_text() == again.team_text()
        assert first.load().name == f"{first.base}-fuzz-7"
    assert draw("living-room", 7).text() != draw("living-room", 8).text()


PARTNER = st.sampled_from(["alice", "bob", "zoe"])


@st.composite
def profiles(draw_from: st.DrawFn) -> dict:
    """A stack partner's profile from the documented keys (docs/jahrvis.md)."""
    profile = {"choices": draw_from(st.lists(st.sampled_from(
                   ["placement_1", "placement_2", "Pick", "Place", "wait"]), max_size=4)),
               "delay": draw_from(st.sampled_from([0, 0.5, 1, 2.5, 4]))}
    if draw_from(st.booleans()):
        profile["look-away"] = {"during": draw_from(st.sampled_from(ROBOT_TASKS)),
                                "for": draw_from(st.sampled_from([0.5, 3, 6, 15, 40]))}
    return profile


@settings(max_examples=6, deadline=None, derandomize=True, database=None,
          phases=(Phase.explicit, Phase.generate),
          suppress_health_check=[HealthCheck.too_slow])
@given(partner=PARTNER, profile=profiles(), wait=st.sampled_from([2, 4, 6]))
def test_a_stack_partner_drawn_by_hypothesis_never_stalls_the_plan(partner, profile, wait):
    data = stack_partner(partner, profile, wait)
    data["scenario"] = "stack-hypothesis"
    text = yaml.safe_dump(data, sort_keys=False)
    state, reason, violations = run_text("stack-nominal", text, family="stack")
    assert violations == {}, f"{violations}\nthe scenario:\n{text}"
    assert state in ("achieved", "failed")


GIVE = """\
    scenario: give-{name}
    robot: {{name: jido, at: base}}
    people:
      alice:
        at: sofa-seat
        profile: {profile}
    goals:
      - {{task: give-object, with: {{object: yellow-bottle, partner: alice}}}}
    timeout: 200s
    expect: {{}}
"""


def test_a_hand_over_nobody_takes_ends_failed_with_its_reason():
    """Found by ``shary fuzz living-room --replay 47``: she agrees but never takes what
    is held out; the give waited for ever and the run reached its timeout."""
    state, reason, violations = run_text("give-bottle", GIVE.format(
        name="never-taken",
        profile="{answers: {ASK-TASK: {reply: H-AGREE, after: 1s}}, takes: null}"))
    assert violations == {}
    assert state == "failed" and reason


def test_a_robot_handed_back_takes_the_task_that_waited_for_it():
    """Found by ``shary fuzz weld --replay 15``: IVA drives K-10 while the weld is
    made; the inspection becomes ready then, nobody else can do it, and after the hand
    back nothing offered it again: the run reached its timeout with the goal open."""
    from sim.weld.scenario import load_weld_scenario

    scenario = load_weld_scenario(builtin_scenarios()["weld-human-supports-robot"], text="""\
scenario: weld-held
site: seam-welding
team: weld/human-supports-robot.team.yaml
mounted: [P1, P2, P3]
script:
  - {at: 2s, by: IVA, take-control: K-10}
  - {at: 30s, by: IVA, hand-back: K-10}
timeout: 4min
expect: {}
""")
    state, reason, violations = judge("weld", scenario, run_scenario(scenario))
    assert violations == {} and state == "achieved"


CLEAN_UP = """\
    scenario: clean-up-{name}
    robot: {{name: jido, at: base}}
    people:
      alice:
        at: sofa-seat
        profile: {profile}
    objects:
      yellow-bottle: {{on: coffee-table, at: [{at}]}}
    goals:
      - {{task: clean-up, with: {{object: yellow-bottle}}}}
    timeout: 200s
    expect: {{}}
"""


def test_the_robot_asks_for_help_only_once_the_helper_looks():
    """Found by ``shary fuzz living-room --replay 20``: Alice is on the phone when the
    pick fails; the robot said "I could not pick the yellow bottle." to no one
    listening.  Now it waits for her glance (as every question does), then asks."""
    state, _, violations = run_text("clean-up-unreachable", CLEAN_UP.format(
        name="helper-away", at="-0.35, 0.2",
        profile="{answers: {ASK-HELP: {reply: H-AGREE, after: 1s}}, distractions: "
                "[{when: {at: 1s}, look: phone, for: 12s}]}"))
    assert violations == {}
    assert state == "achieved"



def test_a_goal_with_someone_who_never_comes_to_interact_is_dropped_saying_why():
    """Found by ``shary fuzz living-room --replay 76``: Alice never looks at the robot,
    so no session opens and the give waited for one until the run's timeout.  Now
    the goal is cancelled after a while, the reason in its ``goal-over`` row."""
    state, reason, violations = run_text("give-bottle", GIVE.format(
        name="never-attends", profile="{attention: store-table}"))
    assert violations == {}
    assert state == "failed" and "alice" in reason


def test_the_robot_stops_asking_when_the_helper_walks_away():
    """Found by ``shary fuzz living-room --replay 100``: Alice walks to the door while
    the robot says "I could not pick the yellow bottle."; it went on with "Can you give
    me the yellow bottle?" after she had looked away.  Now it waits for her again."""
    state, reason, violations = run_text("clean-up-unreachable", CLEAN_UP.format(
        name="helper-leaves", at="-0.35, 0.2",
        profile="{speed: 1.27, script: [{at: 4.1s, leave: true}]}"))
    assert violations == {}
    assert state == "failed" and reason


def test_a_person_who_looks_away_once_she_has_the_object_was_given_it():
    """Found by ``shary fuzz living-room --replay 206``: Alice takes the bottle and
    looks at her phone while the arm goes back; the robot waited for her attention,
    gave up and said "You are busy, so I will not give you the yellow bottle." while
    she held it.  The give is done once she has taken it."""
    text = GIVE.format(name="taken-then-away", profile=(
        "{answers: {ASK-TASK: {reply: H-AGREE, after: [2.2s, 3.3s]}}, takes: {after: "
        "[2.4s, 3s]}, speed: 1.13, distractions: [{when: {at: 27.6s}, after: 0.9s, "
        "look: away, for: never}]}")) + "    noise: {hold: 0.8s, flicker: {isHolding: 0.17}}\n"
    state, _, violations = run_text("give-bottle", text, seed=206)
    assert violations == {}
    assert state == "achieved"


def test_no_answer_to_a_no_is_said_to_someone_who_is_not_looking():
    """Found by ``shary fuzz living-room --replay 248``: Alice says no, and the robot's
    perception no longer sees her look at it (her gaze flickers): it said "I will not
    give you the yellow bottle." all the same.  Now it says so only to her face."""
    text = GIVE.format(name="no-then-away", profile=(
        "{answers: {ASK-TASK: {reply: H-DISAGREE, after: 0.7s}}, speed: 0.95}")) + \
        "    noise: {hold: 0s, flicker: {looksAt: 0.14}}\n"
    state, _, violations = run_text("give-bottle", text, seed=248)
    assert violations == {}
    assert state == "failed"


def test_thanks_are_said_to_a_helper_who_looks():
    """Found by ``shary fuzz living-room --replay 96``: "Thank you for the yellow
    bottle." said while the robot did not see Alice look at it."""
    state, _, violations = run_text("clean-up-unreachable", CLEAN_UP.format(
        name="thanks", at="-0.35, 0.2", profile=(
            "{answers: {ASK-TASK: [{reply: H-AGREE, after: [0.7s, 2.4s]}], ASK-HELP: "
            "[{reply: H-AGREE, after: [1.4s, 2.3s]}, {reply: H-AGREE, after: [1.7s, 2.5s]}]}, "
            "distractions: [{when: {at: 38.4s}, after: 0.7s, look: away, for: 13.1s}], "
            "takes: {after: [2.8s, 3.2s]}, helps: true, speed: 1.29}"
        )) + "    noise: {hold: 0s, flicker: {looksAt: 0.07}}\n",
        seed=96)
    assert violations == {}
    assert state == "achieved"


STACK = """\
    scenario: stack-{name}
    robot: {{name: pr2, model: pr2like, at: coffee-area}}
    people:
      {partner}: {{at: coffee-north, profile: cooperative}}
    action-models: [stack]
    shared-plan:
      problem: stack
      partner: {partner}
      decision-wait: {wait}
      profile: {profile}
    timeout: 300s
    expect: {{}}
"""


def test_a_partner_who_never_looks_back_does_not_keep_the_run_going():
    """Found by ``shary fuzz stack --replay 9``: Bob looks away for ten minutes as the
    robot places the last cube; the plan is achieved, the robot calls him and gives up
    telling him, and the run went on until its timeout waiting for his glance.  Now it
    ends there, the untold inform in a ``belief`` row."""
    text = STACK.format(name="never-looks-back", partner="bob", wait="6s", profile=(
        "{choices: [Place, Place, Place], delay: 4.0, "
        "look-away: {during: 'Place(pr2, blue_cube', for: 600}}"))
    scenario = load_scenario(builtin_scenarios()["stack-nominal"], text=textwrap.dedent(text))
    result = run_scenario(scenario, seed=9)
    state, _, violations = judge("stack", scenario, result)
    assert violations == {}
    assert state == "achieved" and result.simulated_seconds < 100
    assert any(kind == "belief" and data.get("why") == "untold"
               for _, kind, _, _, data in result.events)


def test_what_a_partner_who_left_missed_is_tried_once_the_plan_is_over():
    """Found by ``shary fuzz stack --replay 128``: Carol walks out after her last
    pick; the robot's last actions are NOT_SEEN in her view, and the inform at the end
    of the plan ends untold (she has left: she is not called).  That is all it can do:
    the invariant now reads the ``belief ... why=untold`` row the end's inform writes
    (it counted only a failed plan as over)."""
    state, _, violations = run_text("stack-nominal", STACK.format(
        name="partner-left", partner="carol", wait="4.4s", profile=(
            "{choices: [placement_2], delay: 3.9, "
            "leave: {after: 'Pick(carol, blue_cube_2)'}}")), family="stack", seed=128)
    assert violations == {}
    assert state == "achieved"


def test_an_inform_is_not_said_to_a_partner_who_looks_away_as_it_starts():
    """Found by ``shary fuzz stack --replay 155``: Carol's gaze flickers; she looked
    away while the robot turned to her and it said "I placed the blue cube on the green
    cube." all the same.  A look-away before the sentence starts now sends the inform
    back to waiting for her attention (``recipes/dialogue.yaml``: ``until: speak``)."""
    text = STACK.format(name="inform-flicker", partner="carol", wait="2.3s", profile=(
        "{choices: [placement_1, placement_2, Place], delay: 2.2}")) + \
        "    noise: {hold: 0s, flicker: {looksAt: 0.09}}\n"
    state, _, violations = run_text("stack-nominal", text, family="stack", seed=155)
    assert violations == {}
    assert state == "achieved"


def test_a_replan_keeps_the_partner_s_top_blue_cube():
    """Found by ``shary fuzz stack --replay 58``: the robot's place failed twice, the
    plan was made again, Bob left the first blue cube to the robot, and the new plan
    ended with no blue cube on the green one: its agendas lacked ``HumanTopBlue``,
    which the old branch had found already done (no primitive task).  The replan's
    agendas now keep such tasks (``shary/plans/replan.py``)."""
    text = STACK.format(name="replan-top-blue", partner="bob", wait="6.3s", profile=(
        "{choices: [placement_1, wait], delay: 3.6}")) + \
        "    faults: [{action: place, reason: the place slipped, times: 2}]\n"
    state, _, violations = run_text("stack-nominal", text, family="stack", seed=58)
    assert violations == {}
    assert state == "achieved"


def test_a_partner_cannot_take_a_cube_out_of_the_robot_s_hand():
    """Found by ``shary fuzz stack --replay 140``: Dana means to do the robot's next
    step (pick the green cube, put it on her blue one) but is late; the simulator let
    her pull the green cube out of the robot's gripper while she held her blue cube,
    and the plan waited 45 s for a place the robot could not do, then failed.  A
    person's pick of something another agent holds now does nothing (sim/people.py)."""
    state, _, violations = run_text("stack-nominal", STACK.format(
        name="snatch", partner="dana", wait="2.3s", profile=(
            "{choices: [], delay: 2.8, before: {'Pick(pr2, green_cube)': "
            "[[Pick, green_cube], [Place, green_cube, blue_cube_2]]}}")),
        family="stack", seed=140)
    assert violations == {}
    assert state == "achieved"


def weld_killed(base: str, member: str, at: float) -> tuple[tuple, list]:
    """Run the built-in weld scenario ``base`` with ``member`` killed ``at`` seconds in
    (as a weld campaign draws it); its judgement and its log rows."""
    from sim.weld.run import run_weld
    from sim.weld.scenario import load_weld_scenario

    scenario = load_weld_scenario(builtin_scenarios()[base])
    result = run_weld(scenario, kill=(member, at))
    return judge("weld", scenario, result), result.events


def test_a_robot_killed_mid_task_falls_silent_and_its_task_is_taken_back():
    """K-10 is killed while it drives to its first inspection: it stops (no message
    from it, its position no longer changes), the Task Manager takes the inspection
    back (``agent-lost``) as a distributed conductor would, and since nobody else can
    inspect, the watchdog ends the goal failed saying so, well before the timeout."""
    (state, reason, violations), rows = weld_killed("weld-nominal", "K-10", 3.0)
    assert [(r[2], r[4].get("state")) for r in rows if r[1] == "agent-lost"] == \
        [("inspect-P1-P2", "running")]
    assert not [r for r in rows if r[0] > 3.0 and r[1] == "message" and r[3] == "K-10"]
    moved = [r for r in rows if r[0] > 3.2 and r[1] == "fact-added"
             and r[4].get("s") == "K-10" and r[4].get("p") in ("x", "y")]
    assert not moved, moved[:3]
    assert violations == {} and state == "failed"
    assert "inspect-P1-P2" in reason and "no agent can do" in reason


def test_a_person_killed_has_her_panel_offered_to_the_other_astronaut():
    """EVA2 is killed while offered the mount of P4: the task is taken back and EVA1
    mounts it; the weld goes on to the end."""
    (state, reason, violations), rows = weld_killed("weld-nominal", "EVA2", 0.5)
    lost = [r[2] for r in rows if r[1] == "agent-lost"]
    assert lost == ["mount-P4"]
    done = {r[2]: r[3] for r in rows if r[1] == "task-done"}
    assert done["mount-P4"] == "EVA1"
    assert violations == {} and state == "achieved"


def test_a_person_killed_while_carrying_a_panel_puts_it_down():
    """EVA1 is killed 8 s in, carrying P3 to the frame: she stops where she is and the
    panel is put down on the ground beside her (before: she walked on holding it and
    tacked it, dead); EVA2, offered the task taken back, fetches it from there."""
    (state, reason, violations), rows = weld_killed("weld-nominal", "EVA1", 8.0)
    (down,) = [r for r in rows if r[1] == "put-down"]
    assert down[0] == 8.0 and down[3] == "EVA1" and down[4]["panel"] == "P3"
    p3_z = [r[4]["o"] for r in rows if r[0] >= 8.0 and r[1] == "fact-added"
            and r[4].get("s") == "P3" and r[4].get("p") == "z"]
    assert p3_z and float(p3_z[0]) < 0.05  # lying on the ground, not held at 1 m
    walked = [r for r in rows if r[0] > 8.0 and r[1] == "fact-added"
              and r[4].get("s") == "EVA1" and r[4].get("p") in ("x", "y")]
    assert not walked, walked[:3]
    done = {r[2]: r[3] for r in rows if r[1] == "task-done"}
    assert done["mount-P3"] == "EVA2"
    assert violations == {} and state == "achieved"


def test_a_helper_killed_while_carrying_puts_the_panel_down_and_helps_no_more():
    """EVA2 helps EVA1 carry P4 and is killed 9 s in: the panel is put down, EVA1 hears
    her mount failed, and the retry (the team file names EVA2 as the helper) is refused
    instead of a dead helper walking beside her."""
    (state, reason, violations), rows = weld_killed("weld-robot-supports-human", "EVA2", 9.0)
    (down,) = [r for r in rows if r[1] == "put-down"]
    assert down[3] == "EVA2" and down[4]["carriers"] == ["EVA1", "EVA2"]
    failed = [r[4]["reason"] for r in rows if r[1] == "task-failed" and r[2] == "mount-P4"]
    assert failed == ["EVA2 left: P4 was put down",
                      "EVA2 has left the site: nobody to carry P4 with"]
    assert violations == {} and state == "failed" and "mount-P4" in reason


def test_the_report_says_the_task_verdict_and_the_invariants_apart():
    """Before: "✓ seed 1 failed", the tick for the invariants beside the task's verdict,
    read as a contradiction."""
    from rich.console import Console

    from sim.fuzz.campaign import Campaign, Outcome
    from sim.fuzz.report import print_campaign, progress_line

    checked = ("verdict", "no-ongoing", "facts", "told-unseen")
    failed = Outcome(1, "clean-up", "Bob refuses", "failed", "declined", 44.1, 0.4,
                     checked=checked)
    lied = Outcome(2, "give-bottle", "Alice leaves", "achieved", "", 16.7, 0.2,
                   {"facts": "the bottle is on the shelf"}, checked)
    console = Console(record=True, width=200, color_system=None)
    told = progress_line(console)
    told(failed)
    told(lied)
    print_campaign(console, Campaign("living-room", 1, [failed, lied], 0.6))
    lines = console.export_text().splitlines()
    assert [line.split() for line in lines[:3]] == [
        ["seed", "task", "verdict", "invariants", "held", "simulated", "wall", "scenario"],
        ["1", "failed", "✓", "all", "4", "44.1", "s", "0.4", "s", "clean-up"],
        ["2", "achieved", "✗", "3", "of", "4", "16.7", "s", "0.2", "s", "give-bottle",
         "(violated:", "facts)"]]
    header = lines[0]
    assert lines[1].index("failed") == lines[2].index("achieved") == header.index("task")
    assert lines[1].index("✓") == lines[2].index("✗") == header.index("invariants held")
    assert lines[3] == ("shary fuzz living-room: 2 runs (seed 1 to 2): task verdicts 1 "
                        "achieved, 1 failed, 0 none; invariants held in 1 of 2; 60.8 s "
                        "simulated in 0.6 s")


DIALOGUE_FOUND = {
    8: "two informs to Alice at once (the scenario's and the robot's answer to her plan "
       "change): the newer look took the head from the older, whose sentence was lost and "
       "its goal failed without a word; two looks at one target no longer take the head "
       "from each other (shary/kernel/arbiter.py)",
    10: "a goal she asked for again once back was counted as outliving her goodbye "
        "(after-farewell now judges the goals there when she left)",
    48: "\"All right, I will stop and put the yellow bottle back.\" said to Bob's back "
        "after his CANCEL: a stop is said to a partner who attends, else the robot turns "
        "to them in silence",
    135: "\"Yes, I will do that.\" said 14 s after Bob asked, to his back: an agreement "
         "is said to a partner who attends, else the robot turns to them in silence",
    49: "her own CANCEL, on the phone: the goal failed without a stated reason (the "
        "verdict reads her CANCEL) and \"All right, I will stop.\" was said to her back",
    156: "\"Hello, Bob.\" said as he took a call: GREET watches his look until it speaks",
    21: "\"Sorry, I did not understand what to change.\" begun 3 s into \"All right, I will "
        "stop and put the yellow bottle back.\": two tasks spoke at once (as seed 8's "
        "answer over its inform); the voice now says one sentence at a time "
        "(shary/kernel/arbiter.py)",
    23: "\"Actually, never mind.\" on the phone, for the clean-up she had asked: the robot "
        "stopped in silence and the goal ended failed with no reason (a goal its person "
        "cancels now ends \"cancelled by alice\", shary/kernel/agenda.py), and its plan "
        "had been proposed as she looked away",
    **dict.fromkeys(
        (28, 31, 105, 230, 257, 265, 277, 387, 438),
        "\"Here is my plan. … Is that all right?\" said to the back of the person who had "
        "asked for the clean-up (turned away, on the phone, walking out): PROPOSE-PLAN is "
        "said to a partner who attends, else the robot turns to them and waits for their "
        "look (WAIT-ATTENTION, then a call), and gives up saying why if it never comes"),
    **dict.fromkeys(
        (243, 303, 469),
        "\"All right: you will pick up the orange bottle. I will plan again.\" said to her "
        "back as she went to pick it up: the acknowledgement of MODIFY-PLAN is said to a "
        "partner who attends, else the robot turns to them in silence"),
    443: "the plan proposal said to her back (as 438), then \"Can you give me the orange "
         "bottle?\" as she looked away when ASK-HELP began: ASK-HELP asks only a helper "
         "who attends, and waits for them again otherwise",
    **dict.fromkeys(
        (50, 401, 434, 435),
        "\"Shall I give you …?\" asked of someone on the phone or whose gaze flickered "
        "away as the robot turned to them: ASK-TASK asks only a partner who attends, "
        "and otherwise waits for their look, calls them, or gives up saying why"),
    417: "\"Do you mean …?\" asked as her gaze flickered away while the robot turned to "
         "her: the wait for her attention starts again when she looks away during it",
    **dict.fromkeys(
        (356, 357),
        "\"All right, the green cube on the store table.\" said to her looking at the "
        "store table: the acknowledgement of her answer is said only to a partner who "
        "attends, else the robot turns to her in silence"),
    318: "\"I gave you the yellow bottle.\" said as her gaze flickered away: the END-TASK "
         "of a hand-over speaks only to a partner who attends, else turns to them",
    59: "\"I have cleared the orange bottle away.\" said to the back of the person who "
        "had asked for the clean-up: its END-TASK speaks only to the person who asked "
        "($initiator) if they attend, else turns to them",
}
"""Seeds of ``shary fuzz dialogue`` that violated an invariant, and why, now fixed."""


@pytest.mark.parametrize("seed", sorted(DIALOGUE_FOUND))
def test_a_dialogue_campaign_finding_holds_every_invariant(seed):
    outcome = run_one("dialogue", seed)
    assert outcome.violations == {}, DIALOGUE_FOUND[seed]


STACK_FOUND = {
    330: "Bob's gaze flickered away as the robot's head reached him: the wait for his "
         "attention ended with the turn of the head and \"I placed the green cube …\" was "
         "said to him looking away (the wait now starts again when he looks away during it)",
    411: "Bob looked back a tenth of a second after the robot gave up telling him what he "
         "missed, at the end of the plan: nothing was said and the pick stayed NOT_SEEN "
         "though he was looking (an inform given up as he looks back is tried again)",
    142: "Bob walked out, then his look-away's end turned his head to the robot from "
         "outside: the inform given up as he looked was tried again, ended at once (he had "
         "left) and was tried again, for ever at one instant (a person who left is not "
         "told again; so were seeds 254 and 273)",
}
"""Seeds of ``shary fuzz stack`` (500 runs from seed 1) that violated the conversation
invariants, or raised, and why, now fixed."""


@pytest.mark.parametrize("seed", sorted(STACK_FOUND))
def test_a_stack_campaign_finding_holds_every_invariant(seed):
    outcome = run_one("stack", seed)
    assert outcome.violations == {}, STACK_FOUND[seed]


def test_an_operator_killed_while_driving_a_robot_gives_it_back_to_its_goals():
    """Found by ``shary fuzz weld --replay 385``: IVA took control of K-10 at 21.1 s and
    was killed at 21.4 s; nobody was left to hand K-10 back, its goals waited under the
    dead operator's hold and the run reached its timeout.  A robot whose operator is
    killed is in system mode again (``shary/team/team.py``, ``Team.kill``)."""
    outcome = run_one("weld", 385)
    assert outcome.violations == {}
    assert outcome.verdict is not None

