"""Timed verdicts as the constants grow: zones and seconds, the whole command each.

Run:  .venv/bin/python -m bench.timed_scale [--timeout SECONDS]

(prints the section of ``bench/RESULTS.md``.)

The cost of ``mcl2pnml analyze MISSION --timed --json`` (start-up, compiling,
"every run ends", the end times), one fresh process per row under
GNU ``time``, on missions whose only change from row to row is a constant:

* a loop beside a long timer: a ``while`` whose body holds for 5 s and whose
  condition waits up to 3 s for a report, in a monitor whose other branch is a
  time-out of 100 s, then of 1,000 s and 10,000 s;
* ``examples/sampling.mcl`` with every time-out multiplied by 1, 2 and 3;
* ``examples/sauce.mcl`` with acknowledgements within 0, 1, 10 and 100 s.

Each row prints the zones of the verdict and of the end times (the JSON's
``zones`` and ``end_time_zones``), of the latter those that bound the latest end
(``latest_bound_zones``), the steps of the run that ends latest, and the number
of distinct time constants of the mission and its assumptions: the zones may
grow with how many constants there are, not with how large they are, but for
the run that ends latest, which is found zone by zone.
"""
from __future__ import annotations

import datetime
import json
import re
import sys
import tempfile
from pathlib import Path

from bench.real_models import ROOT, timed

#: Seconds a command may take.
TIMEOUT = 600.0
OURS = str(Path(sys.executable).with_name("mcl2pnml"))

LOOP_BESIDE_TIMER = """\
primitive Sonar();
primitive Hover();
primitive Wait();
task Check() = AchieveGoal(Sonar()) timeout 3;
task Hold() = KeepGoal(Hover()) timeout 5;
task Watch() = AchieveGoal(Wait()) timeout {long};
function Loop() {{
    while (Check()) do {{
        Hold();
    }}
}}
mission {{
    monitor(Loop(), Watch());
}}
"""


def _scaled(source: str, factor: int) -> str:
    """``source`` with every ``timeout N`` multiplied by ``factor``."""
    return re.sub(r"timeout (\d+)", lambda m: f"timeout {int(m.group(1)) * factor}", source)


def _constants(source: str, extra: tuple[str, ...]) -> int:
    """The distinct time constants: the mission's time-outs and the assumptions'."""
    return len(set(re.findall(r"timeout (\d+(?:\.\d+)?)", source)) | set(extra))


def cases() -> list[tuple[str, str, list[str]]]:
    """(row name, MCL source, extra options) of every row."""
    out = [(f"loop beside a {t:,} s timer", LOOP_BESIDE_TIMER.format(long=t), [])
           for t in (100, 1000, 10000)]
    sampling = (ROOT / "examples" / "sampling.mcl").read_text()
    out += [(f"sampling, time-outs x{k}", _scaled(sampling, k), []) for k in (1, 2, 3)]
    sauce = (ROOT / "examples" / "sauce.mcl").read_text()
    out += [(f"sauce, acknowledgements within {k} s", sauce, ["--ack-within", str(k)])
            for k in (0, 1, 10, 100)]
    return out


def run(timeout: float = TIMEOUT) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (name, source, extra) in enumerate(cases()):
            mission = Path(tmp) / f"case{k}.mcl"
            mission.write_text(source)
            ran = timed([OURS, "analyze", str(mission), "--timed", "--json", "--no-progress",
                         *extra], timeout)
            ack = extra[1:] if extra and extra[1] != "0" else ()
            row = {"name": name, "constants": _constants(source, tuple(ack) + ("1",))}
            if ran is None:
                row["seconds"] = None
            else:
                seconds, peak, output, _ = ran
                got = json.loads(output[:output.rindex("}") + 1])["timed"]
                row.update(seconds=seconds, peak=peak, ends=got["always_ends"],
                           zones=got["zones"], time_zones=got.get("end_time_zones"),
                           bound_zones=got.get("latest_bound_zones"),
                           steps=len(got.get("latest_run") or ()), latest=got["latest"])
            rows.append(row)
            print(f"  {row}", file=sys.stderr, flush=True)
    return rows


def table(rows: list[dict], timeout: float) -> str:
    out = ["| mission | distinct constants | always ends | zones (verdict) | zones (end times) "
           "| of which the latest's bound | latest end (s) | steps of the latest run | seconds "
           "| peak MiB |", "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if r["seconds"] is None:
            out.append(f"| {r['name']} | {r['constants']} | no answer in {timeout:g} s "
                       "| - | - | - | - | - | - | - |")
            continue
        ends = {True: "yes", False: "no", None: "unknown"}[r["ends"]]
        latest = "never" if r["latest"] is None else f"{r['latest']:,}"
        out.append(f"| {r['name']} | {r['constants']} | {ends} | {r['zones']:,} "
                   f"| {r['time_zones'] or 0:,} | {r['bound_zones'] or 0:,} | {latest} "
                   f"| {r['steps']:,} | {r['seconds']:.2f} "
                   f"| {r['peak']:.0f} |")
    return "\n".join(out)


def main(argv: list[str]) -> None:
    timeout = float(argv[argv.index("--timeout") + 1]) if "--timeout" in argv else TIMEOUT
    rows = run(timeout)
    print(f"## Timed verdicts as the constants grow\n\nMeasured {datetime.date.today()}, "
          "one process at a time (`python -m bench.timed_scale`): `mcl2pnml analyze MISSION "
          "--timed --json`, the whole command, wall seconds and peak resident memory (GNU "
          "time). \"distinct constants\": the mission's time-outs and the assumptions' "
          "bounds.\n")
    print(table(rows, timeout))


if __name__ == "__main__":
    main(sys.argv[1:])
