"""The executor's reaction time: from a vehicle event to the actions it causes.

Run:  .venv/bin/python -m bench.executor_latency [TASKS...]   (default 10 100 1000 10000)

Surveys of N task calls (:func:`bench.missions.survey`) run against a
scripted vehicle that achieves every goal after one second; every event's
handling (the executor firing what it enables, up to the actions it emits)
is timed, over three runs of a fresh engine, pooled. The median and the
99th percentile are reported; the last event, which closes the mission's N
nested sequences at once (a cascade of firings linear in N), is the
maximum and is left out of neither.
"""
from __future__ import annotations

import json
import statistics
import sys
import time

from mcl2pnml.runtime.aal import ScriptedVehicle
from mcl2pnml.runtime.engine import run
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.pipeline import compile_source

from bench.missions import survey


def measure(tasks: int, runs: int = 3) -> dict[str, float]:
    """The event times of ``runs`` runs of a fresh engine on the ``tasks``-call survey, pooled."""
    net = compile_source(survey(tasks), f"survey{tasks}.mcl")
    times: list[float] = []
    for _ in range(runs):
        engine = PetriEngine(net)
        vehicle = ScriptedVehicle.from_json(json.dumps(
            {"KeepDepth": ["ok@1"] * tasks, "GoToWayPoint": ["ok@1"] * tasks}))
        handle = engine.on_event

        def timed(event, handle=handle):
            t0 = time.perf_counter()
            actions = handle(event)
            times.append(time.perf_counter() - t0)
            return actions
        engine.on_event = timed
        result = run(engine, vehicle)
        assert result.outcome.value == "OK", result.outcome
    times.sort()
    return {"tasks": tasks, "events": len(times) // runs, "runs": runs,
            "median_us": statistics.median(times) * 1e6,
            "p99_us": times[min(len(times) - 1, int(0.99 * len(times)))] * 1e6,
            "max_us": times[-1] * 1e6}


def main(argv: list[str]) -> None:
    for n in [int(a) for a in argv] or [10, 100, 1000, 10_000]:
        print(json.dumps(measure(n)))


if __name__ == "__main__":
    main(sys.argv[1:])
