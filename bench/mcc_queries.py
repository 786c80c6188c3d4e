"""The Model Checking Contest's questions: ours against verifypn on the contest's own files.

Run:  .venv/bin/python -m bench.mcc_queries   (prints the section of bench/RESULTS.md)

For each of the 19 models of ``../shared/external-nets/mcc-queries`` and each of its
seven formula files, the whole command a user runs, in a fresh process: ours,
``mcl2pnml query model.pnml FILE.xml``; verifypn with its defaults (reductions on),
``verifypn-linux64 -n 1 -x 1,...,16 model.pnml FILE.xml`` (``-ltl`` for the LTL
files). Wall seconds and the process's peak memory; a call past 60 s counts as not
answered. Every answer is held to the 2021 consensus (``oracle/``).
"""
from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORPUS = ROOT.parent / "shared" / "external-nets" / "mcc-queries"
VERIFYPN = ROOT.parent / "shared" / "peers" / "bin" / "verifypn-linux64"
FILES = ("ReachabilityCardinality", "ReachabilityFireability", "CTLCardinality",
         "CTLFireability", "LTLCardinality", "LTLFireability", "UpperBounds")
TIMEOUT = 60.0


def run(args: list[str]) -> tuple[float, float, str]:
    """Wall seconds (None past the timeout), the process's peak MiB (GNU time's %M),
    stdout."""
    start = time.perf_counter()
    try:
        done = subprocess.run(["/usr/bin/time", "-f", "%M", *args], capture_output=True,
                              text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return None, 0.0, ""
    seconds = time.perf_counter() - start
    peak = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "0"
    return seconds, int(peak) / 1024 if peak.isdigit() else 0.0, done.stdout


def answers(out: str) -> dict[str, str]:
    return dict(re.findall(r"^FORMULA (\S+) (TRUE|FALSE|\d+)", out, re.M))


def oracle(model: str) -> dict[str, str]:
    found = {}
    for f in (CORPUS / "oracle").glob(f"{model}-*.out"):
        found.update(re.findall(r"^FORMULA (\S+) (\S+) TECHNIQUES", f.read_text(), re.M))
    return found


def main() -> None:
    rows = {name: {"ours": [0.0, 0, 0, 0.0], "verifypn": [0.0, 0, 0, 0.0]} for name in FILES}
    for model in sorted(p for p in CORPUS.iterdir() if p.is_dir() and p.name != "oracle"):
        truth = oracle(model.name)
        for name in FILES:
            file = model / f"{name}.xml"
            ours = [sys.executable, "-m", "mcl2pnml", "query", str(model / "model.pnml"),
                    str(file)]
            peer = [str(VERIFYPN), "-n", "1", *(["-ltl"] if name.startswith("LTL") else []),
                    "-x", ",".join(map(str, range(1, 17))), str(model / "model.pnml"), str(file)]
            for who, args in (("ours", ours), ("verifypn", peer)):
                seconds, mib, out = run(args)
                got = answers(out)
                row = rows[name][who]
                row[0] += seconds if seconds is not None else TIMEOUT
                row[1] += sum(1 for k, v in got.items() if truth.get(k) == v)
                row[2] += sum(1 for k, v in got.items() if truth.get(k) not in (v, "?", None))
                row[3] = max(row[3], mib)
    print("| examination | ours: right | ours: wrong | ours (s) | ours peak MiB | "
          "verifypn: right | verifypn: wrong | verifypn (s) | verifypn peak MiB | "
          "ours / verifypn |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, r in rows.items():
        o, v = r["ours"], r["verifypn"]
        print(f"| {name} | {o[1]} | {o[2]} | {o[0]:.1f} | {o[3]:.0f} | {v[1]} | {v[2]} | "
              f"{v[0]:.1f} | {v[3]:.0f} | {o[0] / max(v[0], 1e-9):.1f}x |")


if __name__ == "__main__":
    main()
