"""What writing every arc's inscription costs: a 10,000-call mission's PNML, with the
weight-1 inscriptions (as written now, so that WoPeD reads the file without a warning)
and without them (the same bytes with those inscriptions taken out).

Run:  .venv/bin/python -m bench.inscriptions [CALLS]   (default 10,000)
"""
from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

from bench.missions import survey
from mcl2pnml import pipeline
from mcl2pnml.io.pnml.writer import _ONE, write_pnml


def main(argv: list[str]) -> None:
    calls = int(argv[0]) if argv else 10_000
    net = pipeline.compile_checked(pipeline.check_source(survey(calls), "survey.mcl"))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "survey.pnml"
        times = []
        for _ in range(5):
            start = time.perf_counter()
            write_pnml(net, path)
            times.append(time.perf_counter() - start)
        data = path.read_bytes()
    without = len(data.replace(_ONE.encode(), b""))
    print(f"{calls:,} calls: {len(net.places):,} places, {len(net.transitions):,} "
          f"transitions, {len(net.arcs):,} arcs; written in {statistics.median(times):.2f} s "
          f"(median of 5); {len(data):,} bytes with every inscription, {without:,} without "
          f"those of weight 1 (+{len(data) / without - 1:.1%})")


if __name__ == "__main__":
    main(sys.argv[1:])
