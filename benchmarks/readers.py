"""The safe, located YAML loader against PyYAML's own safe loader, on the same text.

``userfiles.yamlsafe`` does more than PyYAML's ``safe_load``: an event pass
(depth, tags, documents, the format's size limits), positions for every value
and key, duplicate keys, finite and bounded numbers.  Measured, in CPU time of
this process (best of ``--repeat``; the machines here are shared):

* a big valid file (about 0.9 MB, 20,000 list items): ours against
  ``yaml.load(text, CSafeLoader)`` (the peer: libyaml's C loader, no positions,
  no limits), and the ratio;
* the refusal of a 10,000-person scenario (``people:`` at most 50): ours, which
  stops in the event pass after the 51st person, against the peer's full load
  of the same text (what any loader that checks sizes after loading pays).

    python benchmarks/readers.py [--json] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable

import yaml

from userfiles import yamlsafe
from userfiles.errors import FileError

PEER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def best(repeat: int, run: Callable[[], object]) -> float:
    """Least CPU seconds of ``repeat`` runs."""
    times = []
    for _ in range(repeat):
        start = time.process_time()
        run()
        times.append(time.process_time() - start)
    return min(times)


def big_file() -> str:
    items = "".join(f"  - {{name: item{i}, at: [{i % 7}.5, 2.0], tags: [a, b]}}\n"
                    for i in range(20_000))
    return "items:\n" + items


def crowd() -> str:
    people = "".join(f"  p{i}: {{at: sofa-seat, profile: cooperative}}\n" for i in range(10_000))
    return f"scenario: crowd\npeople:\n{people}expect: {{acts: [ASK-TASK]}}\n"


def refuse(text: str) -> None:
    try:
        yamlsafe.load_text(text, "crowd.yaml", sizes={("people",): 50})
    except FileError:
        return
    raise AssertionError("the crowd was not refused")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    figures: dict[str, float] = {}

    text = big_file()
    ours = best(args.repeat, lambda: yamlsafe.load_text(text, "big.yaml"))
    peer = best(args.repeat, lambda: yaml.load(text, Loader=PEER))
    figures.update(big_kb=len(text) / 1024, big_ours_s=ours, big_peer_s=peer,
                   big_ratio=ours / peer)
    print(f"valid file of {len(text) / 1024:.0f} KB: ours {ours * 1000:.0f} ms, PyYAML "
          f"{PEER.__name__} {peer * 1000:.0f} ms: x{ours / peer:.2f} (positions, limits, "
          "duplicate keys, bounded numbers)")

    text = crowd()
    ours = best(args.repeat, lambda: refuse(text))
    peer = best(args.repeat, lambda: yaml.load(text, Loader=PEER))
    figures.update(crowd_kb=len(text) / 1024, crowd_refused_s=ours, crowd_peer_load_s=peer,
                   crowd_ratio=ours / peer)
    print(f"10,000-person scenario ({len(text) / 1024:.0f} KB): refused in {ours * 1000:.1f} ms; "
          f"PyYAML loads it in {peer * 1000:.0f} ms: x{ours / peer:.3f}")
    if args.json:
        print(json.dumps({k: round(v, 6) for k, v in figures.items()}))


if __name__ == "__main__":
    main()
