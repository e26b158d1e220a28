"""Where output goes: every command that writes refuses a place it cannot write, clearly.

An output path has no line, so a refusal reads ``PATH: error: what is wrong
(what to do)`` with exit status 2 (docs/architecture.md, "User files").  The
cases are made for real wherever the machine allows: a file where a folder is
wanted and the reverse, a path through a file, ``/dev/full`` (a disk that is
always full), a read-only mount or a folder without write permission, a
process file-size limit (which SQLite reports as ``disk I/O error``), a tiny
file system that fills up.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from hostile import HOSTILE, MAX_MB, MAX_SECONDS, Outcome, run_inprocess

sys.path.insert(0, str(HOSTILE / "log"))
from make_corpus import good_log  # noqa: E402

from userfiles.outputs import OutputError, output_file, write_output  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
PROBLEM = REPO / "planner" / "problems" / "clean-up.yaml"
CHART = """<scxml xmlns="http://www.w3.org/2005/07/scxml" version="1.0" initial="a">
  <state id="a"><transition event="go" target="b"/></state>
  <final id="b"/>
</scxml>
"""


def assert_output_refused(outcome: Outcome, path: str | Path, message: str) -> None:
    """Exit 2, no traceback, ``PATH: error: MESSAGE (what to do)``, within the rule."""
    where = f"\n--- stderr ---\n{outcome.err[-2000:]}\n--- stdout ---\n{outcome.out[-500:]}"
    assert "Traceback" not in outcome.err + outcome.out, where
    assert outcome.status == 2, f"exit status {outcome.status}, not 2{where}"
    line = re.compile(rf"^{re.escape(str(path))}: error: (?P<message>.+) \((?P<hint>[^()]+)\)$")
    found = [m for m in map(line.match, outcome.err.splitlines()) if m]
    assert found, f"no line '{path}: error: … (what to do)'{where}"
    assert any(re.search(message, m["message"]) for m in found), \
        f"no message matches {message!r}{where}"
    assert outcome.seconds < MAX_SECONDS and outcome.peak_mb < MAX_MB, where


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("inputs")
    good_log(folder / "run.sqlite")
    (folder / "chart.scxml").write_text(CHART, encoding="utf-8")
    return {"log": folder / "run.sqlite", "chart": folder / "chart.scxml"}


# name -> (suffix of the file it writes, argv given the output path)
FILE_COMMANDS: dict[str, tuple[str, Callable[[dict[str, Path], Path], list[object]]]] = {
    "render scheme": (".svg", lambda i, out: ["render", "scheme", "give-object", "-o", out]),
    "render tree": (".svg", lambda i, out: ["render", "tree", i["log"], "-o", out]),
    "import-scxml": (".yaml", lambda i, out: ["import-scxml", i["chart"], "-o", out]),
    "plan": (".dot", lambda i, out: ["plan", "living-room", PROBLEM, "--render", "tree",
                                     "-o", out]),
    "log --jsonl": (".jsonl", lambda i, out: ["log", i["log"], "--jsonl", out]),
}


def run_command(name: str, inputs: dict[str, Path], out: Path) -> Outcome:
    return run_inprocess(*FILE_COMMANDS[name][1](inputs, out))


@pytest.mark.parametrize("name", FILE_COMMANDS)
def test_each_command_writes_where_it_can(name: str, inputs: dict[str, Path], tmp_path: Path):
    out = tmp_path / "new" / "folder" / f"out{FILE_COMMANDS[name][0]}"
    outcome = run_command(name, inputs, out)
    assert outcome.status in (0, 1), outcome.err  # plan: 1 would mean "no valid plan"
    assert out.stat().st_size > 0
    assert [p.name for p in out.parent.iterdir()] == [out.name]  # no partial file left


@pytest.mark.parametrize("name", FILE_COMMANDS)
def test_a_path_through_a_file(name: str, inputs: dict[str, Path], tmp_path: Path):
    (tmp_path / "notes.txt").write_text("mine\n")
    out = tmp_path / "notes.txt" / f"out{FILE_COMMANDS[name][0]}"
    assert_output_refused(run_command(name, inputs, out), out,
                          f"^{re.escape(str(tmp_path / 'notes.txt'))} is not a folder, so "
                          "nothing can be written under it$")
    assert (tmp_path / "notes.txt").read_text() == "mine\n"


@pytest.mark.parametrize("name", FILE_COMMANDS)
def test_a_folder_where_a_file_is_wanted(name: str, inputs: dict[str, Path], tmp_path: Path):
    assert_output_refused(run_command(name, inputs, tmp_path), tmp_path,
                          "^this is a folder, not a file$")


@pytest.mark.parametrize("name", FILE_COMMANDS)
def test_a_full_disk(name: str, inputs: dict[str, Path], tmp_path: Path):
    """/dev/full refuses every write with ENOSPC, for every user."""
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full here")
    out = tmp_path / f"full{FILE_COMMANDS[name][0]}"
    out.symlink_to("/dev/full")
    assert_output_refused(run_command(name, inputs, out), out, "^the disk is full$")


@pytest.mark.parametrize("name", FILE_COMMANDS)
def test_a_folder_the_system_will_not_let_us_write(name: str, inputs: dict[str, Path]):
    """/sys cannot be written, not even by root (EACCES, or EPERM for a new folder)."""
    if not os.path.isdir("/sys/kernel"):
        pytest.skip("no /sys here")
    for out in (Path(f"/sys/shary-test{FILE_COMMANDS[name][0]}"),
                Path(f"/sys/shary-test/out{FILE_COMMANDS[name][0]}")):
        assert_output_refused(run_command(name, inputs, out), out,
                              "^(no permission to write here|the system does not allow "
                              "writing here)$")


@pytest.mark.parametrize("name", FILE_COMMANDS)
def test_a_folder_whose_entries_the_system_makes_up(name: str, inputs: dict[str, Path]):
    """/proc takes no new entry, not even root's (ENOENT, "no such file"): the message
    says so, not that a folder on the way is missing."""
    if not os.path.isdir("/proc/self"):
        pytest.skip("no /proc here")
    for out in (Path(f"/proc/shary-test{FILE_COMMANDS[name][0]}"),
                Path(f"/proc/shary-test/out{FILE_COMMANDS[name][0]}")):
        assert_output_refused(run_command(name, inputs, out), out,
                              "^(nothing can be made in /proc: the system makes up what is "
                              "in it|no permission to write here)$")


@pytest.mark.parametrize("name", FILE_COMMANDS)
def test_a_link_that_leads_nowhere(name: str, inputs: dict[str, Path], tmp_path: Path):
    link = tmp_path / "gone"
    link.symlink_to(tmp_path / "nowhere")
    for out in (link / f"out{FILE_COMMANDS[name][0]}", link / "sub" / "out"):
        assert_output_refused(run_command(name, inputs, out), out,
                              f"^{link} is a link to {tmp_path / 'nowhere'}, which does not "
                              f"exist$")


@contextmanager
def mounted(folder: Path, options: str) -> Iterator[Path]:
    """A tmpfs at ``folder`` (root can mount; others skip), unmounted afterwards."""
    folder.mkdir(exist_ok=True)
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)],
                          capture_output=True, check=False) if os.geteuid() == 0 else None
    if done is None or done.returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root)")
    try:
        yield folder
    finally:  # lazily if a file is still open: never leave a mount behind
        subprocess.run(["umount", "--lazy", str(folder)], check=True)


@contextmanager
def read_only(tmp_path: Path) -> Iterator[Path]:
    """A folder this process cannot write: a read-only mount as root (no permission bit
    stops root), a folder without write permission otherwise."""
    if os.geteuid() == 0:
        with mounted(tmp_path / "ro", "ro,size=1m") as folder:
            yield folder
        return
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        yield folder
    finally:
        folder.chmod(0o755)


@pytest.mark.parametrize("name", FILE_COMMANDS)
def test_a_read_only_folder(name: str, inputs: dict[str, Path], tmp_path: Path):
    with read_only(tmp_path) as folder:
        for out in (folder / f"out{FILE_COMMANDS[name][0]}",
                    folder / "sub" / f"out{FILE_COMMANDS[name][0]}"):
            assert_output_refused(run_command(name, inputs, out), out,
                                  "^(the file system is read-only|no permission to write "
                                  "here)$")


# -- shary run --out: a folder, and the context log written during the run ------------


def test_run_out_naming_an_existing_file(tmp_path: Path):
    out = tmp_path / "notes.txt"
    out.write_text("mine\n")
    assert_output_refused(run_inprocess("run", "give-bottle", "--out", out, "--quiet"), out,
                          "^this is a file, not a folder$")
    assert out.read_text() == "mine\n"


def test_run_out_through_a_file_and_in_a_read_only_folder(tmp_path: Path):
    (tmp_path / "notes.txt").write_text("mine\n")
    out = tmp_path / "notes.txt" / "run"
    assert_output_refused(run_inprocess("run", "give-bottle", "--out", out, "--quiet"), out,
                          "is not a folder, so nothing can be made under it$")
    with read_only(tmp_path) as folder:
        for out in (folder, folder / "run"):
            assert_output_refused(run_inprocess("run", "give-bottle", "--out", out, "--quiet"),
                                  out, "^(the file system is read-only|no permission to "
                                  "write here)$")


def test_run_out_in_proc_or_through_a_broken_link(tmp_path: Path):
    link = tmp_path / "gone"
    link.symlink_to(tmp_path / "nowhere")
    for out in (Path("/proc/forbidden"), link, link / "run"):
        if out.parts[1] == "proc" and not os.path.isdir("/proc/self"):
            continue
        assert_output_refused(run_inprocess("run", "give-bottle", "--out", out, "--quiet"),
                              out, "^(nothing can be made in /proc|.* is a link to .*, which "
                              "does not exist$|no permission to write here$)")


LIMITED = """
import resource, sys
resource.setrlimit(resource.RLIMIT_FSIZE, (40_000, 40_000))
from shary.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.skipif(sys.platform == "win32", reason="RLIMIT_FSIZE is POSIX")
def test_a_file_size_limit_while_the_run_logs_is_sqlites_disk_io_error(tmp_path: Path):
    """Past the limit every write fails with EFBIG (Python ignores SIGXFSZ), which SQLite
    reports as 'disk I/O error': the message names the log and says what it means."""
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-c", LIMITED, "run", "give-bottle", "--out",
                           str(out), "--quiet"], capture_output=True, text=True,
                          timeout=6 * MAX_SECONDS)
    outcome = Outcome(done.returncode, done.stdout, done.stderr, 0.0, 0.0)
    assert_output_refused(outcome, out / "log.sqlite",
                          "^cannot write the context log: SQLite reports 'disk I/O error'")


def test_a_disk_that_fills_up_during_the_run(tmp_path: Path):
    with mounted(tmp_path / "tiny", "size=48k") as folder:
        out = folder / "run"
        outcome = run_inprocess("run", "give-bottle", "--out", out, "--quiet")
        assert_output_refused(outcome, out / "log.sqlite", "^the disk is full$")


# -- whole or nothing ---------------------------------------------------------------


def test_a_failed_write_keeps_the_last_good_file(tmp_path: Path):
    with mounted(tmp_path / "small", "size=64k") as folder:
        out = folder / "tree.svg"
        out.write_text("the last good drawing\n")
        with pytest.raises(OutputError, match="the disk is full"):
            write_output(out, "x" * 200_000)
        assert out.read_text() == "the last good drawing\n"
        assert sorted(p.name for p in folder.iterdir()) == ["tree.svg"]


def test_an_error_while_streaming_keeps_the_target(tmp_path: Path):
    from userfiles.outputs import open_output

    out = tmp_path / "events.jsonl"
    out.write_text("old\n")
    with pytest.raises(KeyError), open_output(out) as stream:
        stream.write("half of it\n")
        raise KeyError("the producer failed")
    assert out.read_text() == "old\n" and sorted(tmp_path.iterdir()) == [out]


def test_a_replaced_file_keeps_its_mode_and_a_link_its_target(tmp_path: Path):
    target = tmp_path / "real.svg"
    target.write_text("old")
    target.chmod(0o640)
    link = tmp_path / "link.svg"
    link.symlink_to(target)
    write_output(link, "new")
    assert link.is_symlink() and target.read_text() == "new"
    assert target.stat().st_mode & 0o777 == 0o640


def test_output_file_creates_the_missing_folders_and_nothing_else(tmp_path: Path):
    out = output_file(tmp_path / "a" / "b" / "c.svg")
    assert out.parent.is_dir() and not out.exists()


@pytest.mark.parametrize("name", ["import-scxml", "log --jsonl"])
def test_writing_over_the_file_being_read_is_refused(name: str, tmp_path: Path):
    log, chart = tmp_path / "run.sqlite", tmp_path / "chart.scxml"
    good_log(log)
    chart.write_text(CHART, encoding="utf-8")
    source = chart if name == "import-scxml" else log
    before = source.read_bytes()
    outcome = run_command(name, {"log": log, "chart": chart}, source)
    assert_output_refused(outcome, source, f"^this is {re.escape(str(source))}, which the "
                          "command reads$")
    assert source.read_bytes() == before
