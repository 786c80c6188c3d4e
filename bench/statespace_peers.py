"""State spaces: our explorer against SNAKES, pm4py, verifypn and LoLA, on the same PNML files.

Run:  .venv/bin/python -m bench.statespace_peers

Every exploration runs in a fresh interpreter (so that peak memory is its
own) on a PNML file written by us. Ours explores the reachable markings
(:func:`mcl2pnml.analysis.statespace.explore.explore`) with the native explorer (the loops
in C; the numpy one where they were not built), and then,
timed apart, finds what ``mcl2pnml analyze FILE --state-space`` adds to
them (terminal markings, deadlock freedom, reusability); "numpy" is our
numpy explorer on the same file; SNAKES builds its ``StateGraph``; pm4py
its reachability graph. Loading the file and the code is not timed (loading
the explorer's code is timed apart as ``load_seconds``); the exploration is. (The peers also store the edges; ours derives them when
asked, which the second, analysis time includes where it needs them.) A run that does
not finish within :data:`TIMEOUT` seconds is reported as such. Each figure
is the median of :data:`RUNS` runs when a run takes under 5 s, else one run.

Then, on the same file, the whole commands a user runs, each a fresh process
with its peak memory (:func:`measure_command`): ``mcl2pnml analyze
--state-space`` (start-up, reading, exploring, the analysis and the output),
TAPAAL's verifypn and LoLA with their reductions off; for the peers also
their exploration alone, as they print it.
"""
from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from mcl2pnml.io.pnml import write_pnml

from mcl2pnml.analysis import zoo
from bench import nets, real_models

TIMEOUT = 60.0
RUNS = 3

CHILD = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
engine, path = sys.argv[1], sys.argv[2]
def rss():
    # the peak resident memory of this process (VmHWM), in bytes; getrusage's
    # ru_maxrss would include the parent's pages at the fork before exec
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) * 1024
extra = {}
if engine in ("ours", "numpy"):
    from mcl2pnml.io.pnml import read_pnml
    from mcl2pnml.analysis.statespace import compiled as compiledspace
    from mcl2pnml.analysis.behaviour import behaviour
    from mcl2pnml.core.structure import structure
    from mcl2pnml.analysis.statespace.explore import explore
    s = structure(read_pnml(path))
    # ours: the loops in C where they were built (what `analyze` takes), else numpy;
    # loading them is timed apart
    t0 = time.perf_counter()
    backend = ("native" if compiledspace.native_available() else "packed"
               ) if engine == "ours" else "packed"
    extra["load_seconds"] = time.perf_counter() - t0
    extra["backend"] = backend
    before = rss(); t0 = time.perf_counter()
    space = explore(s, max_states=50_000_000, backend=backend)
    states = space.states
    seconds, size = time.perf_counter() - t0, max(0, rss() - before)
    if engine == "ours":
        t1 = time.perf_counter(); verdict = behaviour(space)
        extra.update(analysis_seconds=time.perf_counter() - t1, reusable=verdict.reusable)
elif engine == "snakes":
    import snakes.pnml
    from snakes.nets import StateGraph
    net = snakes.pnml.loads(open(path).read())
    before = rss(); t0 = time.perf_counter()
    graph = StateGraph(net); graph.build(); states = len(graph)
else:
    import pm4py
    from pm4py.objects.petri_net.utils.reachability_graph import construct_reachability_graph
    pn, im, _ = pm4py.read_pnml(path)
    before = rss(); t0 = time.perf_counter()
    states = len(construct_reachability_graph(pn, im).states)
if engine != "ours":
    seconds, size = time.perf_counter() - t0, max(0, rss() - before)
print(json.dumps({"states": states, "seconds": seconds, "bytes": size, **extra}))
"""


def measure(engine: str, path: Path) -> dict | None:
    """One engine on one file: median of a few runs, or None if it timed out."""
    results = []
    for _ in range(RUNS):
        try:
            out = subprocess.run([sys.executable, "-c", CHILD, engine, str(path)],
                                 capture_output=True, text=True, timeout=TIMEOUT, check=True)
        except subprocess.TimeoutExpired:
            return None
        results.append(json.loads(out.stdout.strip().splitlines()[-1]))
        if results[-1]["seconds"] > 5:
            break
    summary = {"states": results[0]["states"],
               "seconds": statistics.median(r["seconds"] for r in results),
               "bytes": statistics.median(r["bytes"] for r in results)}
    for extra in ("analysis_seconds", "load_seconds"):
        if extra in results[0]:
            summary[extra] = statistics.median(r[extra] for r in results)
    if "backend" in results[0]:
        summary["backend"] = results[0]["backend"]
    return summary


def measure_command(tool: str, path: Path) -> dict | None:
    """The whole command a user runs (:mod:`bench.real_models`): ``mcl2pnml analyze
    --state-space``, or a peer with its reductions off; the median of a few
    runs when a run takes under 5 s, else one. None: not installed, failed,
    timed out."""
    command = real_models.commands(path)[tool]
    if command is None:
        return None
    results = []
    for _ in range(RUNS):
        result = real_models.measure(tool, command)
        if result is None:
            return None
        results.append(result)
        if result["seconds"] > 5:
            break
    middle = sorted(results, key=lambda r: r["seconds"])[len(results) // 2]
    return {**middle, "peak_mb": statistics.median(r["peak_mb"] for r in results)}


#: The nets where our whole command is held to the peers: at least as fast as the
#: faster of verifypn and LoLA, within twice verifypn's peak memory.
HELD = (("cycles", 10), ("cycles", 11), ("dam inspection, aborts pending", 0),
        ("dam inspection, aborts pending", 1))

CASES = ([("cycles", k, zoo.cycles) for k in range(6, 12)]
         + [("philosophers", n, zoo.philosophers_left_first) for n in (8, 10, 12)]
         + [("token ring", n, zoo.token_ring) for n in (8, 10, 12)]
         + [("shared memory", n, zoo.shared_memory) for n in (6, 8, 10)]
         + [("mission, parallel width", w, nets.mission) for w in (2, 3, 4)]
         + [("dam inspection, aborts pending", a, nets.dam) for a in (0, 1)])


def run(cases=CASES, peers=("snakes", "pm4py"), log=print,
        commands=("ours", "verifypn", "lola")) -> list[dict]:
    """Every case on ours and on each peer, then as whole commands (``commands``).

    A peer is not run on a net where it cannot finish in time: where it
    timed out on a smaller net of the family, or where its time per marking
    on the previous net of the family, times this net's markings, is past
    :data:`TIMEOUT` (peers take at least linear time in the markings).
    """
    rows = []
    last: dict[tuple[str, str], float | None] = {}   # (family, peer) -> seconds a marking
    with tempfile.TemporaryDirectory() as tmp:
        for family, size, make in cases:
            path = write_pnml(make(size), Path(tmp) / f"{family}-{size}.pnml".replace(" ", "_"))
            row = {"family": family, "size": size, "ours": measure("ours", path),
                   "numpy": measure("numpy", path)}
            for peer in peers:
                rate = last.get((family, peer), 0.0)
                hopeless = rate is None or rate * row["ours"]["states"] > TIMEOUT
                row[peer] = None if hopeless else measure(peer, path)
                last[family, peer] = (row[peer]["seconds"] / row["ours"]["states"]
                                      if row[peer] else None)
            row["command"] = {tool: measure_command(tool, path) for tool in commands}
            rows.append(row)
            log(f"  {family} {size}: " + ", ".join(
                f"{k} {v['seconds']:.3f}s" if v else f"{k} -" for k, v in
                [*row.items(), *row["command"].items()] if k not in ("family", "size", "command")))
    return rows


if __name__ == "__main__":
    for r in run():
        print(json.dumps(r))
