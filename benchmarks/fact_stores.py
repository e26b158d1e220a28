"""Fact stores for the kernel's workload: one triple added or removed, and whether it changed.

The fact database must tell, for every perception update, whether the fact
is new (or was there) and then deliver an event; SPARQL is only for
recipe-time questions.  Measured here, on 10,000 people looking at the robot
and away (20,000 changes on a perspective of 20,000 triples):

* rdflib ``Dataset``, a named graph per perspective, ``len`` before and after
  (the fact database's store before Oxigraph);
* raw rdflib ``Graph.add``/``remove`` (the kernel benchmark's peer);
* oxrdflib: rdflib's API on Oxigraph, ``Dataset(store="Oxigraph")``, with a
  membership test (its ``len`` is a scan), if installed (``pip install oxrdflib``);
* raw ``pyoxigraph.Store`` quads (rdflib terms converted once, cached);
* ``shary.facts.database.FactDatabase`` as it is: its own index in front of rdflib,
  the graph brought up to date when read (no subscribers here).

and then the price of the first SPARQL query after those changes (the index's
pending changes applied to rdflib first), against oxrdflib's.

    python benchmarks/fact_stores.py [--json] [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

from rdflib import Dataset, Graph, URIRef

from shary.facts.database import FactDatabase

NS = "http://shary.dev/world#"
PEOPLE = 10_000
CHANGES = 20_000
LOOKS, JIDO, REACH = URIRef(NS + "looksAt"), URIRef(NS + "jido"), URIRef(NS + "isReachableBy")
PERSPECTIVE = URIRef("urn:shary:perspective:robot")
QUERY = f"SELECT (COUNT(?p) AS ?n) WHERE {{ ?p <{LOOKS}> <{JIDO}> . ?c <{REACH}> ?p }}"


def _people() -> list[URIRef]:
    return [URIRef(f"{NS}person{i}") for i in range(PEOPLE)]


def _changes(people: list[URIRef]):
    """(triple, remove?) pairs: everyone looks away, then back."""
    for i in range(CHANGES):
        yield (people[(i * 7919) % PEOPLE], LOOKS, JIDO), (i // PEOPLE) % 2 == 0


def _fill(add, people) -> None:
    for person in people:
        add((person, LOOKS, JIDO))
        add((URIRef(person + "-cup"), REACH, person))


def rdflib_dataset() -> float:
    people = _people()
    graph = Dataset().graph(PERSPECTIVE)
    _fill(graph.add, people)
    start = time.process_time()
    for triple, remove in _changes(people):
        size = len(graph)
        (graph.remove if remove else graph.add)(triple)
        _changed = len(graph) != size
    return CHANGES / (time.process_time() - start)


def rdflib_raw() -> float:
    people = _people()
    graph = Graph()
    _fill(graph.add, people)
    start = time.process_time()
    for triple, remove in _changes(people):
        (graph.remove if remove else graph.add)(triple)
    return CHANGES / (time.process_time() - start)


def oxrdflib_dataset() -> tuple[float, float]:
    people = _people()
    dataset = Dataset(store="Oxigraph")
    graph = dataset.graph(PERSPECTIVE)
    _fill(graph.add, people)
    start = time.process_time()
    for triple, remove in _changes(people):
        _changed = (triple in graph) == remove
        (graph.remove if remove else graph.add)(triple)
    rate = CHANGES / (time.process_time() - start)
    start = time.process_time()
    list(dataset.query(QUERY))
    return rate, (time.process_time() - start) * 1000


def pyoxigraph_raw() -> float:
    import pyoxigraph

    people = _people()
    store, graph = pyoxigraph.Store(), pyoxigraph.NamedNode(str(PERSPECTIVE))
    nodes: dict[URIRef, object] = {}

    def quad(triple):
        return pyoxigraph.Quad(*(nodes.get(t) or nodes.setdefault(t, pyoxigraph.NamedNode(t))
                                 for t in triple), graph)

    _fill(lambda t: store.add(quad(t)), people)
    start = time.process_time()
    for triple, remove in _changes(people):
        q = quad(triple)
        _changed = (q in store) == remove
        (store.remove if remove else store.add)(q)
    return CHANGES / (time.process_time() - start)


def shary_facts() -> tuple[float, float, float]:
    people = _people()
    db = FactDatabase(NS)
    _fill(lambda t: db.add(*t), people)
    db.select("SELECT ?s WHERE { ?s ?p ?o } LIMIT 1")  # the graph built once, as in a run
    start = time.process_time()
    for triple, remove in _changes(people):
        (db.remove if remove else db.add)(*triple)
    rate = CHANGES / (time.process_time() - start)
    start = time.process_time()
    db.select(QUERY)
    first = (time.process_time() - start) * 1000
    start = time.process_time()
    db.select(QUERY)
    return rate, first, (time.process_time() - start) * 1000


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="end with one JSON line of figures")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each (median reported)")
    args = parser.parse_args()
    figures: dict[str, float | None] = {}
    runs = {"rdflib_dataset": [], "rdflib_raw": [], "oxrdflib": [], "oxrdflib_query_ms": [],
            "pyoxigraph_raw": [], "shary_facts": [], "shary_query_ms": [],
            "shary_query_again_ms": []}
    try:
        import oxrdflib  # noqa: F401
        have_oxrdflib = True
    except ImportError:
        have_oxrdflib = False
    for _ in range(max(1, args.repeat)):  # interleaved: the machines here are noisy
        runs["rdflib_dataset"].append(rdflib_dataset())
        runs["rdflib_raw"].append(rdflib_raw())
        if have_oxrdflib:
            rate, query = oxrdflib_dataset()
            runs["oxrdflib"].append(rate)
            runs["oxrdflib_query_ms"].append(query)
        runs["pyoxigraph_raw"].append(pyoxigraph_raw())
        rate, query, again = shary_facts()
        runs["shary_facts"].append(rate)
        runs["shary_query_ms"].append(query)
        runs["shary_query_again_ms"].append(again)
    for name, values in runs.items():
        figures[name] = round(statistics.median(values), 1) if values else None
    peer = figures["rdflib_raw"]
    labels = {"rdflib_dataset": "rdflib Dataset named graph + len (the store before)",
              "rdflib_raw": "raw rdflib Graph.add/remove (the peer)",
              "oxrdflib": "oxrdflib Dataset(store='Oxigraph') + membership test",
              "pyoxigraph_raw": "raw pyoxigraph.Store quads + membership test",
              "shary_facts": "shary FactDatabase (own index, rdflib synced when read)"}
    for name, label in labels.items():
        rate = figures[name]
        if rate is None:
            print(f"{label:58s} not installed (pip install oxrdflib)")
        else:
            print(f"{label:58s} {rate:>10,.0f} changes/s  ({rate / peer:.2f} of the peer)")
    print(f"first SPARQL join after {CHANGES:,} changes: shary {figures['shary_query_ms']} ms "
          f"(the changes applied to rdflib first; {figures['shary_query_again_ms']} ms "
          "the next time, rdflib's SPARQL alone)"
          + (f", oxrdflib {figures['oxrdflib_query_ms']} ms" if have_oxrdflib else ""))
    if args.json:
        figures["ratio_shary_vs_rdflib_raw"] = round(figures["shary_facts"] / peer, 2)
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
