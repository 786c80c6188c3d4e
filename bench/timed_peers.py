"""Timed verdicts: our checker against TAPAAL's verifydtapn, the whole command each.

Run:  .venv/bin/python -m bench.timed_peers [--timeout SECONDS] [NAME ...]

(prints the section of ``bench/RESULTS.md``; NAME: only those examples.)

For each example mission (``examples/*.mcl``), measured one process after
another (no two at once), each a fresh process under GNU ``time`` (wall-clock
seconds, the whole process's peak resident memory in MiB), one run each:

* ours, the command a user runs: ``mcl2pnml analyze MISSION --timed`` (start-up,
  compiling, the zone graph, whether every run ends and the earliest and latest
  end times), in our default semantics
  (the supervisor's steps first at their instant) and with ``--urgency-only``
  (the supervisor's steps urgent only: verifydtapn's semantics, the one its
  verdict is compared with);
* verifydtapn on the timed-arc net ``mcl2pnml compile MISSION --format tapn``
  writes (not timed: it is the file the user hands over) with the query "every
  run ends" (``MISSION.ends.q``) and the ``-k`` bound ``compile``
  prints beside it.

Both under the same vehicle assumptions, the defaults of both commands:
acknowledgements at once, a primitive's reports at least 1 s apart. A call
past ``--timeout`` seconds (default :data:`TIMEOUT`) gives no answer: the cell
says so and no ratio is taken. verifydtapn's address space is not limited here
(a call that runs out of memory gives no answer either). "verdicts" compares
verifydtapn's answer with ours under ``--urgency-only``.
"""
from __future__ import annotations

import datetime
import re
import sys
import tempfile
from pathlib import Path

from bench.real_models import ROOT, _tool, timed
from mcl2pnml.core.vocabulary import ENDS

EXAMPLES = ROOT / "examples"
#: Seconds a call may take, ours or verifydtapn's.
TIMEOUT = 300.0
OURS = str(Path(sys.executable).with_name("mcl2pnml"))


def _ours_answer(output: str) -> tuple[bool | None, str]:
    """(always ends, the end times as printed) from ``analyze --timed``'s lines."""
    found = re.search(re.escape(ENDS) + r": (yes|no|unknown)", output)
    ends = None if found is None or found.group(1) == "unknown" else found.group(1) == "yes"
    times = re.search(r"end time: (.*)", output)
    return ends, times.group(1).strip() if times else "-"


def ours(mission: Path, urgency_only: bool, timeout: float) -> dict:
    command = [OURS, "analyze", str(mission), "--no-progress", "--timed",
               *(["--urgency-only"] if urgency_only else [])]
    ran = timed(command, timeout)
    if ran is None:
        return {"seconds": None}
    seconds, peak, output, status = ran
    ends, times = _ours_answer(output)
    return {"seconds": seconds, "peak_mb": peak, "ends": ends, "times": times,
            "status": status}


def verifydtapn(mission: Path, folder: Path, timeout: float) -> dict | None:
    """verifydtapn on the mission's timed-arc net and its "always ends" query; None if
    verifydtapn is absent."""
    binary = _tool("verifydtapn")
    if binary is None:
        return None
    net = folder / f"{mission.stem}.tapn"
    wrote = timed([OURS, "compile", str(mission), "--format", "tapn", "-o", str(net)], 120)
    query = folder / f"{mission.stem}.ends.q"
    bound = re.search(rf"verifydtapn -k (\d+) \S+ {re.escape(str(query))}", wrote[2] if wrote
                      else "")
    if bound is None:
        return {"seconds": None, "error": "compile --format tapn failed"}
    ran = timed([binary, "-k", bound.group(1), str(net), str(query)], timeout)
    if ran is None:
        return {"seconds": None}
    seconds, peak, output, _ = ran
    verdict = re.search(r"^Query is (NOT )?satisfied\.", output, re.M)
    tokens = re.search(r"^Max number of tokens found in any reachable marking: *(\S+)",
                       output, re.M)
    markings = re.search(r"discovered markings:\s*(\d+)", output)
    ends = None
    if verdict is not None and tokens is not None and not tokens.group(1).startswith(">"):
        ends = verdict.group(1) is None
    return {"seconds": seconds, "peak_mb": peak, "ends": ends, "k": int(bound.group(1)),
            "markings": int(markings.group(1)) if markings else None}


def run(names: list[str], timeout: float, log=lambda text: None) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for mission in sorted(EXAMPLES.glob("*.mcl")):
            if names and mission.stem not in names:
                continue
            folder = Path(tmp) / mission.stem
            folder.mkdir()
            row = {"mission": mission.stem,
                   "ours": ours(mission, False, timeout),
                   "urgency": ours(mission, True, timeout),
                   "verifydtapn": verifydtapn(mission, folder, timeout)}
            rows.append(row)
            log(f"  {mission.stem}: " + ", ".join(
                f"{k} {_cell(v, timeout)}" for k, v in row.items() if k != "mission"))
    return rows


def _word(ends: bool | None) -> str:
    return "unknown" if ends is None else "yes" if ends else "no"


def _cell(result: dict | None, timeout: float) -> str:
    if result is None:
        return "absent"
    if result["seconds"] is None:
        return result.get("error") or f"no answer in {timeout:.0f} s"
    return f"{result['seconds']:.2f} s, {result['peak_mb']:.0f} MiB, {_word(result['ends'])}"


def _ratio(a: dict | None, b: dict | None) -> str:
    if not a or not b or a["seconds"] is None or b["seconds"] is None:
        return "-"
    return f"{a['seconds'] / b['seconds']:.2f}x"


def _agree(urgency: dict, peer: dict | None) -> str:
    if peer is None:
        return "-"
    if urgency["seconds"] is None or peer["seconds"] is None:
        return "not compared (no answer)"
    if urgency["ends"] is None or peer["ends"] is None:
        return "not compared (unknown)"
    return "agree" if urgency["ends"] == peer["ends"] else "DIFFER"


def table(rows: list[dict], timeout: float) -> list[str]:
    lines = ["| mission | ours (s, MiB, ends) | ours --urgency-only (s, MiB, ends) | end times "
             "(--urgency-only) | verifydtapn (s, MiB, ends) | markings (verifydtapn) | "
             "ours / verifydtapn | --urgency-only / verifydtapn | verdicts |",
             "|---|---|---|---|---|---:|---:|---:|---|"]
    for r in rows:
        peer = r["verifydtapn"]
        markings = f"{peer['markings']:,}" if peer and peer.get("markings") else "-"
        lines.append(f"| {r['mission']} | {_cell(r['ours'], timeout)} | "
                     f"{_cell(r['urgency'], timeout)} | {r['urgency'].get('times', '-')} | "
                     f"{_cell(peer, timeout)} | {markings} | {_ratio(r['ours'], peer)} | "
                     f"{_ratio(r['urgency'], peer)} | {_agree(r['urgency'], peer)} |")
    return lines


def section(names: list[str] = (), timeout: float = TIMEOUT, log=lambda text: None
            ) -> list[str]:
    rows = run(list(names), timeout, log)
    return ["## Timed verdicts: ours, verifydtapn", "",
            f"Measured {datetime.date.today().isoformat()}, one process at a time, one run "
            "each (`python -m bench.timed_peers`). Ours: `mcl2pnml analyze MISSION --timed`, "
            f"the command a user runs (start-up, compiling, the zone graph, then \"{ENDS}\" "
            "and the end times), in our semantics "
            "(the supervisor's steps first at their instant) and with `--urgency-only` "
            "(verifydtapn's: urgent only). verifydtapn: `verifydtapn -k K MISSION.tapn "
            "MISSION.ends.q` on what `mcl2pnml compile MISSION --format tapn` writes, K the "
            "bound it prints. Acknowledgements at once, reports at least 1 s apart (both "
            "commands' defaults). Seconds and the whole process's peak resident memory "
            f"(GNU time); a call past {timeout:.0f} s gives no answer. \"verdicts\": "
            "verifydtapn's \"always ends\" against ours under `--urgency-only`.", "",
            *table(rows, timeout)]


if __name__ == "__main__":
    args = sys.argv[1:]
    limit = TIMEOUT
    if "--timeout" in args:
        k = args.index("--timeout")
        limit = float(args[k + 1])
        del args[k:k + 2]
    print("\n".join(section(args, limit, log=lambda t: print(t, file=sys.stderr,
                                                                flush=True))))
