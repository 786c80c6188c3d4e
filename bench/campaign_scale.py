"""Campaigns: simulated runs of the paper's mission per second, on 1 and on 2 workers.

Run:  .venv/bin/python -m bench.campaign_scale [RUNS]   (default 100,000; prints the
      section of bench/RESULTS.md, which ``make bench`` writes)

The whole command a user runs, ``mcl2pnml campaign examples/sauce.mcl
--vehicle-model examples/sauce.model.json --runs N --workers W --json``, in a
fresh process (Dask's local cluster started and stopped inside it), timed on
the wall clock, with the peak resident memory of its largest process (the
command or a worker). The exact odds (``mcl2pnml odds``) are timed beside it,
and the campaign's frequencies are held to them. Then the same mission on the
kinematic simulator, with currents, injected faults and its properties judged
(:data:`SIM_RUNS` runs).
"""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MISSION = ROOT / "examples" / "sauce.mcl"
MODEL = ROOT / "examples" / "sauce.model.json"
WORLD = ROOT / "examples" / "currents.world.json"
FAULTS = ROOT / "examples" / "sauce.faults.json"
#: Runs of the campaign on the kinematic simulator (each integrates the vehicle's motion).
SIM_RUNS = 5_000


def timed(args: list[str]) -> tuple[float, float, str]:
    """Wall seconds, peak MiB (the largest process of the command's tree), stdout."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "mcl2pnml", *args], capture_output=True,
                         text=True, check=True)
    seconds = time.perf_counter() - start
    peak = max(before, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024
    return seconds, peak, out.stdout


def measure(runs: int) -> dict:
    base = ["--vehicle-model", str(MODEL), "--json"]
    exact_s, exact_mib, exact = timed(["odds", str(MISSION), *base])
    rows = []
    for workers in (1, 2):
        s, mib, out = timed(["campaign", str(MISSION), *base, "--runs", str(runs),
                             "--workers", str(workers), "--no-progress"])
        rows.append({"workers": workers, "seconds": s, "mib": mib, "result": json.loads(out)})
    sim_runs = min(runs, SIM_RUNS)
    simulated = []
    for workers in (1, 2):
        s, mib, out = timed(["campaign", str(MISSION), "--world", str(WORLD), "--faults",
                             str(FAULTS), "--properties", "--json", "--runs", str(sim_runs),
                             "--workers", str(workers), "--no-progress"])
        simulated.append({"workers": workers, "seconds": s, "mib": mib,
                          "result": json.loads(out)})
    return {"runs": runs, "exact": json.loads(exact), "exact_seconds": exact_s,
            "exact_mib": exact_mib, "campaigns": rows, "cores": os.cpu_count(),
            "sim_runs": sim_runs, "simulated": simulated}


def section(m: dict) -> tuple[list[str], list[tuple[str, bool, str]]]:
    runs = m["runs"]
    lines = ["## Campaigns: simulated runs on Dask", "",
             f"`mcl2pnml campaign examples/sauce.mcl --vehicle-model examples/sauce.model.json "
             f"--runs {runs:,} --workers W` (the paper's mission with a sonar that misses the "
             "cross one time in three), the whole command in a fresh process, Dask's local "
             "cluster started and stopped inside it; peak memory is its largest process's. "
             "Beside it, `mcl2pnml odds` on the same model, whose figures the campaign's "
             "99% intervals must hold.", "",
             "| workers | seconds | runs/s | runs/s per worker | peak MiB | P(OK) [99%] | "
             "holds the exact P(OK) |", "|---:|---:|---:|---:|---:|---|---|"]
    exact_ok = m["exact"]["outcomes"]["OK"]
    held = True
    for r in m["campaigns"]:
        ok = r["result"]["outcomes"].get("OK", {"frequency": 0, "interval": [0, 0]})
        low, high = ok["interval"]
        inside = low <= exact_ok <= high
        held &= inside
        rate = runs / r["seconds"]
        lines.append(f"| {r['workers']} | {r['seconds']:.1f} | {rate:,.0f} | "
                     f"{rate / r['workers']:,.0f} | {r['mib']:.0f} | {ok['frequency']:.4f} "
                     f"[{low:.4f}, {high:.4f}] | {'yes' if inside else 'no'} |")
    one, two = (r["seconds"] for r in m["campaigns"])
    speedup = one / two
    lines += ["", f"Speed-up from 1 to 2 workers: {speedup:.2f}x (on {m['cores']} cores). "
              f"The exact odds: P(OK) = {exact_ok:.6f}, in {m['exact_seconds']:.2f} s and "
              f"{m['exact_mib']:.0f} MiB: {one / m['exact_seconds']:,.0f} times faster than "
              f"the campaign on one worker, and exact."]
    n = m["sim_runs"]
    lines += ["", f"On the kinematic simulator: `mcl2pnml campaign examples/sauce.mcl --world "
              "examples/currents.world.json --faults examples/sauce.faults.json --properties "
              f"--runs {n:,} --workers W` (the vehicle's motion integrated every 0.1 s, "
              "currents seeded per run, KeepDepth's reports failed one time in five, each run "
              "judged on the mission's eight properties).", "",
              "| workers | seconds | runs/s | runs/s per worker | peak MiB | P(OK) [99%] |",
              "|---:|---:|---:|---:|---:|---|"]
    for r in m["simulated"]:
        ok = r["result"]["outcomes"].get("OK", {"frequency": 0, "interval": [0, 0]})
        low, high = ok["interval"]
        rate = n / r["seconds"]
        lines.append(f"| {r['workers']} | {r['seconds']:.1f} | {rate:,.0f} | "
                     f"{rate / r['workers']:,.0f} | {r['mib']:.0f} | {ok['frequency']:.4f} "
                     f"[{low:.4f}, {high:.4f}] |")
    sim_one, sim_two = (r["seconds"] for r in m["simulated"])
    lines += ["", f"Speed-up from 1 to 2 workers on the simulator: {sim_one / sim_two:.2f}x."]
    targets = [(f"campaign: {runs:,} runs of the paper's mission on 2 workers within 5 minutes",
                two <= 300, f"{two:.0f} s"),
               ("campaign: its 99% intervals hold the exact P(OK)", held,
                f"exact {exact_ok:.4f}"),
               ("campaign: 1.6x from 1 to 2 workers", speedup >= 1.6, f"{speedup:.2f}x")]
    return lines, targets


def main(argv: list[str]) -> None:
    m = measure(int(argv[0]) if argv else 100_000)
    lines, targets = section(m)
    print("\n".join(lines))
    for name, ok, said in targets:
        print(f"- {name}: {'holds' if ok else 'missed'} ({said})")


if __name__ == "__main__":
    main(sys.argv[1:])
