"""Certificates: proving a mission from its parts against exploring it, and how it scales.

Run:  .venv/bin/python -m bench.certify_scale [--quick]

* the dam inspection (``examples/dam_inspection.mcl``), from ``mission.B``
  and with an abort pending (``mission.A`` marked too): certifying
  (:func:`mcl2pnml.certify.certificate.certify`) and checking the
  certificate against the compiled net (:func:`mcl2pnml.certify.recheck.check_certificate`,
  which re-reads the stored proofs and re-derives the library's own
  digests), each in this process, the median of :data:`RUNS`; beside them,
  exploring the same net and deciding its behaviour (1-safe, a proper end always
  reachable, reusable) with our fastest explorer;
* surveys of 100 to 10,000 calls (:func:`bench.missions.survey`): certify
  and check, with the fitted exponent of time against size (1: linear);
* the whole commands a user runs, each a fresh process with its peak memory
  (:func:`bench.real_models.timed`): ``mcl2pnml certify`` on the 10,000-call
  survey and ``mcl2pnml analyze --state-space`` on the dam inspection.
"""
from __future__ import annotations

import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from bench.core_scale import slope
from bench.missions import survey
from bench.real_models import ROOT, timed

RUNS = 3
SIZES = (100, 300, 1_000, 3_000, 10_000)


def _median(call) -> float:
    times = []
    for _ in range(RUNS):
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def certify_and_check(checked, net, abort_pending: bool = False) -> dict:
    from mcl2pnml.certify.certificate import certify
    from mcl2pnml.certify.recheck import check_certificate
    cert = json.loads(json.dumps(certify(checked, abort_pending=abort_pending)))
    assert check_certificate(net, cert) == [], "the certificate holds"
    return {"certify": _median(lambda: certify(checked, abort_pending=abort_pending)),
            "check": _median(lambda: check_certificate(net, cert)), "ends": cert["conclusion"]["ends"]}


def dam(log=lambda text: None) -> list[dict]:
    """The dam inspection, from B and with an abort pending: certify, check, explore."""
    from mcl2pnml.analysis.behaviour import behaviour
    from mcl2pnml.analysis.statespace.explore import explore
    from mcl2pnml import pipeline
    checked = pipeline.check_file(ROOT / "examples" / "dam_inspection.mcl")
    net = pipeline.compile_checked(checked)
    rows = []
    for pending in (False, True):
        start = net.with_initial({**net.initial, "mission.A": 1}) if pending else net
        log(f"  dam inspection{', abort pending' if pending else ''}")
        row = {"start": "mission.B" + (" and mission.A" if pending else ""),
               **certify_and_check(checked, start, pending)}
        t0 = time.perf_counter()
        space = explore(start, max_states=50_000_000)
        verdict = behaviour(space)
        # the ends exploring finds, as the certificate names them (mission.A, left marked
        # when the end is not ABORTED, aside)
        ends = {p for n in space.terminal for p in space.format(n)
                if p.startswith("mission.") and p not in ("mission.MTX", "mission.A")}
        row.update(explore=time.perf_counter() - t0, markings=space.states,
                   agrees=space.safe and verdict.reusable and verdict.final_always_reachable
                   and ends == set(row.pop("ends")))
        rows.append(row)
    return rows


def scale(sizes=SIZES, log=lambda text: None) -> list[dict]:
    from mcl2pnml import pipeline
    rows = []
    for n in sizes:
        log(f"  survey of {n:,} calls")
        checked = pipeline.check_source(survey(n), f"survey-{n}.mcl")
        net = pipeline.compile_checked(checked)
        rows.append({"calls": n, **certify_and_check(checked, net)})
    return rows


def commands(calls: int = 10_000) -> dict:
    """The whole commands, fresh processes: certify the survey, check its certificate file
    against its PNML; certify the dam; analyze the dam (explores)."""
    ours = str(Path(sys.executable).with_name("mcl2pnml"))
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        mission = Path(tmp) / f"survey-{calls}.mcl"
        mission.write_text(survey(calls))
        ran = timed([ours, "certify", str(mission)])
        out["certify survey"] = ran and {"seconds": ran[0], "peak_mb": ran[1], "ok": ran[3] == 0}
        # the certificate read back as a user's file: its size bound, its schema, the check
        pnml = Path(tmp) / f"survey-{calls}.pnml"
        timed([ours, "compile", str(mission), "-o", str(pnml)])
        ran = timed([ours, "certify", str(mission.with_name(f"survey-{calls}.cert.json")),
                     "--check", str(pnml)])
        out["check survey's certificate file against its PNML"] = ran and {
            "seconds": ran[0], "peak_mb": ran[1], "ok": ran[3] == 0}
        dam_mission = Path(tmp) / "dam_inspection.mcl"
        dam_mission.write_text((ROOT / "examples" / "dam_inspection.mcl").read_text())
        ran = timed([ours, "certify", str(dam_mission)])
        out["certify dam"] = ran and {"seconds": ran[0], "peak_mb": ran[1], "ok": ran[3] == 0}
        (Path(tmp) / "dam_inspection.cert.json").unlink()
        ran = timed([ours, "analyze", str(dam_mission), "--state-space", "--no-progress"])
        out["explore dam"] = ran and {"seconds": ran[0], "peak_mb": ran[1], "ok": ran[3] == 0}
    return out


def section(quick: bool = False, log=lambda text: None) -> tuple[list[str], list]:
    dams = dam(log)
    rows = scale(SIZES[:3] if quick else SIZES, log)
    cmds = commands(1_000 if quick else 10_000)
    lines = ["## Certificates: proven from the parts, against exploring", "",
             "`mcl2pnml certify` proves a mission 1-safe, always able to end and reusable "
             "from its parts (every template and the compiler's call-site joints proven once "
             "against the interface contract; docs/ARCHITECTURE.md, `mcl2pnml.certify`), "
             "without exploring; the checker re-checks the certificate against the compiled "
             "net alone. In this process, the median of "
             f"{RUNS} runs; exploring is our fastest explorer and the behaviour decided on "
             "its markings. \"agrees\": exploring finds what the certificate concludes, "
             "the same ends too.", "",
             "| mission | markings | certify (s) | check (s) | explore and decide (s) | agrees |",
             "|---|---:|---:|---:|---:|---|"]
    for r in dams:
        lines.append(f"| dam inspection, from {r['start']} | {r['markings']:,} | "
                     f"{r['certify']:.4f} | {r['check']:.4f} | {r['explore']:.2f} | "
                     f"{'yes' if r['agrees'] else '**no**'} |")
    lines += ["", "Surveys (`bench/missions.py`), certify and check:", "",
              "| calls | certify (s) | check (s) | together (s) |", "|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['calls']:,} | {r['certify']:.3f} | {r['check']:.3f} | "
                     f"{r['certify'] + r['check']:.3f} |")
    sizes = [r["calls"] for r in rows]
    exponent = slope(sizes, [r["certify"] + r["check"] for r in rows])
    lines += [f"| exponent | | | {exponent:.2f} |", "",
              "The whole commands, each a fresh process (start-up, compiling, output), "
              "seconds and peak memory:", ""]
    for what, m in cmds.items():
        lines.append(f"- {what}: " + (f"{m['seconds']:.2f} s, {m['peak_mb']:.0f} MB"
                                      if m else "did not finish"))
    aborted = dams[1]
    largest = rows[-1]
    targets = [
        ("certify: dam inspection with an abort pending, certified and checked under 0.1 s",
         aborted["certify"] + aborted["check"] < 0.1,
         f"{aborted['certify'] + aborted['check']:.3f} s (exploring: {aborted['explore']:.2f} s)"),
        (f"certify: a {largest['calls']:,}-call survey certified and checked under 2 s",
         largest["certify"] + largest["check"] < 2,
         f"{largest['certify'] + largest['check']:.2f} s"),
        ("certify: exponent at most 1.1", exponent <= 1.1, f"{exponent:.2f}"),
        ("certify: every certified dam agrees with exploring", all(r["agrees"] for r in dams),
         "from B and with an abort pending")]
    return lines, targets


if __name__ == "__main__":
    lines, targets = section("--quick" in sys.argv, lambda t: print(t, file=sys.stderr))
    print("\n".join(lines))
    for name, ok, what in targets:
        print(f"- {name}: {'holds' if ok else 'missed'} ({what})")
