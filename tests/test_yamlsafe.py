"""Hostile and broken files are refused cleanly, quickly, with positions."""

from __future__ import annotations

import time

import pytest
from conftest import problems

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
