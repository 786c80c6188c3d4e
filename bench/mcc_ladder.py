"""The contest's development ladder: ours against verifypn and LoLA, past what exploring
answers.

Run:  .venv/bin/python -m bench.mcc_ladder [--exams RC,RF,...] [--timeout 60] [--jobs 2]
                                           [--only ours,verifypn,lola]
                                           [--first-of-family | --rest-of-family]
                                           [--instances NAME,...]
(prints the section of bench/RESULTS.md; ``--floor`` alone checks the start-up floor)

For each of the 36 instances of ``../shared/external-nets/mcc-ladder`` (18 families, as the
contest published them) and each examination asked (default: the seven formula files and
the five generic examinations), the whole
command a user runs, each tool with its defaults (reductions on): ours, ``mcl2pnml query
model.pnml FILE.xml``; verifypn, ``verifypn-linux64 -n 1 -x 1,...,16 model.pnml FILE.xml``
(``-ltl`` for the LTL files); LoLA, ``lola --pnmlnet model.pnml --xmlformula
--formula=FILE.xml --mcc --quiet``. A generic examination: ours, ``mcl2pnml query
model.pnml --examination NAME``; LoLA, ``lola --pnmlnet model.pnml --check=CHECK --mcc
--quiet``; verifypn, which has no command for them, the examination's definition as
formulas, one a place or transition (:func:`write_atoms`), its answers combined
(:func:`verdict`). A command past ``--timeout`` seconds (60 by default) is
stopped, its whole process group; what it printed before counts, as in the contest. Every
answer is held to the 2021 consensus (``oracle/``, ``?`` where the tools did not agree:
neither right nor wrong). ``--jobs`` commands run at once (two on two cores: each tool is
as loaded as the others). The instances are unpacked into a scratch folder, never into
the project.

``--first-of-family``: one instance of each family (the first by name, the smaller);
``--rest-of-family``: the others (the larger). The two runs make the whole ladder.

``--floor``: ``mcl2pnml --version`` and a query on a 10-place net, the median of five
whole commands after one to warm up, with the bytecode written as a user's install keeps
it, against 0.3 s (the interpreter's start-up is the floor; it must not grow).
"""
from __future__ import annotations

import argparse
import concurrent.futures as cf
import os
import re
import signal
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

from bench.mcc_queries import LOLA, VERIFYPN, answers
from mcl2pnml.io.mccquery import escape

ROOT = Path(__file__).resolve().parents[1]
LADDER = ROOT.parent / "shared" / "external-nets" / "mcc-ladder"
TOOLS = ("ours", "verifypn", "lola")
#: The formula files, by the short names of the oracle's files.
FILES = {"RC": "ReachabilityCardinality", "RF": "ReachabilityFireability",
         "CTLC": "CTLCardinality", "CTLF": "CTLFireability", "LTLC": "LTLCardinality",
         "LTLF": "LTLFireability", "UB": "UpperBounds"}
#: The generic examinations, by the short names of the oracle's files, and the check LoLA
#: names each by.
GENERIC = {"RD": ("ReachabilityDeadlock", "deadlockfreedom"), "OS": ("OneSafe", "OneSafe"),
           "SM": ("StableMarking", "StableMarking"),
           "QL": ("QuasiLiveness", "QuasiLiveness"), "L": ("Liveness", "Liveness")}
EXAMS = [*FILES, *GENERIC]
TIMEOUT = 60.0
#: What a query on a 10-place net and ``--version`` may take, whole commands (seconds).
FLOOR = 0.3


def run(args: list[str], timeout: float, cwd: str, env: dict | None = None
        ) -> tuple[float, float, str]:
    """Wall seconds (``timeout`` where stopped), the peak MiB (GNU time's %M, 0 where
    stopped), and what the command printed, up to its end or its stop."""
    start = time.perf_counter()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        child = subprocess.Popen(["/usr/bin/time", "-f", "%M", *args], stdout=out,
                                 stderr=err, cwd=cwd, start_new_session=True, env=env)
        try:
            child.wait(timeout)
            seconds = time.perf_counter() - start
        except subprocess.TimeoutExpired:
            os.killpg(child.pid, signal.SIGKILL)   # the tool too, not only GNU time
            child.wait()
            seconds = timeout
        out.seek(0)
        err.seek(0)
        text = out.read(1 << 24).decode(errors="replace")
        tail = err.read(1 << 20).decode(errors="replace").strip().splitlines()
    peak = tail[-1] if tail and seconds < timeout else "0"
    return seconds, int(peak) / 1024 if peak.isdigit() else 0.0, text


def oracle(instance: str, exam: str) -> dict[str, str]:
    path = LADDER / "oracle" / f"{instance}-{exam}.out"
    return dict(re.findall(r"^FORMULA (\S+) (\S+) TECHNIQUES", path.read_text(), re.M))


def commands(folder: Path, exam: str) -> dict[str, list[str]]:
    net = str(folder / "model.pnml")
    if exam in GENERIC:
        name, check = GENERIC[exam]
        atoms = folder / f"{name}.atoms.xml"
        count = write_atoms(folder / "model.pnml", name, atoms)
        return {
            "ours": [sys.executable, "-m", "mcl2pnml", "query", net, "--examination", name],
            "verifypn": [str(VERIFYPN), "-n", "1", "-x",
                         ",".join(map(str, range(1, count + 1))), net, str(atoms)],
            "lola": [str(LOLA), "--pnmlnet", net, f"--check={check}", "--mcc", "--quiet"],
        }
    file = str(folder / f"{FILES[exam]}.xml")
    return {
        "ours": [sys.executable, "-m", "mcl2pnml", "query", net, file],
        "verifypn": [str(VERIFYPN), "-n", "1", *(["-ltl"] if exam.startswith("LTL") else []),
                     "-x", ",".join(map(str, range(1, 17))), net, file],
        "lola": [str(LOLA), "--pnmlnet", net, "--xmlformula", f"--formula={file}", "--mcc",
                 "--quiet"],
    }


def write_atoms(net: Path, name: str, path: Path) -> int:
    """The generic examination ``name`` as the contest's formulas, for a tool that has no
    command for it (verifypn), written to ``path``; how many. Each is one atom of the
    definition, ids ``A-0``, ``A-1``...: ReachabilityDeadlock ``E F deadlock``; OneSafe
    ``A G (p <= 1)`` and StableMarking ``A G (p = M0(p))``, a place each; QuasiLiveness
    ``E F fireable(t)`` and Liveness ``A G E F fireable(t)``, a transition each
    (:func:`verdict` reads them back)."""
    from mcl2pnml import pipeline
    from mcl2pnml.core.structure import structure
    s = structure(pipeline.load_net(net))

    def le(a: str, b: str) -> str:
        return f"<integer-le>{a}{b}</integer-le>"

    def tokens(p: str) -> str:
        return f"<tokens-count><place>{escape(p)}</place></tokens-count>"

    def const(n: int) -> str:
        return f"<integer-constant>{n}</integer-constant>"

    def fires(t: str) -> str:
        return f"<is-fireable><transition>{escape(t)}</transition></is-fireable>"
    if name == "ReachabilityDeadlock":
        formulas = ["<exists-path><finally><deadlock/></finally></exists-path>"]
    elif name == "OneSafe":
        formulas = [f"<all-paths><globally>{le(tokens(p), const(1))}</globally></all-paths>"
                    for p in s.places]
    elif name == "StableMarking":
        formulas = [f"<all-paths><globally><conjunction>{le(tokens(p), const(int(m)))}"
                    f"{le(const(int(m)), tokens(p))}</conjunction></globally></all-paths>"
                    for p, m in zip(s.places, s.initial_vector())]
    elif name == "QuasiLiveness":
        formulas = [f"<exists-path><finally>{fires(t)}</finally></exists-path>"
                    for t in s.transitions]
    else:
        formulas = [f"<all-paths><globally><exists-path><finally>{fires(t)}</finally>"
                    f"</exists-path></globally></all-paths>" for t in s.transitions]
    path.write_text('<?xml version="1.0"?>\n<property-set xmlns="http://mcc.lip6.fr/">\n' + "".join(
        f"<property><id>A-{k}</id><description/><formula>{f}</formula></property>\n"
        for k, f in enumerate(formulas)) + "</property-set>\n")
    return len(formulas)


def verdict(name: str, atoms: dict[str, str], count: int) -> dict[str, str]:
    """The examination's answer from its atoms' (:func:`write_atoms`): StableMarking holds
    where one atom does, the others where every one does; none where the atoms said
    do not decide it."""
    values = [atoms.get(f"A-{k}") for k in range(count)]
    one = name in ("StableMarking", "ReachabilityDeadlock")
    decisive, other = ("TRUE", "FALSE") if one else ("FALSE", "TRUE")
    if decisive in values:
        return {name: decisive}
    if all(v == other for v in values):
        return {name: other}
    return {}


def unpack(scratch: Path) -> list[Path]:
    """Each instance's folder, unpacked from the ladder's archives (members checked: no
    path leaves the scratch folder)."""
    folders = []
    for archive in sorted((LADDER / "inputs").glob("*.tgz")):
        with tarfile.open(archive) as tar:
            tar.extractall(scratch, filter="data")
        folders.append(scratch / archive.name[:-len(".tgz")])
    return folders


def ladder(exams: list[str], tools: list[str], timeout: float, jobs: int,
           instances: list[str] | None = None) -> list[str]:
    scratch = Path(tempfile.mkdtemp(prefix="mcc-ladder-"))
    folders = [f for f in unpack(scratch) if instances is None or f.name in instances]
    work = [(folder, exam, who, args) for folder in folders for exam in exams
            for who, args in commands(folder, exam).items() if who in tools]
    # per examination and tool: right, wrong, unanswered (of the known), seconds, peak MiB
    rows = {(e, w): [0, 0, 0, 0.0, 0.0] for e in exams for w in tools}

    def one(item):
        folder, exam, who, args = item
        return item, run(args, timeout, str(scratch))

    with cf.ThreadPoolExecutor(jobs) as pool:
        for (folder, exam, who, args), (seconds, mib, out) in pool.map(one, work):
            truth = {k: v for k, v in oracle(folder.name, exam).items() if v != "?"}
            got = answers(out)
            if exam in GENERIC and who == "verifypn":    # its atoms' answers
                got = verdict(GENERIC[exam][0], got, args[args.index("-x") + 1].count(",") + 1)
            row = rows[exam, who]
            right = sum(1 for k, v in got.items() if truth.get(k) == v)
            wrong = sum(1 for k, v in got.items() if k in truth and truth[k] != v)
            row[0] += right
            row[1] += wrong
            row[2] += len(truth) - right - wrong
            row[3] += seconds
            row[4] = max(row[4], mib)
            print(f"  {folder.name} {exam} {who}: {right} right, {wrong} wrong of "
                  f"{len(truth)}, {seconds:.1f} s", file=sys.stderr, flush=True)
    lines = ["| examination | " + " | ".join(
        f"{w}: right / wrong / unanswered | {w} (s) | {w} peak MiB" for w in tools) + " |",
        "|---|" + "---:|---:|---:|" * len(tools)]
    total = {w: [0, 0, 0, 0.0] for w in tools}
    for exam in exams:
        cells = []
        for w in tools:
            right, wrong, left, seconds, mib = rows[exam, w]
            cells.append(f"{right} / {wrong} / {left} | {seconds:.0f} | {mib:.0f}")
            for i, v in enumerate((right, wrong, left, seconds)):
                total[w][i] += v
        lines.append(f"| {FILES[exam] if exam in FILES else GENERIC[exam][0]} | "
                     + " | ".join(cells) + " |")
    lines.append("| **total** | " + " | ".join(
        f"**{r} / {w} / {u}** | **{s:.0f}** | " for r, w, u, s in total.values()) + " |")
    return lines


def floor() -> list[str]:
    """The start-up floor: ``--version`` and a query on a 10-place net, median of five."""
    scratch = Path(tempfile.mkdtemp(prefix="mcc-floor-"))
    net, formula = scratch / "ten.pnml", scratch / "q.xml"
    places = "".join(f'<place id="p{i}"><initialMarking><text>{int(i == 0)}</text>'
                     f'</initialMarking></place>' for i in range(10))
    transitions = "".join(f'<transition id="t{i}"/><arc id="a{i}" source="p{i}" '
                          f'target="t{i}"/><arc id="b{i}" source="t{i}" '
                          f'target="p{(i + 1) % 10}"/>' for i in range(10))
    net.write_text('<?xml version="1.0"?><pnml xmlns="http://www.pnml.org/version-2009/grammar/'
                   'pnml"><net id="ten" type="http://www.pnml.org/version-2009/grammar/ptnet">'
                   f'<page id="g">{places}{transitions}</page></net></pnml>')
    formula.write_text(
        '<?xml version="1.0"?><property-set xmlns="http://mcc.lip6.fr/"><property>'
        '<id>ten-0</id><description/><formula><exists-path><finally><integer-le>'
        '<integer-constant>1</integer-constant><tokens-count><place>p9</place>'
        '</tokens-count></integer-le></finally></exists-path></formula></property>'
        '</property-set>')
    lines = []
    # as a user's install runs: its modules' bytecode written once and kept (a shell that
    # forbids writing it would have every start compile what changed since it was last)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    for what, args in (("--version", ["--version"]),
                       ("query on a 10-place net", ["query", str(net), str(formula)])):
        command = [sys.executable, "-m", "mcl2pnml", *args]
        run(command, 30.0, str(scratch), env)      # the warm-up writes the bytecode
        times = [run(command, 30.0, str(scratch), env)[0] for _ in range(5)]
        median = statistics.median(times)
        lines.append(f"- `mcl2pnml {args[0]}` ({what}): median {median:.2f} s of five; "
                     f"{'within' if median <= FLOOR else 'PAST'} {FLOOR} s")
    return lines


def arguments(argv: list[str]) -> argparse.Namespace:
    """The benchmark's options, as the module's docstring gives them (``--help``)."""
    parser = argparse.ArgumentParser(
        prog="python -m bench.mcc_ladder", description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter)

    def names(known):
        def split(text: str) -> list[str]:
            items = text.split(",")
            unknown = [x for x in items if x not in known]
            if unknown:
                raise argparse.ArgumentTypeError(
                    f"unknown: {', '.join(unknown)}; known: {', '.join(known)}")
            return items
        return split
    parser.add_argument("--exams", type=names(EXAMS), default=EXAMS,
                        help="formula files and generic examinations, comma-separated "
                             "(default: all twelve)")
    parser.add_argument("--only", type=names(TOOLS), default=list(TOOLS),
                        help="tools, comma-separated (default: all)")
    parser.add_argument("--timeout", type=float, default=TIMEOUT,
                        help="seconds a command may run (default: %(default)s)")
    parser.add_argument("--jobs", type=int, default=2, help="commands at once (default: 2)")
    half = parser.add_mutually_exclusive_group()
    half.add_argument("--first-of-family", action="store_true",
                      help="one instance a family, the smaller")
    half.add_argument("--rest-of-family", action="store_true", help="the larger instances")
    parser.add_argument("--instances", type=lambda s: s.split(","), default=None,
                        help="these instances only, comma-separated")
    parser.add_argument("--floor", action="store_true", help="the start-up floor alone")
    return parser.parse_args(argv)


def main(argv: list[str]) -> None:
    args = arguments(argv)
    if args.floor:
        print("\n".join(floor()))
        return
    names = sorted(p.name[:-len(".tgz")] for p in (LADDER / "inputs").glob("*.tgz"))
    first = [n for i, n in enumerate(names)
             if i == 0 or n.rsplit("-", 1)[0] != names[i - 1].rsplit("-", 1)[0]]
    if args.first_of_family:   # one instance a family: the smaller, by its name
        names = first
    elif args.rest_of_family:  # the others: the larger ones
        names = [n for n in names if n not in first]
    if args.instances is not None:
        unknown = sorted(set(args.instances) - set(names))
        if unknown:
            sys.exit(f"not instances of the ladder (or not in this half): {', '.join(unknown)}")
        names = [n for n in names if n in args.instances]
    print("\n".join(ladder(args.exams, args.only, args.timeout, args.jobs, names)))
    print()
    print("\n".join(floor()))


if __name__ == "__main__":
    main(sys.argv[1:])
