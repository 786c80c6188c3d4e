"""How reading and checking a mission grow with its size: ``mcl2pnml check`` on 1 to 16 MiB.

Run:  .venv/bin/python -m bench.mission_scale [MIB...]   (default 1 4 16)

Each size is a generated mission of at most that many MiB, the largest the default
``--max-mission-size`` (16 MiB) lets through, in two shapes: a survey
(:func:`bench.missions.survey`: one long block of calls, what makes missions long in
practice) and a relay (:func:`bench.missions.relay`: functions each running the next
in parallel, the warnings' hardest case). Each runs in a fresh interpreter (so that
peak memory is the size's own), the time of each stage of ``check`` (read and parse,
check, the warnings) and the peak resident memory measured inside it, less the
interpreter's own; the time is the process's CPU time, which other work on the machine
does not lengthen as it does the wall clock's. The table shows the median of three
runs, and the exponent of a least-squares fit of log(time) and log(peak) against
log(size): 1 is linear.
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile

from bench.core_scale import slope
from bench.missions import relay, survey

# Peak memory is the process's VmHWM (bench/compile_scale.py says why not ru_maxrss).
CHILD = r"""
import json, sys, time
def peak_mb():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
from mcl2pnml.language.semantics import check_program
from mcl2pnml.language.lint import lint
from mcl2pnml.language.parser import parse_file
base = peak_mb()   # the interpreter with the package imported, before the mission
t0 = time.process_time(); program = parse_file(sys.argv[1])
t1 = time.process_time(); checked = check_program(program)
t2 = time.process_time(); warnings = lint(checked)
t3 = time.process_time()
print(json.dumps({"parse": t1 - t0, "check": t2 - t1, "warnings": t3 - t2, "total": t3 - t0,
                  "peak_mb": peak_mb() - base}))
"""
STAGES = ("parse", "check", "warnings", "total")
SHAPES = {"survey": survey, "relay": relay}


def sized(shape: str, mib: float) -> str:
    """The mission of ``shape`` with the most units that is at most ``mib`` MiB."""
    make, limit = SHAPES[shape], int(mib * 2 ** 20)
    per = len(make(10_000)) / 10_000
    units = int(limit / per)
    text = make(units)
    while len(text.encode()) > limit:
        units -= max(1, units // 1000)
        text = make(units)
    return text


def measure(shape: str, mib: float, runs: int = 3) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as tmp:
        source = os.path.join(tmp, f"{shape}.mcl")
        with open(source, "w") as f:
            f.write(sized(shape, mib))
        results = [json.loads(subprocess.run([sys.executable, "-c", CHILD, source],
                                             capture_output=True, text=True,
                                             check=True).stdout) for _ in range(runs)]
        size = os.path.getsize(source)
    row = {k: statistics.median(r[k] for r in results) for k in (*STAGES, "peak_mb")}
    return {**row, "mib": size / 2 ** 20}


def main(argv: list[str]) -> None:
    sizes = [float(a) for a in argv] or [1, 4, 16]
    for shape in SHAPES:
        rows = {mib: measure(shape, mib) for mib in sizes}
        print(f"{shape}:")
        print("| MiB | " + " | ".join(f"{s} (s)" for s in STAGES)
              + " | peak (MB) | s/MiB | MB/MiB |")
        print("|---:" * (4 + len(STAGES)) + "|")
        for r in rows.values():
            print(f"| {r['mib']:.2f} | " + " | ".join(f"{r[s]:.2f}" for s in STAGES)
                  + f" | {r['peak_mb']:.0f} | {r['total'] / r['mib']:.2f} "
                  f"| {r['peak_mb'] / r['mib']:.0f} |")
        if len(sizes) > 1:
            mibs = [r["mib"] for r in rows.values()]
            print("exponent against size: " + ", ".join(
                f"{s} {slope(mibs, [r[s] for r in rows.values()]):.2f}"
                for s in (*STAGES, "peak_mb")))
        print()


if __name__ == "__main__":
    main(sys.argv[1:])
