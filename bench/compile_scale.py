"""How compiling grows with the mission: MCL to PNML on disk, 100 to 10,000 calls.

Run:  .venv/bin/python -m bench.compile_scale [CALLS...]   (default 100 1000 10000)

Each size runs in a fresh interpreter (so that peak memory is the size's
own), three times; the table shows the median time of each stage (read and
parse, check, compile, write the PNML), the total, the peak resident memory,
and the exponent of a least-squares fit of log(time) against log(calls):
1 is linear. Missions come from :func:`bench.missions.survey`.
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile

from bench.core_scale import slope

# Peak memory is the process's VmHWM: getrusage's ru_maxrss would also count
# the parent's pages at the fork before exec (Linux keeps that high-water mark
# across execve), so a child of a big parent would report the parent's peak.
CHILD = r"""
import json, sys, time
def peak_mb():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
from mcl2pnml.language.parser import parse_file
from mcl2pnml.language.semantics import check_program
from mcl2pnml.language.compiler import compile_checked
from mcl2pnml.pipeline import save_pnml
source, target = sys.argv[1], sys.argv[2]
t0 = time.perf_counter(); program = parse_file(source)
t1 = time.perf_counter(); checked = check_program(program)
t2 = time.perf_counter(); net = compile_checked(checked)
t3 = time.perf_counter(); save_pnml(net, target)
t4 = time.perf_counter()
print(json.dumps({"parse": t1 - t0, "check": t2 - t1, "compile": t3 - t2, "write": t4 - t3,
                  "total": t4 - t0, "peak_mb": peak_mb(),
                  "places": len(net.places), "transitions": len(net.transitions),
                  "arcs": len(net.arcs)}))
"""
STAGES = ("parse", "check", "compile", "write", "total")


def measure(calls: int, runs: int = 3) -> dict[str, float]:
    from bench.missions import survey

    with tempfile.TemporaryDirectory() as tmp:
        source = os.path.join(tmp, f"survey{calls}.mcl")
        with open(source, "w") as f:
            f.write(survey(calls))
        results = []
        for _ in range(runs):
            out = subprocess.run([sys.executable, "-c", CHILD, source,
                                  os.path.join(tmp, "out.pnml")],
                                 capture_output=True, text=True, check=True)
            results.append(json.loads(out.stdout))
            size_mb = os.path.getsize(os.path.join(tmp, "out.pnml")) / 1e6
    row = {k: statistics.median(r[k] for r in results) for k in (*STAGES, "peak_mb")}
    row.update({k: results[0][k] for k in ("places", "transitions", "arcs")}, pnml_mb=size_mb)
    return row


FLOOR = r"""
import json, sys, time
elements, arcs = int(sys.argv[1]), int(sys.argv[2])
ends = [f"mission.sequence-{i // 100}.T1_OK" for i in range(arcs)]   # ids of compiled length
t0 = time.perf_counter(); objects = [(i, None) for i in range(elements)]
t1 = time.perf_counter(); del objects
text = "".join([f'<arc id="a{k}" source="{a}" target="{b}"/>\n'
                for k, a, b in zip(range(1, arcs + 1), ends, ends)])
t2 = time.perf_counter()
print(json.dumps({"objects": t1 - t0, "arc_lines": t2 - t1}))
"""


def floor(elements: int, arcs: int) -> dict[str, float]:
    """What CPython alone takes, on this machine, for the least a compile must do per element.

    In a fresh interpreter: creating one small object (a 2-tuple) per
    element of the net, and formatting one ``<arc .../>`` line per arc and
    joining them, with nothing else around; the faster of three runs. A
    compile that builds an object per element and writes a line per arc
    cannot beat their sum.
    """
    runs = [json.loads(subprocess.run([sys.executable, "-c", FLOOR, str(elements), str(arcs)],
                                      capture_output=True, text=True, check=True).stdout)
            for _ in range(3)]
    return {k: min(r[k] for r in runs) for k in ("objects", "arc_lines")}


def main(argv: list[str]) -> None:
    sizes = [int(a) for a in argv] or [100, 1_000, 10_000]
    rows = {n: measure(n) for n in sizes}
    print("| calls | places | transitions | arcs | " + " | ".join(f"{s} (s)" for s in STAGES)
          + " | peak (MB) | PNML (MB) |")
    print("|---:" * (6 + len(STAGES)) + "|")
    for n, r in rows.items():
        print(f"| {n:,} | {r['places']:,} | {r['transitions']:,} | {r['arcs']:,} | "
              + " | ".join(f"{r[s]:.3f}" for s in STAGES)
              + f" | {r['peak_mb']:.0f} | {r['pnml_mb']:.1f} |")
    if len(sizes) > 1:
        print()
        print("exponent of time against calls: " + ", ".join(
            f"{s} {slope(sizes, [rows[n][s] for n in sizes]):.2f}" for s in STAGES))


if __name__ == "__main__":
    main(sys.argv[1:])
