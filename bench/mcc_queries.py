"""The Model Checking Contest's questions: ours against verifypn and LoLA on the contest's
own files.

Run:  .venv/bin/python -m bench.mcc_queries   (prints the section of bench/RESULTS.md)

For each of the 19 models of ``../shared/external-nets/mcc-queries`` and each of its
seven formula files, the whole command a user runs, in a fresh process: ours,
``mcl2pnml query model.pnml FILE.xml``; verifypn with its defaults (reductions on),
``verifypn-linux64 -n 1 -x 1,...,16 model.pnml FILE.xml`` (``-ltl`` for the LTL
files); LoLA with its defaults (reductions on), ``lola --pnmlnet model.pnml --xmlformula
--formula=FILE.xml --mcc --quiet``. Wall seconds and the process's peak memory; a call
past 60 s counts as not answered. Every answer is held to the 2021 consensus (``oracle/``).
Run with ``--only ours`` to time ours alone; ``--per-model`` adds ours with a model's
seven files in one command (one start-up, one graph), which the peers' commands do not
take.

Then the generic examinations, one process each: ours, ``mcl2pnml query model.pnml
--examination NAME``; LoLA, ``lola --pnmlnet model.pnml --check=CHECK --mcc`` (verifypn
has no such command), on the 19 models (held to the oracle) and on the larger contest
models of ``../shared/external-nets/bench-models`` (where ours and LoLA's must agree).
LoLA runs in a scratch folder: it leaves files behind.
"""
from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORPUS = ROOT.parent / "shared" / "external-nets" / "mcc-queries"
PEERS = ROOT.parent / "shared" / "peers" / "bin"
VERIFYPN = PEERS / "verifypn-linux64"
LOLA = PEERS / "lola"
TOOLS = ("ours", "verifypn", "lola")
FILES = ("ReachabilityCardinality", "ReachabilityFireability", "CTLCardinality",
         "CTLFireability", "LTLCardinality", "LTLFireability", "UpperBounds")
TIMEOUT = 60.0
BENCH_MODELS = ROOT.parent / "shared" / "external-nets" / "bench-models"
#: The generic examinations, and the check LoLA names each by.
GENERIC = {"ReachabilityDeadlock": "deadlockfreedom", "OneSafe": "OneSafe",
           "StableMarking": "StableMarking", "QuasiLiveness": "QuasiLiveness",
           "Liveness": "Liveness"}
SCRATCH = tempfile.mkdtemp(prefix="mcc-bench-")


def run(args: list[str]) -> tuple[float, float, str]:
    """Wall seconds (None past the timeout), the process's peak MiB (GNU time's %M),
    stdout."""
    start = time.perf_counter()
    try:
        done = subprocess.run(["/usr/bin/time", "-f", "%M", *args], capture_output=True,
                              text=True, timeout=TIMEOUT, cwd=SCRATCH)
    except subprocess.TimeoutExpired:
        return None, 0.0, ""
    seconds = time.perf_counter() - start
    peak = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "0"
    return seconds, int(peak) / 1024 if peak.isdigit() else 0.0, done.stdout


def answers(out: str) -> dict[str, str]:
    return dict(re.findall(r"^FORMULA (\S+)\s+(TRUE|FALSE|\d+)\s", out, re.M))


def oracle(model: str) -> dict[str, str]:
    found = {}
    for f in (CORPUS / "oracle").glob(f"{model}-*.out"):
        found.update(re.findall(r"^FORMULA (\S+) (\S+) TECHNIQUES", f.read_text(), re.M))
    return found


def commands(model: Path, name: str) -> dict[str, list[str]]:
    """Each tool's whole command for one formula file of one model."""
    net, file = str(model / "model.pnml"), str(model / f"{name}.xml")
    return {
        "ours": [sys.executable, "-m", "mcl2pnml", "query", net, file],
        "verifypn": [str(VERIFYPN), "-n", "1", *(["-ltl"] if name.startswith("LTL") else []),
                     "-x", ",".join(map(str, range(1, 17))), net, file],
        "lola": [str(LOLA), "--pnmlnet", net, "--xmlformula", f"--formula={file}", "--mcc",
                 "--quiet"],
    }


def main() -> None:
    tools = sys.argv[sys.argv.index("--only") + 1].split(",") if "--only" in sys.argv \
        else list(TOOLS)
    rows = {name: {who: [0.0, 0, 0, 0.0] for who in tools} for name in FILES}
    for model in sorted(p for p in CORPUS.iterdir() if p.is_dir() and p.name != "oracle"):
        truth = oracle(model.name)
        for name in FILES:
            for who, args in commands(model, name).items():
                if who not in tools:
                    continue
                seconds, mib, out = run(args)
                got = answers(out)
                row = rows[name][who]
                row[0] += seconds if seconds is not None else TIMEOUT
                row[1] += sum(1 for k, v in got.items() if truth.get(k) == v)
                row[2] += sum(1 for k, v in got.items() if truth.get(k) not in (v, "?", None))
                row[3] = max(row[3], mib)
    print("| examination | " + " | ".join(f"{w}: right / wrong | {w} (s) | {w} peak MiB"
                                          for w in tools) + " |")
    print("|---|" + "---:|---:|---:|" * len(tools))
    total = {w: [0.0, 0, 0] for w in tools}
    for name, r in rows.items():
        cells = []
        for w in tools:
            t, right, wrong, mib = r[w]
            cells.append(f"{right} / {wrong} | {t:.1f} | {mib:.0f}")
            total[w][0] += t
            total[w][1] += right
            total[w][2] += wrong
        print(f"| {name} | " + " | ".join(cells) + " |")
    print("| **total** | " + " | ".join(f"**{right} / {wrong}** | **{t:.1f}** | "
                                        for t, right, wrong in total.values()) + " |")
    if "--per-model" in sys.argv:
        per_model()
    if "--generic" in sys.argv:
        generic()


def per_model() -> None:
    """Ours with a model's seven files in one command (``mcl2pnml query model.pnml
    F1.xml ... F7.xml``: one start-up and one reachability graph for all), as a user
    answering a model's questions runs it; the peers read one formula file a command."""
    seconds, right, wrong, peak = 0.0, 0, 0, 0.0
    for model in sorted(p for p in CORPUS.iterdir() if p.is_dir() and p.name != "oracle"):
        truth = oracle(model.name)
        args = [sys.executable, "-m", "mcl2pnml", "query", str(model / "model.pnml"),
                *(str(model / f"{name}.xml") for name in FILES)]
        t, mib, out = run(args)
        got = answers(out)
        seconds += t if t is not None else TIMEOUT
        right += sum(1 for k, v in got.items() if truth.get(k) == v)
        wrong += sum(1 for k, v in got.items() if truth.get(k) not in (v, "?", None))
        peak = max(peak, mib)
    print()
    print(f"ours, a model's seven files in one command: {right} right / {wrong} wrong, "
          f"{seconds:.1f} s over the 19 models, peak {peak:.0f} MiB")


def generic() -> None:
    """The generic examinations: ours against LoLA, per model, one process each."""
    models = [(p.name, p / "model.pnml", oracle(p.name)) for p in sorted(CORPUS.iterdir())
              if p.is_dir() and p.name != "oracle"]
    models += [(p.stem, p, None) for p in sorted(BENCH_MODELS.glob("*.pnml"))]
    print()
    print("| model | ours: answered / wrong | ours (s) | ours peak MiB | lola: answered / "
          "wrong | lola (s) | lola peak MiB | disagreements |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for name, net, truth in models:
        rows = {"ours": [0, 0, 0.0, 0.0], "lola": [0, 0, 0.0, 0.0]}
        said: dict[str, dict[str, str]] = {"ours": {}, "lola": {}}
        for exam, check in GENERIC.items():
            for who, args in (("ours", [sys.executable, "-m", "mcl2pnml", "query", str(net),
                                        "--examination", exam]),
                              ("lola", [str(LOLA), "--pnmlnet", str(net), f"--check={check}",
                                        "--mcc", "--quiet"])):
                seconds, mib, out = run(args)
                got = answers(out).get(exam)
                row = rows[who]
                row[2] += seconds if seconds is not None else TIMEOUT
                row[3] = max(row[3], mib)
                if got is not None:
                    said[who][exam] = got
                    row[0] += 1
                    row[1] += truth is not None and truth.get(exam) not in (got, "?", None)
        differ = sum(1 for e, v in said["ours"].items() if said["lola"].get(e, v) != v)
        cells = " | ".join(f"{a} / {w} | {t:.1f} | {m:.0f}" for a, w, t, m in rows.values())
        print(f"| {name}{'' if truth is not None else ' (no oracle)'} | {cells} | {differ} |")


if __name__ == "__main__":
    main()
