"""Fixtures for the tests against real ROS 2 nodes.

Each test gets a ROS domain of its own (``ROS_DOMAIN_ID``, inherited by the
processes it starts; each parallel worker has ids of its own) and traffic kept on this
host, so that tests never see each other, nor another engineer's run on the same
machine.  Tests skip, with the reason, only when rclpy cannot be imported.
"""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from shary.ros.env import ros_environment, unavailable

HERE = Path(__file__).resolve().parent
WHY_NOT = unavailable()
needs_ros = pytest.mark.skipif(WHY_NOT is not None, reason=f"ROS 2 tests skipped: {WHY_NOT}")
_first, _, _last = os.environ.get("SHARY_TEST_ROS_DOMAINS", "1-100").partition("-")
_WORKERS = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
_WORKER = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0").removeprefix("gw") or 0)
_DOMAINS = range(int(_first), int(_last or _first) + 1)[_WORKER % _WORKERS::_WORKERS]
"""The domain ids this process's tests take theirs from: ``SHARY_TEST_ROS_DOMAINS``
(``150-230``: runs on one machine at once each keep to their own range; Fast DDS refuses
ids above 232), shared out among pytest-xdist's workers, every worker's ids its own."""
_domains = itertools.count((os.getpid() * 7) % len(_DOMAINS))


@pytest.fixture
def ros_domain(monkeypatch) -> int:
    """A ROS domain id of this test's own, in this process's environment and its children's."""
    domain = _DOMAINS[next(_domains) % len(_DOMAINS)]
    monkeypatch.setenv("ROS_DOMAIN_ID", str(domain))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    return domain


class Process:
    """A Python process of the test's, its stdout lines collected as they come."""

    def __init__(self, *args: str, env: dict[str, str] | None = None):
        self.popen = subprocess.Popen([sys.executable, *args], stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, stdin=subprocess.PIPE, text=True,
                                      env=ros_environment(env), cwd=HERE.parent)
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True, name="test-reader")
        self._reader.start()

    def _read(self) -> None:
        assert self.popen.stdout is not None
        for line in self.popen.stdout:
            self.lines.append(line.rstrip("\n"))

    def wait_for(self, line: str, timeout: float = 30.0) -> None:
        end = time.monotonic() + timeout
        while line not in self.lines:
            if time.monotonic() > end or self.popen.poll() is not None and line not in self.lines:
                raise AssertionError(f"{line!r} never came; the process said: {self.lines}")
            time.sleep(0.01)

    def exit_status(self, timeout: float) -> int:
        """The process's exit status once it ends, or a failure after ``timeout`` seconds
        that says what it printed (where it was when it did not end)."""
        try:
            return self.popen.wait(timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError(f"still running after {timeout:g} s; the process said: "
                                 f"{self.lines}") from None

    def send(self, line: str) -> None:
        assert self.popen.stdin is not None
        self.popen.stdin.write(line + "\n")
        self.popen.stdin.flush()

    def stop(self) -> None:
        if self.popen.poll() is None:
            self.popen.terminate()
            try:
                self.popen.wait(10)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait()


@pytest.fixture
def spawn(ros_domain) -> Iterator:
    """Start ``python ARGS`` in the test's domain; stopped at the end of the test."""
    started: list[Process] = []

    def _spawn(*args: str) -> Process:
        process = Process(*args)
        started.append(process)
        return process

    yield _spawn
    for process in started:
        process.stop()


def run_until(loop, condition, timeout: float = 20.0) -> None:
    """Run a wall-clock loop until ``condition()`` or fail after ``timeout`` seconds."""
    end = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > end:
            raise AssertionError("timed out waiting for the condition")
        loop.run_for(0.01)
