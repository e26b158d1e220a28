"""Scheme engine throughput, against raw ``transitions`` in the same run.

A hierarchical scheme of 52 states (4 phases x 3 groups x 3 leaves, with
transitions at every level) runs in 1,000 live instances; a seeded stream of
events (some that no state takes) is spread over them.  The same chart is
built on ``transitions``' HierarchicalMachine, one machine with 1,000 models,
and fed the same stream; both must end in the same configurations, instance
by instance, or the run fails.

Figures: events per second for both and their ratio, creation time per
instance, memory per instance (tracemalloc, once the shared machine is warm).

    python benchmarks/schemes.py [--json] [--instances N] [--events N]
"""

from __future__ import annotations

import argparse
import gc
import json
import random
import statistics
import sys
import time
import tracemalloc

from transitions.extensions import HierarchicalMachine

from shary import compile_scheme
from shary.io.schemes import parse_scheme
from userfiles.yamlsafe import load_text

PHASES, GROUPS, LEAVES = 4, 3, 3
EVENTS = ["next"] * 6 + ["skip"] * 2 + ["phase", "noise"]


def chart_yaml() -> str:
    """The benchmark chart in the scheme format."""
    lines = ["scheme: bench", "initial: p0", "states:"]
    for p in range(PHASES):
        lines += [f"  p{p}:", f"    initial: p{p}g0",
                  f"    on: {{phase: p{(p + 1) % PHASES}}}", "    states:"]
        for g in range(GROUPS):
            lines += [f"      p{p}g{g}:", f"        initial: p{p}g{g}l0",
                      f"        on: {{skip: p{p}g{(g + 1) % GROUPS}}}", "        states:"]
            for leaf in range(LEAVES):
                nxt = f"p{p}g{g}l{(leaf + 1) % LEAVES}"
                lines.append(f"          p{p}g{g}l{leaf}: {{on: {{next: {nxt}}}}}")
    return "\n".join(lines) + "\n"


def raw_machine() -> HierarchicalMachine:
    """The same chart on transitions' HierarchicalMachine."""
    states = [{"name": f"p{p}", "initial": "g0", "children": [
        {"name": f"g{g}", "initial": "l0", "children": [f"l{leaf}" for leaf in range(LEAVES)]}
        for g in range(GROUPS)]} for p in range(PHASES)]
    transitions = []
    for p in range(PHASES):
        transitions.append(["phase", f"p{p}", f"p{(p + 1) % PHASES}"])
        for g in range(GROUPS):
            transitions.append(["skip", f"p{p}_g{g}", f"p{p}_g{(g + 1) % GROUPS}"])
            for leaf in range(LEAVES):
                transitions.append(["next", f"p{p}_g{g}_l{leaf}",
                                    f"p{p}_g{g}_l{(leaf + 1) % LEAVES}"])
    return HierarchicalMachine(model=None, states=states, transitions=transitions,
                               initial="p0", ignore_invalid_triggers=True,
                               auto_transitions=False)


class Model:
    """A plain model for the raw machine."""


def stream(instances: int, events: int, seed: int = 7) -> list[tuple[int, str]]:
    rng = random.Random(seed)
    return [(rng.randrange(instances), rng.choice(EVENTS)) for _ in range(events)]


def run_ours(compiled, instances: int, events: list[tuple[int, str]]):
    runs = [compiled.start() for _ in range(instances)]
    start = time.perf_counter()
    for index, name in events:
        runs[index].send(name)
    elapsed = time.perf_counter() - start
    return elapsed, [r.configuration[0] for r in runs]


def run_raw(instances: int, events: list[tuple[int, str]]):
    machine = raw_machine()
    models = [Model() for _ in range(instances)]
    for model in models:
        machine.add_model(model)
    start = time.perf_counter()
    for index, name in events:
        if name != "noise":  # HSM raises on an event it was never told of; shary ignores it
            models[index].trigger(name)
    elapsed = time.perf_counter() - start
    return elapsed, [m.state.replace("_", "") for m in models]


def creation(compiled, count: int) -> float:
    gc.collect()
    start = time.perf_counter()
    runs = [compiled.start() for _ in range(count)]
    elapsed = time.perf_counter() - start
    del runs
    return elapsed / count * 1000


def raw_creation(count: int) -> float:
    machine = raw_machine()
    models = [Model() for _ in range(count)]
    start = time.perf_counter()
    for model in models:
        machine.add_model(model)
    return (time.perf_counter() - start) / count * 1000


def memory(compiled, count: int, events: list[tuple[int, str]]) -> float:
    warm = [compiled.start() for _ in range(count)]
    for index, name in events:
        warm[index % count].send(name)
    del warm
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    runs = [compiled.start() for _ in range(count)]
    for index, name in events:
        runs[index % count].send(name)
    after = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    return (after - before) / count


def raw_memory(count: int) -> float:
    machine = raw_machine()
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    models = [Model() for _ in range(count)]
    for model in models:
        machine.add_model(model)
    after = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    return (after - before) / count


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="end with one JSON line of figures")
    parser.add_argument("--instances", type=int, default=1000)
    parser.add_argument("--events", type=int, default=50_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    scheme = parse_scheme(load_text(chart_yaml(), "bench.yaml"))
    compiled = compile_scheme(scheme)
    events = stream(args.instances, args.events)
    ours, raw = [], []
    for _ in range(args.repeat):
        t_ours, conf_ours = run_ours(compiled, args.instances, events)
        t_raw, conf_raw = run_raw(args.instances, events)
        if conf_ours != conf_raw:
            print("MISMATCH: the two engines disagree on the final configurations",
                  file=sys.stderr)
            return 1
        ours.append(t_ours)
        raw.append(t_raw)
    events_per_s = args.events / statistics.median(ours)
    raw_per_s = args.events / statistics.median(raw)
    create_ms = statistics.median(creation(compiled, 10_000) for _ in range(args.repeat))
    raw_create_ms = raw_creation(1000)
    bytes_per = memory(compiled, 10_000, events[:20_000])
    raw_bytes = raw_memory(1000)
    figures = {
        "states": len(scheme.states),
        "instances": args.instances,
        "events": args.events,
        "events_per_s": round(events_per_s),
        "raw_hsm_events_per_s": round(raw_per_s),
        "ratio_vs_raw_hsm": round(events_per_s / raw_per_s, 2),
        "create_ms_per_instance": round(create_ms, 4),
        "raw_hsm_add_model_ms": round(raw_create_ms, 4),
        "bytes_per_instance": round(bytes_per),
        "raw_hsm_bytes_per_model": round(raw_bytes),
        "flat_states_compiled": compiled.flat_states,
    }
    print(f"chart: {figures['states']} states, {args.instances} live instances, "
          f"{args.events} events (median of {args.repeat})")
    print(f"shary:               {events_per_s:12,.0f} events/s")
    print(f"transitions HSM:     {raw_per_s:12,.0f} events/s")
    print(f"ratio:               {events_per_s / raw_per_s:12.2f} x")
    print(f"creation:            {create_ms:12.4f} ms/instance "
          f"(HSM add_model {raw_create_ms:.4f} ms)")
    print(f"memory:              {bytes_per:12,.0f} bytes/instance "
          f"(HSM {raw_bytes:,.0f} bytes/model)")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
