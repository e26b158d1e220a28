"""Acts per second and round trips between two agent processes over Zenoh, against the
in-process port, in the same run.

Two :class:`~shary.transport.zenohport.ZenohPort` s on loopback: this process
(a router holding address ``A``) and a child process (a client holding
``B``), exactly as ``shary team up`` and ``shary agent`` set them up.  Every
message goes the whole way: ``port.send`` (logged to nobody), the outbox,
JSON encoding, Zenoh, the child's queue, decoding and checking against the
schema, delivery on the child's loop.

- throughput: ``--acts`` ``Act`` messages A -> B; the child answers the last
  one with how many it received; acts/s = acts / the time until that answer;
- round trip: ``--pings`` times, A sends an ``Act`` and waits for B's reply
  (one at a time); p50/p99 in milliseconds;
- the peer: the same acts and pings through the in-process
  :class:`~shary.transport.port.MessagePort` (two addresses on one loop);
- log records shared: ``--team-runs`` runs of ``shary team up`` (``--team``:
  the panels team by default, every person its own process; or a weld
  scenario, whose world process logs far more) with the members forwarding
  their log rows to the managers and without (``--no-share-log``),
  alternated; the median wall time of the run itself (joins excluded; for a
  scenario, the whole command's) and the ratio.

Goals: >= 40,000 acts/s and p99 RTT <= 1 ms over Zenoh on loopback.

    python benchmarks/transport.py [--json] [--acts 100000] [--pings 2000] [--team-runs 5]
"""

from __future__ import annotations

import argparse
import json
import socket
import statistics
import subprocess
import sys
import time
from typing import Any

from shary.kernel.loop import EventLoop
from shary.transport.messages import Act, Message
from shary.transport.port import MessagePort

TEAM = "bench"
RAW, RAW_COUNT = "bench/raw", "bench/raw-count"
"""The raw Zenoh peer's keys: the same bytes, no port (no queue, no decoding, no loop)."""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def echo(endpoint: str) -> None:
    """The child: hold ``B``, answer ``PING`` and the flood's ``END`` (with the count)."""
    from shary.transport.zenohport import ZenohPort, session_config

    loop = EventLoop()
    port = ZenohPort(loop, None, team=TEAM, name="B", local=["B"],
                     config=session_config(mode="client", connect=[endpoint]))
    count = 0
    done = False

    def handle(message: Message) -> None:
        nonlocal count, done
        assert isinstance(message, Act)
        if message.act == "PING":
            port.send(Act("B", "A", id=message.id, act="PONG"))
        elif message.act == "FLOOD":
            count += 1
        elif message.act == "END":
            port.send(Act("B", "A", act="COUNT", data={"received": count}))
            count = 0
        elif message.act == "QUIT":
            done = True

    port.subscribe("B", handle)
    raw = [0]

    def raw_sample(sample: Any) -> None:  # the raw peer: count on Zenoh's thread
        if sample.payload.to_bytes() == b"END":
            port.session.put(RAW_COUNT, str(raw[0]).encode())
            raw[0] = 0
        else:
            raw[0] += 1

    flood = port.session.declare_subscriber(RAW, raw_sample)
    try:
        while not done:
            port.pump(0.5)
            loop.run_until_idle()
    finally:
        flood.undeclare()
        port.close()


def _percentile(values: list[float], share: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(share * len(ordered)))]


def inproc(acts: int, pings: int) -> dict[str, float]:
    loop = EventLoop()
    port = MessagePort(loop)
    received = 0
    replies: list[Message] = []

    def b(message: Message) -> None:
        nonlocal received
        received += 1
        if isinstance(message, Act) and message.act == "PING":
            port.send(Act("B", "A", act="PONG"))

    port.subscribe("B", b)
    port.subscribe("A", replies.append)
    start = time.perf_counter()
    for i in range(acts):
        port.send(Act("A", "B", act="FLOOD"))
        if i % 1000 == 999:  # deliver in batches, as the Zenoh side flushes
            loop.run_until_idle()
    loop.run_until_idle()
    assert received == acts
    rate = acts / (time.perf_counter() - start)
    rtts = []
    for _ in range(pings):
        t = time.perf_counter()
        port.send(Act("A", "B", act="PING"))
        loop.run_until_idle()
        rtts.append((time.perf_counter() - t) * 1000)
    assert len(replies) == pings
    return {"msgs_per_s": rate, "p50_rtt_ms": statistics.median(rtts),
            "p99_rtt_ms": _percentile(rtts, 0.99)}


def zenoh(acts: int, pings: int) -> dict[str, float]:
    from shary.transport.zenohport import ZenohPort, session_config

    endpoint = f"tcp/127.0.0.1:{_free_port()}"
    loop = EventLoop()
    port = ZenohPort(loop, None, team=TEAM, name="A", local=["A"],
                     config=session_config(mode="router", listen=[endpoint]))
    replies: list[Act] = []
    port.subscribe("A", replies.append)  # type: ignore[arg-type]
    joined: list[str] = []
    port.on_presence = lambda who, yes: joined.append(who) if yes else None
    child = subprocess.Popen([sys.executable, __file__, "--echo", endpoint])
    try:
        end = time.monotonic() + 60
        while "B" not in joined:
            assert time.monotonic() < end, "the echo process did not join"
            port.pump(0.1)
            loop.run_until_idle()

        def wait_reply() -> Act:
            while not replies:
                port.pump(1.0)
                loop.run_until_idle()
            return replies.pop()

        for _ in range(200):  # warm up: publishers declared, links settled
            port.send(Act("A", "B", act="PING"))
            port.flush()
            wait_reply()
        start = time.perf_counter()
        for i in range(acts):
            port.send(Act("A", "B", act="FLOOD"))
            if i % 1000 == 999:
                port.flush()
        port.send(Act("A", "B", act="END"))
        port.flush()
        count = wait_reply()
        rate = acts / (time.perf_counter() - start)
        assert count.data["received"] == acts, count
        raw_rate = _raw(port, acts)
        rtts = []
        for _ in range(pings):
            t = time.perf_counter()
            port.send(Act("A", "B", act="PING"))
            port.flush()
            wait_reply()
            rtts.append((time.perf_counter() - t) * 1000)
        port.send(Act("A", "B", act="QUIT"))
        port.flush()
        child.wait(timeout=10)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
        port.close()
    return {"msgs_per_s": rate, "p50_rtt_ms": statistics.median(rtts),
            "p99_rtt_ms": _percentile(rtts, 0.99), "raw_msgs_per_s": raw_rate}


def _raw(port: Any, acts: int) -> float:
    """Raw Zenoh between the same two sessions: pre-encoded bytes put, counted on arrival."""
    import queue

    import zenoh

    from shary.transport.wire import encode

    counts: queue.SimpleQueue[int] = queue.SimpleQueue()
    answer = port.session.declare_subscriber(
        RAW_COUNT, lambda sample: counts.put(int(sample.payload.to_string())))
    publisher = port.session.declare_publisher(
        RAW, congestion_control=zenoh.CongestionControl.BLOCK)
    payload = encode(Act("A", "B", act="FLOOD"))
    time.sleep(0.2)  # the child's subscriber is known
    start = time.perf_counter()
    for _ in range(acts):
        publisher.put(payload)
    publisher.put(b"END")
    received = counts.get(timeout=60)
    rate = acts / (time.perf_counter() - start)
    publisher.undeclare()
    answer.undeclare()
    assert received == acts, received
    return rate


PANELS = "tests/data/transport/panels.team.yaml"


def team_runs(runs: int, team: str) -> dict[str, Any]:
    """``shary team up`` with and without the log rows forwarded, alternated."""
    from pathlib import Path

    if team == PANELS:
        team = str(Path(__file__).parent.parent / PANELS)
    walls: dict[bool, list[float]] = {True: [], False: []}
    records = 0
    for _ in range(runs):
        for share in (True, False):
            out = subprocess.run(
                [sys.executable, "-m", "shary", "team", "up", team, "--listen",
                 f"tcp/127.0.0.1:{_free_port()}", "--json",
                 *([] if share else ["--no-share-log"])],
                capture_output=True, text=True, check=True).stdout
            result = json.loads(out.strip().splitlines()[-1])
            assert result["outcome"] == "done", result
            walls[share].append(result.get("run_seconds", result["wall_seconds"]))
            if share:
                records = sum(n for who, n in result.get("shared_records", {}).items()
                              if who != "managers")
    return {"shared_s": statistics.median(walls[True]),
            "unshared_s": statistics.median(walls[False]), "records": records}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    parser.add_argument("--acts", type=int, default=100_000)
    parser.add_argument("--pings", type=int, default=2000)
    parser.add_argument("--team-runs", type=int, default=5,
                        help="team runs with and without the log shared (0: none)")
    parser.add_argument("--team", default=PANELS, metavar="TEAM.yaml|SCENARIO",
                        help=f"the team of those runs (default {PANELS})")
    parser.add_argument("--echo", metavar="ENDPOINT", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.echo:
        echo(args.echo)
        return
    z = zenoh(args.acts, args.pings)
    p = inproc(args.acts, args.pings)
    print(f"zenoh, two processes: {z['msgs_per_s']:10,.0f} acts/s   round trip p50 "
          f"{z['p50_rtt_ms']:.3f} ms  p99 {z['p99_rtt_ms']:.3f} ms")
    print(f"raw zenoh, same bytes: {z['raw_msgs_per_s']:9,.0f} msgs/s  (no port: the "
          "transport's own ceiling on this machine now)")
    print(f"in-process port:      {p['msgs_per_s']:10,.0f} acts/s   round trip p50 "
          f"{p['p50_rtt_ms']:.3f} ms  p99 {p['p99_rtt_ms']:.3f} ms")
    print(f"zenoh port / raw zenoh: {z['msgs_per_s'] / z['raw_msgs_per_s']:.2f}; "
          f"zenoh / in-process: {z['msgs_per_s'] / p['msgs_per_s']:.2f} of the throughput; "
          f"goals: >= 40,000 acts/s ({'met' if z['msgs_per_s'] >= 40_000 else 'missed'}), "
          f"p99 <= 1 ms ({'met' if z['p99_rtt_ms'] <= 1.0 else 'missed'})")
    t = team_runs(args.team_runs, args.team) if args.team_runs else None
    if t is not None:
        rows = f" ({t['records']} rows)" if t["records"] else ""
        print(f"team run ({args.team}), median of {args.team_runs}: "
              f"{t['shared_s']:.3f} s with the log rows forwarded{rows}, "
              f"{t['unshared_s']:.3f} s without: x{t['shared_s'] / t['unshared_s']:.2f}")
    if args.json:
        figures: dict[str, Any] = {
            "zenoh_msgs_per_s": round(z["msgs_per_s"]),
            "inproc_msgs_per_s": round(p["msgs_per_s"]),
            "zenoh_p50_rtt_ms": round(z["p50_rtt_ms"], 3),
            "zenoh_p99_rtt_ms": round(z["p99_rtt_ms"], 3),
            "inproc_p99_rtt_ms": round(p["p99_rtt_ms"], 4),
            "raw_zenoh_msgs_per_s": round(z["raw_msgs_per_s"]),
            "ratio": round(z["msgs_per_s"] / p["msgs_per_s"], 3),
            "port_over_raw": round(z["msgs_per_s"] / z["raw_msgs_per_s"], 3),
            "acts": args.acts, "pings": args.pings}
        if t is not None:
            figures.update(team_run_shared_s=round(t["shared_s"], 3),
                           team_run_unshared_s=round(t["unshared_s"], 3),
                           log_share_ratio=round(t["shared_s"] / t["unshared_s"], 3),
                           shared_records=t["records"])
        print(json.dumps(figures))


if __name__ == "__main__":
    main()
