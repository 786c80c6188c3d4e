"""The campaign of hostile PNML files: our reader against TAPAAL's verifypn, mutant by mutant.

Every mutant of tests/support/pnml_mutants.py is read by our reader, in process; a file it
accepts is read by verifypn too (``--write-unfolded-net``, tests/support/pnml_peer.py), and the
two nets compared. Each mutant ends in one outcome:

* ``refused``: our reader refused it, with its located error (fine);
* ``equal``: accepted, and verifypn reads the same net (fine);
* ``vp-refuses``, ``vp-crashes``, ``vp-timeout``, ``vp-unreadable``: accepted, and
  verifypn gives no net (its reader's refusal, a crash, no net in time, a net it wrote
  that cannot be read back): no comparison, counted to be seen;
* ``DIFFERENT``: accepted, and verifypn reads another net from the same bytes: a
  proof about our net says nothing of the file as other tools read it (a failure);
* ``CRASH``: our reader raised something else than its own error (a failure).

The certificate side does the same with compiled missions (certmutations.py's small
generated missions, with their certificates): for each mutant of a mission's PNML that
our reader accepts and for which the certificate's checker (``check_certificate``, what
``mcl2pnml certify CERT --check NET`` runs) finds no fault, verifypn is asked, on the
mutant itself, the certificate's three claims (1-safe, an end always reachable, every dead
marking a proper end: reusable) and which ends are reachable: a certificate accepted for a
net verifypn finds broken is ``BROKEN`` (a failure).

Run from the repository's root::

    .venv/bin/python tests/support/pnml_campaign.py --mutants 100000 --workers 2 [--seed S]

It prints a table of outcomes per operator, the time taken and the mutants a second,
saves each failing mutant with its operator and what differs under ``--out``
(``out/pnml-campaign`` by default), and exits 1 when there is a failure.
tests/io/test_pnml_mutants.py runs a sample of it in ``make test``, and all of it behind
``slow``.
"""
from __future__ import annotations

import argparse
import json
import shutil
import signal
import sys
import tempfile
import time
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:       # run as a script: the tests' modules beside it
    sys.path.insert(0, str(HERE))

import pnml_mutants as pm  # noqa: E402
import pnml_peer  # noqa: E402

READER_OUTCOMES = ("refused", "equal", "vp-refuses", "vp-crashes", "vp-timeout",
                   "vp-unreadable", "DIFFERENT", "CRASH")
CERT_OUTCOMES = ("refused", "cert-refused", "confirmed", "vp-unanswered", "DIFFERENT",
                 "BROKEN", "CRASH")
FAILURES = ("DIFFERENT", "CRASH", "BROKEN")
#: The longest our reader may take on one mutant (a hang is a failure, not a wait).
READ_LIMIT = 60.0
ENDS = ("mission.OK", "mission.FAIL", "mission.ABORTED")


@dataclass
class Result:
    """What one mutant gave: its label, its outcome, and for a failure what went wrong and
    its bytes (to be saved by the parent)."""

    index: int
    operator: str
    seed: str
    outcome: str
    detail: str = ""
    data: bytes | None = None


class _Slow(Exception):
    pass


def _alarm(signum, frame):
    raise _Slow()


def read(data: bytes, name: str, lenient: bool = False, limit: float | None = None):
    """Our reader on ``data``, in process; within ``limit`` seconds if given (an alarm: the
    campaign's workers give one, a test leaves its time to pytest)."""
    from mcl2pnml.io.pnml.reader import parse_pnml
    if limit is None:
        return parse_pnml(data, name, lenient=True) if lenient else parse_pnml(data, name)
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        return parse_pnml(data, name, lenient=True) if lenient else parse_pnml(data, name)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _ours(m: pm.Mutant, lenient: bool, limit: float | None):
    """(our net, None), or (None, outcome and detail) when we give none."""
    from mcl2pnml.core.errors import Mcl2PnmlError
    try:
        return read(m.data, f"mutant-{m.index}.pnml", lenient, limit), None
    except Mcl2PnmlError:
        return None, ("refused", "")
    except _Slow:
        return None, ("CRASH", f"our reader took more than {limit:g} s")
    except Exception as e:      # noqa: BLE001 - any other exception is what is looked for
        return None, ("CRASH", f"{type(e).__name__}: {e}")


def _compared(net, path: Path, timeout: float) -> tuple[str, str]:
    """verifypn's reading of ``path`` beside ``net``: (outcome, detail)."""
    try:
        theirs = pnml_peer.verifypn_net(path, timeout)
    except Exception as e:      # noqa: BLE001 - its written net could not be read back
        return "vp-unreadable", f"{type(e).__name__}: {e}"
    if isinstance(theirs, pnml_peer.Refused):
        why = theirs.why
        if why.startswith("no net within"):
            return "vp-timeout", why
        if why.startswith("exit -") or why.startswith("exit 139") or why.startswith("exit 134"):
            return "vp-crashes", why
        return "vp-refuses", why
    found = pnml_peer.differences(pnml_peer.read_net(net), theirs)
    return ("DIFFERENT", "\n".join(found)) if found else ("equal", "")


def judge(m: pm.Mutant, folder: Path, timeout: float = pnml_peer.TIMEOUT,
          lenient: bool = False, limit: float | None = None) -> Result:
    """One mutant read by us and, if we accept it, by verifypn: its :class:`Result`."""
    net, said = _ours(m, lenient, limit)
    if said is None:
        path = folder / f"m{m.index}.pnml"
        path.write_bytes(m.data)
        try:
            said = _compared(net, path, timeout)
        finally:
            path.unlink(missing_ok=True)
    outcome, detail = said
    return Result(m.index, m.operator, m.seed, outcome, detail,
                  m.data if outcome in FAILURES else None)


# -- the certificate side ----------------------------------------------------------------------

@dataclass(frozen=True)
class CertBase:
    """A compiled mission's PNML and its certificate (JSON text), with where it comes from."""

    seed: pm.Seed
    cert_json: str
    kind: str


def cert_bases(seed: int, missions: int = 3, never_ending: int = 2) -> list[CertBase]:
    """certmutations.py's generated missions, certified from B (and forged where they may
    never end), each also with an abort pending: their nets as our writer writes them."""
    import certmutations as cm
    from mcl2pnml import pipeline
    pool, _ = cm.bases(seed, missions, never_ending)
    return [CertBase(pm.Seed(f"mission{k}:{b.kind}", pipeline.to_pnml_bytes(b.net, "none")),
                     b.cert_json, b.kind) for k, b in enumerate(pool)]


def _claims(net) -> list:
    """The certificate's claims as queries in the contest's language, with the mission's
    own (mccquery's ``mission_properties``): every place at most one token, an end always
    reachable, no dead marking but a proper end, and a dead marking with each result."""
    from mcl2pnml.io import ids
    from mcl2pnml.io.mccquery import Element, Property, mission_properties

    def e(tag, *children):
        return Element(tag, tuple(children))

    def tokens(place):
        return e("tokens-count", Element("place", text=ids.encode(place)))
    safe = e("all-paths", e("globally", e("conjunction", *(
        e("integer-le", tokens(p.id), Element("integer-constant", text="1"))
        for p in net.places))))
    return [*mission_properties(net), Property("safe", "AG every place holds 1 at most", safe),
            *(Property(f"ends-{end}", f"EF (deadlock and {end})", e(
                "exists-path", e("finally", e("conjunction", e("deadlock"), e(
                    "integer-le", Element("integer-constant", text="1"), tokens(end))))))
              for end in ENDS if end in net.place_index)]


def confirm(path: Path, net, cert: dict) -> tuple[str, str]:
    """verifypn's verdicts on the file ``path`` for the claims of ``cert`` (accepted for
    ``net``, our reading of it): ("confirmed" | "BROKEN" | "vp-unanswered", detail)."""
    import peers
    from mcl2pnml.io.mccquery import to_queries
    props = _claims(net)
    queries = path.with_suffix(".xml")
    queries.write_text(to_queries(tuple(props)))
    try:
        said = peers.verifypn_queries(path, queries, len(props))
    except Exception as e:      # noqa: BLE001 - its time limit, mostly
        return "vp-unanswered", f"{type(e).__name__}: {e}"
    finally:
        queries.unlink(missing_ok=True)
    wanted = {p.id for p in props}
    if set(said) != wanted:
        return "vp-unanswered", f"verifypn answered {sorted(said)} of {sorted(wanted)}"
    wrong = []
    if said["safe"] is not True:
        wrong.append("not 1-safe")
    for key, value in said.items():
        if key.endswith("-end-always-reachable") and value is not True:
            wrong.append("an end is not always reachable")
        if key.endswith("-deadlock-not-an-end") and value is not False:
            wrong.append("a dead marking is no proper end")
    ends = {end for end in ENDS if said.get(f"ends-{end}")}
    if ends != set(cert["conclusion"]["ends"]):
        wrong.append(f"the ends are {sorted(ends)}, the certificate says "
                     f"{cert['conclusion']['ends']}")
    return ("BROKEN", "; ".join(wrong)) if wrong else ("confirmed", "")


def judge_certified(m: pm.Mutant, cert: dict, folder: Path,
                    timeout: float = pnml_peer.TIMEOUT, lenient: bool = False,
                    limit: float | None = None) -> Result:
    """A mutant of a mission's PNML: read by us; if accepted, compared with verifypn's
    reading, its certificate checked, and if it holds, its claims asked of verifypn."""
    from mcl2pnml import pipeline
    from mcl2pnml.core.errors import Mcl2PnmlError
    net, said = _ours(m, lenient, limit)
    if said is not None:
        return Result(m.index, m.operator, m.seed, *said,
                      m.data if said[0] in FAILURES else None)
    path = folder / f"c{m.index}.pnml"
    path.write_bytes(m.data)
    try:
        outcome, detail = _compared(net, path, timeout)
        try:
            problems = pipeline.check_certificate(net, cert)
        except Mcl2PnmlError as e:
            problems = [str(e)]
        except Exception as e:      # noqa: BLE001 - the checker must not crash either
            return Result(m.index, m.operator, m.seed, "CRASH",
                          f"the certificate's checker: {type(e).__name__}: {e}", m.data)
        if problems:
            checked = ("cert-refused", "")
        else:
            checked = confirm(path, net, cert)
    finally:
        path.unlink(missing_ok=True)
    if checked[0] == "BROKEN":
        outcome, detail = "BROKEN", checked[1] + (f"\n(and {outcome}: {detail})" if detail
                                                  else "")
    elif outcome != "DIFFERENT":
        outcome, detail = checked
    return Result(m.index, m.operator, m.seed, outcome, detail,
                  m.data if outcome in FAILURES else None)


# -- workers -----------------------------------------------------------------------------------

_WORK: dict = {}


def _start(seeds, bases, seed, timeout, lenient, folder):
    _WORK.update(seeds=seeds, bases=bases, seed=seed, timeout=timeout, lenient=lenient,
                 certs={b.seed.name: json.loads(b.cert_json) for b in bases},
                 tmp=Path(tempfile.mkdtemp(prefix="pnml-campaign-", dir=folder)))


def _reader_chunk(indices: list[int]) -> list[Result]:
    w, out = _WORK, []
    for k in indices:
        m = pm.mutant(w["seeds"], k, w["seed"])
        if m is not None:
            out.append(judge(m, w["tmp"], w["timeout"], w["lenient"], READ_LIMIT))
    return out


def _cert_chunk(indices: list[int]) -> list[Result]:
    w, out = _WORK, []
    pool = [b.seed for b in w["bases"]]
    for k in indices:
        m = pm.mutant(pool, k, w["seed"] + 1)
        if m is not None:
            out.append(judge_certified(m, w["certs"][m.seed], w["tmp"], w["timeout"],
                                       w["lenient"], READ_LIMIT))
    return out


# -- the whole campaign ------------------------------------------------------------------------

@dataclass
class Summary:
    """What a campaign found: per row (operator, or "chain") and outcome, the count;
    the failures' labels and details; the time."""

    reader: dict = field(default_factory=lambda: defaultdict(Counter))
    cert: dict = field(default_factory=lambda: defaultdict(Counter))
    failures: list = field(default_factory=list)
    seconds: float = 0.0
    seeds: int = 0
    bases: int = 0
    #: the seeds whose own bytes give DIFFERENT (every mutant of them may too)
    differing_seeds: list = field(default_factory=list)

    def count(self, side: str, outcome: str) -> int:
        table = self.reader if side == "reader" else self.cert
        return sum(row[outcome] for row in table.values())

    def total(self, side: str) -> int:
        table = self.reader if side == "reader" else self.cert
        return sum(sum(row.values()) for row in table.values())

    def table(self, side: str) -> str:
        table, outcomes = (self.reader, READER_OUTCOMES) if side == "reader" else \
            (self.cert, CERT_OUTCOMES)
        names = sorted(table, key=lambda n: (pm.OPERATORS[n].family if n in pm.OPERATORS
                                             else "~", n))
        width = max([len(n) for n in names] + [8])
        head = f"{'operator':{width}} {'mutants':>8} " + " ".join(f"{o:>13}" for o in outcomes)
        lines = [head, "-" * len(head)]
        for n in names + ["total"]:
            row = table[n] if n != "total" else sum(table.values(), Counter())
            lines.append(f"{n:{width}} {sum(row.values()):>8} "
                         + " ".join(f"{row[o]:>13}" for o in outcomes))
        return "\n".join(lines)

    def as_json(self) -> dict:
        return {"reader": {k: dict(v) for k, v in self.reader.items()},
                "cert": {k: dict(v) for k, v in self.cert.items()},
                "failures": self.failures, "seconds": round(self.seconds, 1),
                "seeds": self.seeds, "cert_bases": self.bases,
                "differing_seeds": self.differing_seeds}


def run(mutants: int, workers: int = 2, seed: int = 1, cert_mutants: int | None = None,
        out: Path | None = None, timeout: float = pnml_peer.TIMEOUT, lenient: bool = False,
        max_seed_bytes: int = pm.MAX_SEED_BYTES, chunk: int = 25,
        progress=lambda line: None) -> Summary:
    """``mutants`` mutants of the seeds and ``cert_mutants`` (default a twentieth as many)
    of the certified missions, over ``workers`` processes; failures saved under ``out``."""
    from concurrent.futures import ProcessPoolExecutor, as_completed
    import multiprocessing
    cert_mutants = mutants // 20 if cert_mutants is None else cert_mutants
    seeds = pm.seeds(max_seed_bytes)
    bases = cert_bases(seed) if cert_mutants else []
    summary = Summary(seeds=len(seeds), bases=len(bases))
    out = out or Path("out/pnml-campaign")
    out.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    with tempfile.TemporaryDirectory(dir=out) as tmp:
        summary.differing_seeds = [
            s.name for s in seeds
            if judge(pm.Mutant(-1, "identity", s.name, s.data), Path(tmp), timeout, lenient,
                     READ_LIMIT).outcome == "DIFFERENT"]
    jobs = [(_reader_chunk, list(range(k, min(k + chunk, mutants))))
            for k in range(0, mutants, chunk)]
    jobs += [(_cert_chunk, list(range(k, min(k + chunk, cert_mutants))))
             for k in range(0, cert_mutants, chunk)]
    done, last = 0, started
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork"),
                             initializer=_start,
                             initargs=(seeds, bases, seed, timeout, lenient, out)) as pool:
        futures = {pool.submit(f, idx): f for f, idx in jobs}
        for fut in as_completed(futures):
            side = "reader" if futures[fut] is _reader_chunk else "cert"
            for r in fut.result():
                (summary.reader if side == "reader" else summary.cert)[
                    pm.family(r.operator)][r.outcome] += 1
                done += 1
                if r.outcome in FAILURES:
                    m = pm.Mutant(r.index, r.operator, r.seed, r.data or b"")
                    path = pm.save(m, out / side / r.outcome.lower(), r.detail)
                    summary.failures.append({
                        "side": side, "index": r.index, "operator": r.operator,
                        "seed": r.seed, "outcome": r.outcome, "detail": r.detail,
                        "file": str(path), "bytes": len(m.data),
                        "seed_differs": r.seed in summary.differing_seeds})
            now = time.monotonic()
            if now - last > 30:
                last = now
                progress(f"{done:,} mutants in {now - started:,.0f} s "
                         f"({done / (now - started):.1f}/s), "
                         f"{len(summary.failures)} failures so far")
    summary.seconds = time.monotonic() - started
    for folder in out.glob("pnml-campaign-*"):     # the workers' scratch folders
        shutil.rmtree(folder, ignore_errors=True)
    (out / "summary.json").write_text(json.dumps(summary.as_json(), indent=1) + "\n")
    return summary


def report(summary: Summary) -> str:
    total = summary.total("reader") + summary.total("cert")
    lines = [f"seeds: {summary.seeds} files; certified missions: {summary.bases}", "",
             "reader: our reader, then verifypn where we accept", summary.table("reader")]
    if summary.cert:
        lines += ["", "certificates: mutants of certified missions' PNML",
                  summary.table("cert")]
    lines += ["", f"{total:,} mutants in {summary.seconds:,.1f} s: "
                  f"{total / max(summary.seconds, 1e-9):.1f} mutants/s"]
    if summary.differing_seeds:
        lines += ["", "seeds that verifypn reads otherwise unmutated: "
                  + ", ".join(summary.differing_seeds)]
    if summary.failures:
        own = [f for f in summary.failures if not f["seed_differs"]]
        lines += ["", f"{len(summary.failures)} failures ({len(own)} of them on seeds read "
                      "alike unmutated); the smallest of each operator:"]
        smallest: dict = {}
        for f in sorted(own or summary.failures, key=lambda f: f["bytes"]):
            smallest.setdefault(pm.family(f["operator"]), f)
        for f in sorted(smallest.values(), key=lambda f: f["bytes"]):
            lines += [f"  {f['outcome']} {f['side']} #{f['index']} {f['operator']} on "
                      f"{f['seed']} ({f['bytes']} bytes): {f['file']}",
                      *(f"      {line}" for line in f["detail"].splitlines()[:5])]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mutants", type=int, default=10_000, help="mutants of the seeds")
    ap.add_argument("--cert-mutants", type=int, default=None,
                    help="mutants of certified missions (default: a twentieth of --mutants)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=Path, default=Path("out/pnml-campaign"))
    ap.add_argument("--timeout", type=float, default=pnml_peer.TIMEOUT,
                    help="seconds verifypn may take on one file")
    ap.add_argument("--max-seed-bytes", type=int, default=pm.MAX_SEED_BYTES)
    ap.add_argument("--lenient", action="store_true", help="our reader's lenient reading")
    ap.add_argument("--list", action="store_true", help="list the operators and exit")
    args = ap.parse_args(argv)
    if args.list:
        print(pm.describe())
        return 0
    import peers
    tool, why = peers.find(peers.VERIFYPN)
    if tool is None:
        print(f"verifypn is needed: {why}", file=sys.stderr)
        return 2
    summary = run(args.mutants, args.workers, args.seed, args.cert_mutants, args.out,
                  args.timeout, args.lenient, args.max_seed_bytes,
                  progress=lambda line: print(line, file=sys.stderr, flush=True))
    print(report(summary))
    return 1 if summary.failures else 0


if __name__ == "__main__":
    sys.exit(main())
