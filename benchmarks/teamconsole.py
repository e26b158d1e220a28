"""What the operator console costs a distributed team: ``shary team up`` with and without
``--console``, in the same run.

Each round runs the same team twice, alternated: plain (``--json``; the wall time
from launch to the verdict's JSON line), and with ``--console`` and
one page on its WebSocket, at ``max`` speed (the wall time from launch to the page's
``ended`` status, the verdict shown).  Both include the agents' processes starting
and joining.  Also printed: what the page was sent (changes, bytes).  The medians
and their ratio (console / plain) are the figures.

    python benchmarks/teamconsole.py [--json] [--runs 3] [--team weld-nominal]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from websockets.sync.client import connect

PANELS = str(Path(__file__).resolve().parents[1] / "tests" / "data" / "transport"
             / "panels.team.yaml")


def _free() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _command(team: str, logs: str) -> list[str]:
    return [sys.executable, "-m", "shary", "team", "up", team, "--listen",
            f"tcp/127.0.0.1:{_free()}", "--log-dir", logs]


def plain(team: str) -> float:
    """Wall seconds to the verdict (the JSON line)."""
    with tempfile.TemporaryDirectory() as logs:
        start = time.perf_counter()
        process = subprocess.Popen([*_command(team, logs), "--json"], text=True,
                                   stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        line = process.stdout.readline() if process.stdout else ""
        wall = time.perf_counter() - start
        process.communicate(timeout=60)
    if process.returncode != 0 or not line.startswith("{"):
        raise SystemExit(f"team up failed: {line[-500:]}")
    return wall


def console(team: str) -> tuple[float, int, int]:
    """Wall seconds to the verdict on the page, changes and bytes the page got."""
    port = _free()
    with tempfile.TemporaryDirectory() as logs:
        start = time.perf_counter()
        process = subprocess.Popen([*_command(team, logs), "--console", "--console-port",
                                    str(port)], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.PIPE, start_new_session=True)
        try:
            while True:
                try:
                    ws = connect(f"ws://127.0.0.1:{port}/ws", open_timeout=5)
                    break
                except OSError:
                    time.sleep(0.05)
            changes = size = 0
            with ws:
                while True:
                    text = ws.recv(timeout=600)
                    size += len(text)
                    message = json.loads(text)
                    if message["type"] == "changes":
                        changes += len(message["changes"])
                    elif message["type"] == "status" and message["status"]["state"] in (
                            "ended", "error"):
                        wall = time.perf_counter() - start
                        if not message["status"]["verdict"]["passed"]:
                            raise SystemExit(f"the run failed: {message['status']}")
                        break
            process.send_signal(signal.SIGINT)
            process.wait(timeout=60)
        finally:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
    return wall, changes, size


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    parser.add_argument("--runs", type=int, default=3, help="rounds (default 3)")
    parser.add_argument("--team", default=PANELS,
                        help="a team file or a team scenario (default: the panels team)")
    args = parser.parse_args()
    plains: list[float] = []
    consoles: list[float] = []
    sent = (0, 0)
    for _ in range(args.runs):
        plains.append(plain(args.team))
        wall, changes, size = console(args.team)
        consoles.append(wall)
        sent = (changes, size)
    figures = {"team": Path(args.team).stem, "runs": args.runs,
               "plain_s": round(statistics.median(plains), 3),
               "console_s": round(statistics.median(consoles), 3),
               "ratio": round(statistics.median(consoles) / statistics.median(plains), 3),
               "changes": sent[0], "bytes_to_page": sent[1]}
    print(f"team up {figures['team']}: plain {figures['plain_s']:.2f} s, with the console "
          f"{figures['console_s']:.2f} s (median of {args.runs}; ratio {figures['ratio']:.2f})")
    print(f"the page got {sent[0]} changes, {sent[1] / 1024:.0f} KiB")
    if args.json:
        print(json.dumps(figures))


if __name__ == "__main__":
    main()
