"""Hostile and broken files are refused cleanly, quickly, with positions."""

from __future__ import annotations

import re
import tempfile
import time
from pathlib import Path

import pytest
from conftest import problems
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from userfiles import yamlsafe


def _refused(shary, path) -> list:
    status, _, err = shary("validate", path)
    assert status == 2, err
    assert "Traceback" not in err
    found = problems(err)
    assert found, err
    assert all(m["file"] == str(path) for m in found)
    return found


def test_yaml_syntax_error_has_position(shary, write):
    path = write("bad.yaml", "scheme: x\nstates:\n  a: {on: [\n")
    (m,) = _refused(shary, path)
    assert "YAML syntax" in m["message"]
    assert int(m["line"]) >= 3


def test_wrong_top_level_type(shary, write):
    (m,) = _refused(shary, write("list.yaml", "- a\n- b\n"))
    assert "expected a mapping" in m["message"]


@pytest.mark.parametrize("text", ["", "   \n", "# only a comment\n"])
def test_empty_file(shary, write, text):
    (m,) = _refused(shary, write("empty.yaml", text))
    assert "empty file" in m["message"]


def test_non_utf8_bytes_position(shary, write):
    (m,) = _refused(shary, write("latin1.yaml", b"scheme: x\ndoc: caf\xe9\n"))
    assert "not UTF-8" in m["message"]
    assert (m["line"], m["col"]) == ("2", "9")


def test_alias_bomb_is_stopped_quickly(shary, write):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    for i in range(1, 12):
        prev = f"*a{i - 1}"
        lines.append(f"a{i}: &a{i} [{', '.join([prev] * 10)}]")
    path = write("bomb.yaml", "\n".join(lines) + "\nscheme: x\nstates: {a: {}}\n")
    start = time.process_time()
    (m,) = _refused(shary, path)
    assert time.process_time() - start < 5
    assert "alias bomb" in m["message"]


def test_very_deep_nesting(shary, write):
    (m,) = _refused(shary, write("deep.yaml", "a: " + "[" * 5000 + "]" * 5000 + "\n"))
    assert "nesting deeper" in m["message"]


def test_huge_file(shary, write):
    path = write("huge.yaml", "doc: '" + "x" * (yamlsafe.MAX_BYTES + 10) + "'\n")
    (m,) = _refused(shary, path)
    assert "limit" in m["message"]


@pytest.mark.parametrize("tag", ["!!python/object/apply:os.system ['touch /tmp/pwned']",
                                 "!!python/name:os.system", "!custom 1", "!!binary aGVsbG8="])
def test_unsafe_tags_are_refused(shary, write, tag):
    (m,) = _refused(shary, write("tag.yaml", f"scheme: x\ndoc: {tag}\nstates: {{a: {{}}}}\n"))
    assert "is not allowed" in m["message"]
    assert (m["line"], m["col"]) == ("2", "6")


def test_duplicate_keys_all_reported(shary, write):
    path = write("dup.yaml", """\
        scheme: x
        states:
          a: {on: {go: b, go: a}}
          b: {}
        scheme: y
        """)
    found = _refused(shary, path)
    messages = [m["message"] for m in found]
    assert sum("duplicate key 'go'" in msg for msg in messages) == 1
    assert sum("duplicate key 'scheme'" in msg for msg in messages) == 1


def test_several_documents_refused(shary, write):
    (m,) = _refused(shary, write("two.yaml", "scheme: x\n---\nscheme: y\n"))
    assert "more than one YAML document" in m["message"]


def test_merge_keys_refused(shary, write):
    found = _refused(shary, write("merge.yaml", "base: &b {a: 1}\nother:\n  <<: *b\n"))
    assert any("merge keys" in m["message"] for m in found)


def test_positions_of_values_and_keys():
    located = yamlsafe.load_text("scheme: x\nstates:\n  a:\n    on: {go: b}\n", "f.yaml")
    assert located.at(("states", "a", "on", "go")) == (4, 14)
    assert located.key_at(("states", "a")) == (3, 3)
    assert located.data["states"]["a"]["on"] == {"go": "b"}


def test_yaml_12_booleans_only():
    located = yamlsafe.load_text("on: {yes: a}\nlist: [on, off, yes, no, true, False]\n")
    assert located.data == {"on": {"yes": "a"}, "list": ["on", "off", "yes", "no", True, False]}


# -- properties (hypothesis): any bytes are a value or positioned problems --------------

_BREAKS = re.compile(r"\r\n|[\r\n\x85\u2028\u2029]")
"""The line breaks YAML counts lines by."""

_YAMLISH = st.lists(st.sampled_from(list("ab1.-:[]{}&*!|>'\"#%@`?,\n\t ") +
                                    ["\r", "\x85", "\u2028", "\ufeff", "é", "\x00", "<<",
                                     "!!python/object", "1e999", ".nan", "- ", ": ", "\n  "]),
                    max_size=80).map("".join)
"""Text made of YAML's significant pieces: reaches the parser's corners faster than bytes."""


def _lines(text: str) -> list[str]:
    """The lines an editor shows (a final line break opens none)."""
    lines = _BREAKS.split(text)
    return lines[:-1] if len(lines) > 1 and lines[-1] == "" else lines


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(st.binary(max_size=300), _YAMLISH.map(lambda t: t.encode("utf-8"))))
def test_any_bytes_load_or_refuse_in_place(raw: bytes) -> None:
    """Any bytes: a located value, or a FileError whose every position is in the file
    (never another exception)."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "any.yaml"
        path.write_bytes(raw)
        try:
            yamlsafe.load_file(path)
        except yamlsafe.FileError as err:
            assert err.problems
            text = raw.decode("utf-8", "replace").removeprefix("\ufeff")
            lines = _lines(text)
            for problem in err.problems:
                assert problem.file == str(path)
                assert 1 <= problem.line <= len(lines), (problem, len(lines))
                assert 1 <= problem.col <= len(lines[problem.line - 1]) + 1, problem


def test_positions_inside_strings():
    """An expression's error lands on its column when the string is written as it reads;
    at the string's start when escapes or folding would make columns lie."""
    located = yamlsafe.load_text('a: x + y\nb: "x + y"\nc: "x \\" + y"\nd: >\n  x +\n  y\n')

    def where(key: str, offset: int) -> tuple[int, int]:
        problem = located.problem_inside((key,), offset, "m")
        return problem.line, problem.col

    assert where("a", 4) == (1, 8)
    assert where("b", 4) == (2, 9)
    assert where("c", 5) == (3, 4)
    assert where("d", 2) == (4, 4)


def test_what_dump_writes_load_reads_back_plain_where_it_can():
    """The project's one YAML writer quotes a string only where the loader (YAML 1.2's
    booleans) would read something else: ``on`` and ``yes`` stay plain."""
    data = {"on": {"H-AGREE": "end", "no": "off"}, "yes": ["true", "null", "1.5", "on"],
            "flag": True, "n": 3, "none": None, "text": "a: b"}
    text = yamlsafe.dump(data)
    assert "on:\n  H-AGREE: end\n  no: off\n" in text and "yes:\n" in text
    assert "'on'" not in text and "'true'" in text
    assert yamlsafe.load_text(text, "t.yaml").data == data
