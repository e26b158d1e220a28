"""Hostile Turtle: every refusal at a line the file has, big files within the limits, no fetching.

The corpus in ``tests/hostile/turtle/`` is checked through ``shary validate
FILE.ttl`` as a user would run it; each file was mishandled before Turtle
was read with Oxigraph's parser (accepted though not Turtle, a line past the
end of the file, a negative column, a Python error for a message, a
misleading message or position).  Files too big for git (a million dense
triples, a file at the triple limit, nesting 200,000 deep, a file past the
size limit) are generated in ``tmp_path`` and run in a child process, whose
time and peak memory the harness measures.
"""

from __future__ import annotations

import socket
import urllib.request

import pytest
from hostile import HOSTILE, MAX_MB, MAX_SECONDS, assert_refused, run_inprocess, run_subprocess

from shary.facts.database import FactDatabase
from shary.facts.turtle import MAX_TURTLE_BYTES, MAX_TURTLE_TRIPLES

TURTLE = HOSTILE / "turtle"
W = "@prefix w: <http://shary.dev/world#> .\n"

EXPECTED = {
    "bad-escape": r"escape sequence '\\uZZZZ'",
    "crlf-missing-dot": "Unexpected end",
    "dangling-semicolon": "Unexpected end",
    "dangling-subject": "Unexpected end",
    "ill-typed-boolean": r'ill-typed literal: "maybe"\^\^<.*#boolean>',
    "iri-with-spaces": "Invalid IRI code point ' '",
    "literal-subject": "not a valid subject",
    "missing-final-dot": "Unexpected end",
    "missing-final-dot-newline": "Unexpected end",
    "reifier-annotation": "triple terms .* are not facts",
    "sparql-prefix-then-open-iri": "Unexpected end of file",
    "triple-term": "triple terms .* are not facts",
    "unterminated-iri": "Unexpected end of file",
    "unterminated-long-string": "Unexpected end of file",
}

POSITIONS = {  # where the mistake is, not past the end of the file
    "missing-final-dot": (2, 24),
    "missing-final-dot-newline": (3, 21),
    "crlf-missing-dot": (3, 21),
    "dangling-subject": (7, 6),
    "unterminated-long-string": (2, 18),
    "ill-typed-boolean": (3, 17),
    "triple-term": (2, 12),
    "reifier-annotation": (3, 22),
}


@pytest.fixture(autouse=True, scope="module")
def warm() -> None:
    """Pay for imports once, outside the measured refusals."""
    run_inprocess("validate", TURTLE / "literal-subject.ttl")


def test_every_corpus_file_has_an_expectation():
    assert {p.stem for p in TURTLE.glob("*.ttl")} == set(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_hostile_turtle_is_refused(name):
    path = TURTLE / f"{name}.ttl"
    outcome = run_inprocess("validate", path)
    assert_refused(outcome, path, message=EXPECTED[name])
    if name in POSITIONS:
        [problem] = outcome.problems()
        assert (int(problem["line"]), int(problem["col"])) == POSITIONS[name], outcome.err


def test_a_million_dense_triples_are_refused_at_the_limit(tmp_path):
    path = tmp_path / "dense.ttl"
    path.write_text(W + "w:a w:p " + ",".join(map(str, range(1_000_000))) + " .\n")
    assert path.stat().st_size < MAX_TURTLE_BYTES  # the triple limit, not the size, refuses it
    outcome = run_subprocess("validate", path)
    assert_refused(outcome, path, message=f"more than {MAX_TURTLE_TRIPLES} triples; "
                                          f"the limit is {MAX_TURTLE_TRIPLES}")


def test_a_file_at_the_triple_limit_is_loaded_within_the_limits(tmp_path):
    path = tmp_path / "big.ttl"
    path.write_text(W + "".join(f"w:thing{i} w:isOn w:shelf{i % 97} ; w:weight {i} .\n"
                                for i in range(MAX_TURTLE_TRIPLES // 2)))
    outcome = run_subprocess("validate", path)
    assert outcome.status == 0, outcome.err
    assert outcome.seconds < MAX_SECONDS and outcome.peak_mb < MAX_MB, outcome


def test_a_file_past_the_size_limit_is_refused_unread(tmp_path):
    path = tmp_path / "huge.ttl"
    path.write_text(W + '#' + "x" * MAX_TURTLE_BYTES + "\n")
    outcome = run_subprocess("validate", path)
    assert_refused(outcome, path, message=f"the limit is {MAX_TURTLE_BYTES} bytes")


@pytest.mark.parametrize("nesting", ["[ w:p ", "( "])
def test_deep_nesting_is_refused_without_recursion(tmp_path, nesting):
    path = tmp_path / "deep.ttl"
    path.write_text(W + "w:a w:p " + nesting * 200_000 + "\n")  # never closed
    outcome = run_subprocess("validate", path)
    assert_refused(outcome, path, message="Unexpected end|the limit is")


def test_turtle_fetches_nothing(tmp_path, monkeypatch):
    """Prefixes, bases and owl:imports are names: nothing is fetched or read."""
    def refuse(*args, **kwargs):
        raise AssertionError(f"network access attempted: {args}")

    monkeypatch.setattr(socket.socket, "connect", refuse)
    monkeypatch.setattr(socket, "create_connection", refuse)
    monkeypatch.setattr(urllib.request, "urlopen", refuse)
    secret = tmp_path / "secret.ttl"
    secret.write_text(W + "w:secret w:is w:leaked .\n")
    path = tmp_path / "world.ttl"
    path.write_text(
        "@prefix owl: <http://www.w3.org/2002/07/owl#> .\n"
        "@prefix remote: <http://203.0.113.7/ontology.ttl#> .\n"
        f"@base <{tmp_path.as_uri()}/> .\n"
        "<world> owl:imports <http://203.0.113.7/ontology.ttl>, <secret.ttl> .\n"
        "<cup> remote:isOn <table> .\n")
    db = FactDatabase()
    assert db.load_turtle(path) == 3
    assert not db.holds("secret", "is", "leaked")
    assert db.holds(f"{tmp_path.as_uri()}/cup", "http://203.0.113.7/ontology.ttl#isOn",
                    f"{tmp_path.as_uri()}/table")
