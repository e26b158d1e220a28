"""The sentences robots say in a small campaign of runs, for reading and for the tests.

A campaign of headless runs: the stack scenarios with partner profiles
recombined from the documented keys (the choice at each decision, a delay
that makes her late, a look-away during one of the robot's actions), the
living-room scenarios with each shipped person profile and two seeds, and the
weld scenarios, and forty conversations drawn by ``shary fuzz dialogue``.  What the
robots say in them (``speech`` reports of a robot,
never a person's) is kept once each per family, sorted: ``tests/data/sentences.txt``,
which ``tests/test_sentences.py`` regenerates and compares, and which a person
reads as a native speaker would when it changes.

    python tests/sentences.py          # rewrite tests/data/sentences.txt
    python tests/sentences.py --check  # say what differs, change nothing
"""

from __future__ import annotations

import argparse
import difflib
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parent.parent
SCENARIOS = ROOT / "sim" / "scenarios"
LIST = Path(__file__).resolve().parent / "data" / "sentences.txt"

STACK_PROFILES: list[dict[str, Any]] = [
    {"choices": ["placement_2", "Pick"], "delay": 1,
     "look-away": {"during": "Pick(pr2", "for": 6}},
    {"choices": ["wait", "wait"], "delay": 1, "look-away": {"during": "Place(pr2", "for": 8}},
    {"choices": ["placement_1", "Pick"], "delay": 6,
     "look-away": {"during": "Place(pr2", "for": 8}},
    {"choices": ["placement_1", "wait"], "delay": 25,
     "look-away": {"during": "Pick(pr2", "for": 15}},
]
"""Partner profiles of the stack family (docs/jahrvis.md's ``profile`` keys): she looks
away while the robot picks or places (told when she looks back), and she is late for her
own tasks (asked for them)."""

FAMILIES: dict[str, list[str]] = {
    "stack": ["stack-not-seen", "stack-failure-said-on-the-phone",
              "stack-told-across-a-replan", "stack-partner-walks-out"],
    "living-room": ["give-bottle", "give-bottle-abandoned", "give-bottle-unanswered",
                    "give-bottle-refused", "give-red-cup", "clean-up", "clean-up-unreachable",
                    "person-asks-for-bottle", "person-cancels", "person-modifies-plan",
                    "request-ambiguous-cube", "request-unknown-object",
                    "serve-drink-initiative", "session-greeting-farewell",
                    "explore-new-objects", "inform-after-look-back",
                    "give-bottle-walks-out"],
    "weld": ["weld-question-expires"],
    "dialogue": [],
}
"""The shipped scenarios of each family run as they are.  Only runs that say something
new are kept (the campaign runs in the suite): the other stack scenarios, the other
weld scenarios (with seeds 0-2, their robots only ask "Is this seam okay?") and the
seeds other than 0 (they move timings, not words) said nothing more when tried."""

DIALOGUE_SEEDS = range(1, 41)
"""Runs of ``shary fuzz dialogue`` whose drawn conversations (requests, cancels, plan
changes, sessions closed and opened again, a bystander) are read here too."""

PROFILES = {"clean-up-unreachable": ["phone-call", "refuser"],
            "give-red-cup": ["phone-call-forever", "refuser"]}
"""Living-room scenarios run again with each of these person profiles."""


def _yaml(path: Path) -> Any:
    """A scenario's data, with YAML 1.1's ``on`` key (a boolean to PyYAML) kept a key."""
    def keys(value: Any) -> Any:
        if isinstance(value, dict):
            return {("on" if k is True else k): keys(v) for k, v in value.items()}
        if isinstance(value, list):
            return [keys(v) for v in value]
        return value
    return keys(yaml.safe_load(path.read_text("utf-8")))


def runs(folder: Path, family: str) -> Iterator[Path]:
    """The family's scenario files, the variants written into ``folder`` (a copy of
    ``sim/scenarios``, so that their recipe and team files are found beside them)."""
    def variant(base: str, name: str, edit: Callable[[dict[str, Any]], None]) -> Path:
        data = _yaml(SCENARIOS / f"{base}.yaml")
        edit(data)
        data["scenario"] = name
        data["expect"] = {"plan": ["started"]} if "shared-plan" in data else {}
        path = folder / f"{name}.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False), "utf-8")
        return path

    if family == "stack":
        for i, profile in enumerate(STACK_PROFILES):
            def partner(data: dict[str, Any], profile: dict[str, Any] = profile) -> None:
                data["shared-plan"]["profile"] = profile
                data["timeout"] = "300s"
            yield variant("stack-nominal", f"stack-profile-{i + 1}", partner)
    for name in FAMILIES[family]:
        yield folder / f"{name}.yaml"
    if family == "dialogue":
        from sim.fuzz.behaviours import draw

        for seed in DIALOGUE_SEEDS:
            drawn = draw("dialogue", seed)
            path = folder / f"{drawn.scenario['scenario']}.yaml"
            path.write_text(drawn.text(), "utf-8")
            yield path
    if family == "living-room":
        for base, profiles in PROFILES.items():
            for profile in profiles:
                def person(data: dict[str, Any], profile: str = profile) -> None:
                    for spec in data["people"].values():
                        spec["profile"] = profile
                yield variant(base, f"{base}-{profile}", person)


def _words(text: str) -> str:
    """A robot's speech report as said: without the addressee and picture a team's
    question is reported with ("(IVA) Is this seam okay?  [image …]")."""
    text = text.split("  [image")[0]
    if text.startswith("(") and ") " in text:
        text = text.split(") ", 1)[1]
    return text


def _robots(path: Path) -> set[str]:
    from sim.scenario import load_scenario

    scenario = load_scenario(path)
    team = getattr(scenario, "team", None)
    if team is not None:
        return {name for name, agent in team.agents.items() if agent.kind == "robot"}
    return {scenario.robot}


def generate(family: str) -> list[str]:
    """Every sentence a robot says in the family's runs, once, sorted."""
    from sim.run import run_scenario

    said: set[str] = set()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "scenarios"
        shutil.copytree(SCENARIOS, folder)
        for path in runs(folder, family):
            robots = _robots(path)

            def report(t: float, who: str, kind: str, text: str,
                       robots: set[str] = robots) -> None:
                if kind == "speech" and who in robots:
                    said.add(_words(text))
            run_scenario(path, seed=0, report=report)
    return sorted(said)


def read() -> dict[str, list[str]]:
    """The checked-in list, by family (``# FAMILY`` lines head each family's sentences)."""
    found: dict[str, list[str]] = {}
    family = None
    for line in LIST.read_text("utf-8").splitlines():
        if line.startswith("# "):
            family = line[2:]
            found[family] = []
        elif line and family is not None:
            found[family].append(line)
    return found


def write(sentences: dict[str, list[str]]) -> None:
    LIST.write_text("".join(f"# {family}\n" + "".join(f"{s}\n" for s in said)
                            for family, said in sentences.items()), "utf-8")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="print what differs from tests/data/sentences.txt, write nothing")
    args = parser.parse_args()
    sentences = {family: generate(family) for family in FAMILIES}
    old = read() if LIST.exists() else {}
    lines = [f"{f}: {s}" for f, said in old.items() for s in said]
    new = [f"{f}: {s}" for f, said in sentences.items() for s in said]
    diff = list(difflib.unified_diff(lines, new, str(LIST), "generated", lineterm=""))
    count = len({s for said in sentences.values() for s in said})
    print("\n".join(diff) if diff else f"{count} sentences, as in {LIST}")
    if not args.check:
        write(sentences)
    return 1 if diff and args.check else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    raise SystemExit(main())
