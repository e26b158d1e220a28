"""A chart with a data model, against python-statemachine 3.x on the same SCXML in the same run.

The chart is a dialogue that counts: the robot asks, a reply with a positive
``n`` in its data is taken (counted, and summed into ``total`` while fewer
than three were taken in a row), a reply with nothing is asked again up to
three times before giving up and starting over.  Every transition has a guard
over the data or the event's data, and every transition assigns.  The one
SCXML text is imported by shary (``shary import-scxml``'s path: scheme YAML,
checked, compiled) and loaded by python-statemachine (its restricted
evaluator, the default); both are fed the same seeded stream of events and
must end in the same configuration with the same variables, or the run fails.

Figures: events per second for both, and their ratio.

    python benchmarks/datamodel.py [--json] [--events N] [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

from statemachine.io import load

from shary import compile_scheme
from shary.io.schemes import parse_scheme
from shary.io.scxml import import_scxml
from userfiles.yamlsafe import load_text

CHART = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" datamodel="python"
       name="counting" initial="asking">
  <datamodel>
    <data id="asked" expr="0"/><data id="taken" expr="0"/><data id="total" expr="0"/>
    <data id="rounds" expr="0"/>
  </datamodel>
  <state id="asking">
    <transition event="reply" cond="_event.data.n &gt; 0 and taken &lt; 3" target="taking">
      <assign location="taken" expr="taken + 1"/>
      <assign location="total" expr="total + _event.data.n"/>
    </transition>
    <transition event="reply" cond="_event.data.n &gt; 0" target="asking">
      <assign location="taken" expr="0"/>
      <assign location="rounds" expr="rounds + 1"/>
    </transition>
    <transition event="reply" cond="asked &lt; 3" target="asking">
      <assign location="asked" expr="asked + 1"/>
    </transition>
    <transition event="reply" cond="asked &gt;= 3" target="gave_up">
      <assign location="asked" expr="0"/>
    </transition>
  </state>
  <state id="taking">
    <transition event="reply" cond="_event.data.n % 2 == 0" target="asking">
      <assign location="asked" expr="0"/>
    </transition>
    <transition event="reply" cond="_event.data.n % 2 == 1" target="asking">
      <assign location="total" expr="total - 1"/>
    </transition>
    <transition event="reply" cond="_event.data.n == 0" target="asking">
      <assign location="asked" expr="asked + 1"/>
    </transition>
  </state>
  <state id="gave_up">
    <transition event="reply" cond="rounds &gt;= 0" target="asking">
      <assign location="rounds" expr="rounds + 1"/>
    </transition>
  </state>
</scxml>
"""
VARIABLES = ("asked", "taken", "total", "rounds")


def stream(events: int, seed: int = 11) -> list[int]:
    """The ``n`` of each reply: zero (no answer) a third of the time, else 1 to 5."""
    rng = random.Random(seed)
    return [0 if rng.random() < 0.33 else rng.randint(1, 5) for _ in range(events)]


def run_ours(compiled, replies: list[int]) -> tuple[float, tuple]:
    instance = compiled.start()
    send = instance.send
    start = time.perf_counter()
    for n in replies:
        send("reply", {"n": n})
    elapsed = time.perf_counter() - start
    return elapsed, (set(instance.configuration),
                     tuple(instance.data[v] for v in VARIABLES))


def run_peer(chart_class, replies: list[int]) -> tuple[float, tuple]:
    machine = chart_class()
    send = machine.send
    start = time.perf_counter()
    for n in replies:
        send("reply", n=n)
    elapsed = time.perf_counter() - start
    return elapsed, ({s.id for s in machine.configuration},
                     tuple(getattr(machine.model, v) for v in VARIABLES))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="end with one JSON line of figures")
    parser.add_argument("--events", type=int, default=20_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    replies = stream(args.events)
    ours, theirs = [], []
    with tempfile.TemporaryDirectory() as tmp:
        chart = Path(tmp) / "counting.scxml"
        chart.write_text(CHART, encoding="utf-8")
        compiled = compile_scheme(parse_scheme(load_text(import_scxml(chart), str(chart))))
        for _ in range(args.repeat):
            elapsed, end_ours = run_ours(compiled, replies)
            ours.append(elapsed)
            # a class loaded by python-statemachine binds its variables in its first instance
            # only, so each run loads the chart again (outside the timing)
            elapsed, end_theirs = run_peer(load(str(chart)), replies)
            theirs.append(elapsed)
            if end_ours != end_theirs:
                print(f"the engines disagree: shary ended in {end_ours}, python-statemachine "
                      f"in {end_theirs}", file=sys.stderr)
                return 1
    rate = args.events / statistics.median(ours)
    peer_rate = args.events / statistics.median(theirs)
    print(f"chart: 3 states, every transition guarded and assigning; {args.events} events "
          f"(median of {args.repeat}); both ended in {sorted(end_ours[0])} with "
          f"{dict(zip(VARIABLES, end_ours[1], strict=True))}")
    print(f"shary:                  {rate:>10,.0f} events/s")
    print(f"python-statemachine:    {peer_rate:>10,.0f} events/s")
    print(f"ratio:                  {rate / peer_rate:>10.1f} x")
    if args.json:
        print(json.dumps({"events": args.events, "events_per_s": round(rate),
                          "python_statemachine_events_per_s": round(peer_rate),
                          "ratio_vs_python_statemachine": round(rate / peer_rate, 1)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
