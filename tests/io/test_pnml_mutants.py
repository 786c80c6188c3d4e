"""Hostile PNML files against our reader: each is refused, or read as TAPAAL's verifypn reads it.

A proof about a net is a proof about a file only if the file has one meaning: the net our
reader gives must be the net another tool gives from the same bytes. The files are
mutants of real ones (tests/support/pnml_mutants.py: namespaces, nodes out of place, labels and
ids given twice, numbers and ids written otherwise, other dialects' attributes,
references, entities, encodings, order, nesting, cuts), made at run time from the
external corpus (where it is) and our templates; tests/support/pnml_campaign.py reads each with
our reader and, where we accept it, with verifypn. Here a sample of every operator runs in
``make test``, and the whole campaign (100,000 mutants) behind ``slow``; the same for
certified missions, whose accepted certificates verifypn must confirm on the file.
"""
from __future__ import annotations

import functools
import hashlib
import json

import pytest

import peers
import pnml_campaign as pc
import pnml_mutants as pm
from sampling import sample
from sessioncache import shared

SEED = 20_260_301
#: Mutants of each operator in the sample, and chains of two operators.
PER_OPERATOR, CHAINS = 5, 40
#: Mutants of certified missions in the sample (each operator about once in the whole one).
CERT_MUTANTS = sample(80, 30)


@functools.cache
def _seeds() -> tuple[pm.Seed, ...]:
    return tuple(pm.seeds())


@functools.cache
def _bases() -> tuple[pc.CertBase, ...]:
    return tuple(pc.cert_bases(SEED, missions=2, never_ending=1))


@pytest.fixture(scope="session")
def operator_mutants(tmp_path_factory):
    """The sample of one operator's mutants, made once per session: the two tests of each
    operator below (changes real files; refused or read as verifypn reads it) judge the
    same mutants, and under xdist they mostly ran on two workers that made them twice."""
    pool = _seeds()
    made: dict[str, list] = {}
    seeds = hashlib.sha256(b"".join(hashlib.sha256(s.data).digest() for s in pool)).hexdigest()

    def of(name: str) -> list:
        if name not in made:
            made[name] = shared(tmp_path_factory, "pnml-operator-mutants",
                                (seeds, SEED, PER_OPERATOR, name),
                                lambda: [pm.mutant(pool, k, SEED, [name])
                                         for k in range(PER_OPERATOR)])
        return made[name]
    return of


def _failures(results: list[pc.Result]) -> str:
    return "\n".join(f"{r.outcome} #{r.index} {r.operator} on {r.seed}:\n{r.detail}"
                     for r in results if r.outcome in pc.FAILURES)


def test_mutants_are_made_again_byte_for_byte_and_named_by_their_operator():
    """A mutant is a function of its number and the campaign's seed (a failure found in a
    long run is made again from its number), and is labelled with what made it."""
    pool = _seeds()
    names = sorted(pm.OPERATORS)
    for k in range(0, len(names) + pm.CHAINS, 3):
        first, again = pm.mutant(pool, k, SEED), pm.mutant(pool, k, SEED)
        assert first == again, k
        planned = pm.plan(k)
        if planned is not None:
            assert first.operator == planned[0]
        else:
            assert len(first.operator.split("+")) == 2 and \
                all(n in pm.OPERATORS for n in first.operator.split("+")), first.operator


@pytest.mark.parametrize("name", sorted(pm.OPERATORS))
def test_every_operator_changes_real_files(name, operator_mutants):
    """Each operator applies to the seeds, and (but for the seed's own bytes) changes
    them: a sample of its mutants is a sample of what it names."""
    pool = _seeds()
    made = operator_mutants(name)
    assert all(m is not None and m.operator == name for m in made), made
    if name != "identity":
        seeds = {s.name: s.data for s in pool}
        assert any(m.data != seeds[m.seed] for m in made), name


@pytest.mark.parametrize("name", sorted(pm.OPERATORS))
def test_mutants_are_refused_or_read_as_verifypn_reads_them(name, tmp_path, operator_mutants):
    peers.need(peers.VERIFYPN)
    results = [pc.judge(m, tmp_path) for m in operator_mutants(name)]
    assert not _failures(results), _failures(results)


@pytest.mark.parametrize("name", sorted(n for n, o in pm.OPERATORS.items() if o.preserves))
def test_a_file_that_means_what_its_seed_means_is_read_as_its_seed(name):
    """Refusing is not the whole answer: a file that differs from one we read only in what
    XML says carries no meaning (attribute and element order, white space between
    elements, ids as character references, unused namespace declarations, a byte-order
    mark) is read, as the same net."""
    from mcl2pnml.core.errors import Mcl2PnmlError
    from mcl2pnml.io.pnml.reader import parse_pnml
    from pnml_peer import read_net
    read = {}
    for s in _seeds():
        try:
            read[s.name] = read_net(parse_pnml(s.data, s.name))
        except Mcl2PnmlError:
            continue
    assert len(read) >= 10, sorted(read)    # the templates at least, and the corpus's
    accepted = [s for s in _seeds() if s.name in read]
    for k in range(PER_OPERATOR * 2):
        m = pm.mutant(accepted, k, SEED, [name])
        assert read_net(parse_pnml(m.data, f"{name}-{k}.pnml")) == read[m.seed], m.seed


def test_chains_of_two_operators_are_refused_or_read_as_verifypn_reads_them(tmp_path):
    peers.need(peers.VERIFYPN)
    pool = _seeds()
    cycle = len(pm.OPERATORS) + pm.CHAINS
    # the numbers the campaign gives chains: the last CHAINS of each cycle
    indices = [c * cycle + len(pm.OPERATORS) + k for c in range(CHAINS // pm.CHAINS)
               for k in range(pm.CHAINS)]
    results = [pc.judge(pm.mutant(pool, k, SEED), tmp_path) for k in indices]
    assert all("+" in r.operator for r in results)
    assert not _failures(results), _failures(results)


def test_certificates_accepted_for_mutated_missions_hold_on_the_net_verifypn_reads(tmp_path):
    """Compiled missions' PNML mutated, their certificates kept: where our reader accepts
    the file and the checker the certificate, verifypn confirms on the file the claims
    (1-safe, an end always reachable, every dead marking a proper end, the ends said).
    Mutants that keep the meaning (attribute order, white space) are certified: the
    sample is not one of refusals only."""
    peers.need(peers.VERIFYPN)
    bases = _bases()
    certs = {b.seed.name: json.loads(b.cert_json) for b in bases}
    pool = [b.seed for b in bases]
    results = []
    for k in range(CERT_MUTANTS):
        m = pm.mutant(pool, k, SEED)
        results.append(pc.judge_certified(m, certs[m.seed], tmp_path))
    assert not _failures(results), _failures(results)
    assert any(r.outcome == "confirmed" for r in results), \
        sorted((r.operator, r.outcome) for r in results)


@pytest.mark.slow
def test_a_hundred_thousand_mutants_are_refused_or_read_as_verifypn_reads_them(tmp_path):
    """The whole campaign: 100,000 mutants of the seeds and 5,000 of certified missions,
    on two processes (``tests/support/pnml_campaign.py`` runs it by hand, with its table)."""
    peers.need(peers.VERIFYPN)
    summary = pc.run(100_000, workers=2, seed=SEED, out=tmp_path)
    print(pc.report(summary))        # said with -s: what the campaign ran
    assert summary.total("reader") >= 99_000 and summary.total("cert") >= 4_900
    assert not summary.failures, pc.report(summary)
