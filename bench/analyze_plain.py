"""Plain ``analyze`` against ``analyze --state-space`` on every example: what the invariant
bases and the bounded enumerations add to the exploration a user waits for.

Run:  .venv/bin/python -m bench.analyze_plain   (prints the section of bench/RESULTS.md)

For each mission of ``examples/``, the whole command a user runs, ``mcl2pnml analyze
MISSION --untimed`` with and without ``--state-space``, each five times in turn, in fresh
processes after one to warm up (the bytecode written, as a user's install keeps it); the
medians, and their ratio. The plain report has the exploration's verdicts
and the invariant bases besides; where the state space is built whole, the minimal
semi-positive invariants, siphons and traps are not enumerated (``--structure`` asks).
"""
from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUNS = 5


#: As a user's install runs: its modules' bytecode written once and kept.
ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def seconds(args: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mcl2pnml", *args], capture_output=True,
                   check=True, timeout=300, env=ENV)
    return time.perf_counter() - start


def main() -> None:
    print("| example | plain `analyze` (s) | `analyze --state-space` (s) | ratio |")
    print("|---|---:|---:|---:|")
    for mission in sorted((ROOT / "examples").glob("*.mcl")):
        seconds(["analyze", str(mission), "--untimed"])     # the warm-up writes the bytecode
        plain, space = [], []
        for _ in range(RUNS):   # in turn: a load that comes and goes weighs on both
            plain.append(seconds(["analyze", str(mission), "--untimed"]))
            space.append(seconds(["analyze", str(mission), "--untimed", "--state-space"]))
        a, b = statistics.median(plain), statistics.median(space)
        print(f"| {mission.stem} | {a:.2f} | {b:.2f} | {a / b:.2f} |")


if __name__ == "__main__":
    main()
