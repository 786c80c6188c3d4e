"""Mission properties: our checker against verifypn and LoLA, on the same queries.

Run:  .venv/bin/python -m bench.properties_peers [--quick]

(prints the section of ``bench/RESULTS.md`` that ``make bench`` writes, the
same lines: :func:`section`.)

For each example mission and each of its property files (``NAME.props``,
which hold, and ``NAME.false.props``, which do not; ``--quick`` leaves out
dam_inspection, whose 197,331 markings take the peers seconds a query),
measured in the same run, one process after another (no two at once, for
clean timings), each as a fresh process under GNU ``time`` (wall-clock
seconds, the whole process's peak resident memory in MiB):

* ours, the command a user runs: ``mcl2pnml analyze MISSION --untimed
  --state-space --properties FILE --json`` (start-up, compiling, the state
  space's facts, every property checked on the fly, the JSON printed;
  ``--untimed``: the runs of the net, the semantics the peers check), the
  median of :data:`RUNS` when a run takes under 5 s; and, in this process,
  the inner loop alone: :func:`mcl2pnml.analysis.checking.on_graph.check_properties` on the
  compiled net and properties (:func:`mcl2pnml.pipeline.properties_of`, not
  timed), on the fly (the default) and with the reference method (every
  marking first, then each product: ``method="full"``), each the median of
  :data:`RUNS` when under 5 s;
* verifypn and LoLA on the queries ``compile --properties`` writes
  (:func:`mcl2pnml.io.mccquery.property_queries`: every property in
  LTLCardinality; those with an exact CTL or reachability form also in those
  categories) beside the PNML file ours compiles, each tool with its defaults
  (its structural reductions and stubborn sets, what a user gets) and with
  them off (verifypn ``-r 0 -p``; LoLA ``--netreduction=off
  --stubborn=off``, the flags of this build's ``--help``; its LTL stubborn
  sets, ``--ltlstubborn``, are off by default). verifypn answers a category
  file in one call (``-x 1,2,...``, ``-ltl`` for LTL), with its query
  simplification off either way (``-q 0``: with it, some of our
  bounded-existence queries run its linear programs to their 30 s time-out);
  LoLA answers one query per call, since given several this build idles a
  scheduling tick between them. A tool's time is the sum of its calls on a
  file, its memory the largest peak; one run each.

Every answer is compared with our verdict (query id = property name); the
"verdicts" column says "agree" or which answers differ or are missing. A
disagreement is reported, not fatal: this LoLA build has a known fault (an
until of equal sides, ``a U a``, answered wrongly;
tests/peers/test_properties_peers.py). A call that passes :data:`TIMEOUT` seconds
counts as timed out: the cell says so and its time is not summed. A peer not
found (``../shared/peers/bin`` or PATH) is reported absent.
"""
from __future__ import annotations

import datetime
import json
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

from bench.real_models import ROOT, _tool, timed

EXAMPLES = ROOT / "examples"
#: Seconds a call may take, ours or a peer's.
TIMEOUT = 120.0
RUNS = 3
#: The examples whose state spaces take the peers seconds a query: left out by ``--quick``.
LARGE = {"dam_inspection"}
#: Each peer's configurations: (name, extra arguments).
CONFIGS = {"verifypn": (("defaults", ["-q", "0"]), ("no reductions", ["-q", "0", "-r", "0", "-p"])),
           "lola": (("defaults", []), ("no reductions", ["--netreduction=off", "--stubborn=off"]))}
BINARIES = {"verifypn": "verifypn-linux64", "lola": "lola"}
NAMES = {"verifypn": "verifypn", "lola": "LoLA"}


def cases(quick: bool = False) -> list[tuple[str, Path, Path]]:
    """(label, mission, property file) of every example's property files."""
    out = []
    for mission in sorted(EXAMPLES.glob("*.mcl")):
        if quick and mission.stem in LARGE:
            continue
        for suffix in (".props", ".false.props"):
            out.append((f"{mission.stem}{suffix}", mission, EXAMPLES / f"{mission.stem}{suffix}"))
    return out


def _median_of_runs(once, seconds=lambda r: r) -> list:
    """Up to :data:`RUNS` results of ``once()``, fewer when one takes over 5 s; stops at
    a None (a failure or a time-out), which it returns last."""
    results = []
    for _ in range(RUNS):
        results.append(once())
        if results[-1] is None or seconds(results[-1]) > 5:
            break
    return results


def ours(mission: Path, props: Path) -> dict | None:
    """Our whole command (median of a few runs when fast), and the inner loop in-process;
    None if the command failed or timed out."""
    from mcl2pnml.analysis.checking.on_graph import Status, check_properties
    from mcl2pnml import pipeline
    command = [str(Path(sys.executable).with_name("mcl2pnml")), "analyze", str(mission),
               "--untimed", "--state-space", "--no-progress", "--properties", str(props),
               "--json"]
    runs = _median_of_runs(lambda: timed(command, TIMEOUT), seconds=lambda r: r[0])
    if runs[-1] is None or "}" not in runs[-1][2]:
        return None
    seconds, peak, output, _ = sorted(runs)[len(runs) // 2]
    result = json.loads(output[:output.rindex("}") + 1])
    net, properties = pipeline.properties_of(mission, extra=props)
    inner, full, verdicts = [], [], []

    def once(method: str, into: list) -> float:
        t0 = time.perf_counter()
        verdicts[:] = check_properties(net, properties, method=method)
        into.append(time.perf_counter() - t0)
        return into[-1]
    _median_of_runs(lambda: once("full", full))
    _median_of_runs(lambda: once("auto", inner))
    return {"seconds": seconds, "peak_mb": peak, "inner_seconds": statistics.median(inner),
            "full_seconds": statistics.median(full),
            "markings": result.get("states"),
            "verdicts": {v.property.name: None if v.status is Status.UNKNOWN
                         else v.status is Status.HOLDS for v in verdicts}}


def _answers(pattern: str, text: str) -> dict[str, bool]:
    return {m.group(1): m.group(2).lower() == "true" for m in re.finditer(pattern, text, re.M)}


def _calls(tool: str, path: str, extra: list[str], pnml: Path, category: str,
           queries: Path, scratch: Path) -> list[tuple[list[str], list[str]]]:
    """(command, the query ids it answers) of each call that answers one category file:
    verifypn all at once, LoLA one query a call (each written to its own file)."""
    from lxml import etree
    root = etree.parse(str(queries)).getroot()
    ids = [p.findtext("{*}id") for p in root]
    if tool == "verifypn":
        return [([path, *(["-ltl"] if category.startswith("LTL") else []), *extra,
                  "-x", ",".join(str(k) for k in range(1, len(ids) + 1)), str(pnml),
                  str(queries)], ids)]
    calls = []
    for k, prop in enumerate(list(root)):
        single = etree.Element(root.tag, nsmap=root.nsmap)
        single.append(prop)
        one = scratch / f"{queries.stem}.{k}.xml"
        one.write_bytes(etree.tostring(single, xml_declaration=True, encoding="utf-8"))
        calls.append(([path, "--pnmlnet", str(pnml), "--xmlformula", f"--formula={one}",
                       *extra], [ids[k]]))
    return calls


def peer(tool: str, extra: list[str], pnml: Path, files: dict[str, Path],
         scratch: Path) -> dict | None:
    """One peer in one configuration on every category file: summed seconds of the calls
    that finished, the largest peak, its answers, what timed out or went unanswered;
    None if the peer is absent."""
    path = _tool(BINARIES[tool])
    if path is None:
        return None
    seconds, peak, answers, failed, timeouts, calls = 0.0, 0.0, {}, [], 0, 0
    for category, queries in files.items():
        for command, asked in _calls(tool, path, extra, pnml, category, queries, scratch):
            calls += 1
            ran = timed(command, TIMEOUT)
            if ran is None:
                timeouts += 1
                failed += [f"{q} ({category[:3]}) timed out" for q in asked]
                continue
            seconds += ran[0]
            peak = max(peak, ran[1])
            got = (_answers(r"^FORMULA (\S+) (TRUE|FALSE)", ran[2]) if tool == "verifypn" else
                   _answers(r"^\s*(\S+):.*?\s(true|false)\s", ran[2].partition("FINAL RESULTS")[2]))
            for q in asked:
                if q in got:
                    answers[category, q] = got[q]
                else:
                    failed.append(f"{q} ({category[:3]}) no answer")
    return {"seconds": seconds, "peak_mb": peak, "answers": answers, "failed": failed,
            "calls": calls, "timeouts": timeouts}


def run(quick: bool = False, log=lambda text: None) -> list[dict]:
    """One row per (example, property file): ours, and each peer in each configuration."""
    from mcl2pnml import pipeline
    from mcl2pnml.io.mccquery import property_queries, to_queries
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, mission, props in cases(quick):
            folder = Path(tmp) / label
            folder.mkdir()
            net, properties = pipeline.properties_of(mission, extra=props)
            pnml = pipeline.save_pnml(net, folder / "net.pnml", "none")
            files = {}
            for category, queries in property_queries(properties).items():
                files[category] = folder / f"net.{category}.xml"
                files[category].write_text(to_queries(queries))
            row = {"case": label, "properties": len(properties), "ours": ours(mission, props)}
            for tool, configs in CONFIGS.items():
                for name, extra in configs:
                    row[tool, name] = peer(tool, extra, pnml, files, folder)
            rows.append(row)
            log(f"  {label}: " + ", ".join(
                f"{k if isinstance(k, str) else ' '.join(k)} "
                + (f"{v['seconds']:.2f}s" if v else "-")
                for k, v in row.items() if k not in ("case", "properties")))
    return rows


def differs(row: dict, result: dict | None) -> str:
    """What a peer answered otherwise than we did (or did not answer), or "agree"; "-" for
    an absent peer."""
    if result is None:
        return "-"
    verdicts = row["ours"]["verdicts"] if row["ours"] else {}
    wrong = [f"{q} ({c[:3]}) {'true' if a else 'false'}" for (c, q), a
             in sorted(result["answers"].items())
             if verdicts.get(q) is not None and a != verdicts[q]]
    return "; ".join(wrong + result["failed"]) or "agree"


def _seconds(m: dict | None) -> str:
    if m is None:
        return "absent"
    cell = f"{m['seconds']:.2f} s, {m['peak_mb']:.0f} MiB"
    return cell + (f", {m['timeouts']} of {m['calls']} calls timed out" if m["timeouts"] else "")


def _ratio(m: dict | None, o: dict | None) -> str:
    if m is None or o is None:
        return "-"
    return (">" if m["timeouts"] else "") + f"{m['seconds'] / o['seconds']:.2f}x"


def table(rows: list[dict]) -> list[str]:
    """The Markdown table of RESULTS.md, then the summed times and their ratios, then the
    answers that differ from ours (the last line; "none." when every answer agrees)."""
    configs = [(tool, name) for tool in CONFIGS for name, _ in CONFIGS[tool]]
    label = {c: f"{NAMES[c[0]]}{'' if c[1] == 'defaults' else ', ' + c[1]}" for c in configs}
    head = (["case", "properties", "markings", "ours (s)", "ours (MiB)", "inner loop (s)",
             "inner loop, every marking first (s)"]
            + [f"{label[c]} (s, MiB)" for c in configs] + [f"{label[c]} / ours" for c in configs]
            + ["verdicts"])
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 2) + "---|"]
    disagreements = []
    for r in rows:
        o = r["ours"]
        said = {c: differs(r, r[c]) for c in configs}
        other = [f"{label[c]}: {said[c]}" for c in configs if said[c] not in ("agree", "-")]
        disagreements += [f"- {r['case']}, {text}" for text in other]
        cells = [r["case"], str(r["properties"]),
                 f"{o['markings']:,}" if o and o["markings"] else "-",
                 f"{o['seconds']:.2f}" if o else "failed",
                 f"{o['peak_mb']:.0f}" if o else "-",
                 f"{o['inner_seconds']:.3f}" if o else "-",
                 f"{o['full_seconds']:.3f}" if o else "-",
                 *[_seconds(r[c]) for c in configs], *[_ratio(r[c], o) for c in configs],
                 "; ".join(other) if other else "agree" if o else "-"]
        lines.append("| " + " | ".join(cells) + " |")
    measured = [r for r in rows if r["ours"]]
    if measured:
        total = sum(r["ours"]["seconds"] for r in measured)
        inner = sum(r["ours"]["inner_seconds"] for r in measured)
        sums = []
        for c in configs:
            got = [r[c] for r in measured if r[c]]
            if len(got) == len(measured):
                late = sum(m["timeouts"] for m in got)
                spent = sum(m["seconds"] for m in got)
                sums.append(f"{label[c]} {spent:.2f} s ({spent / total:.2f}x ours"
                            + (f"; {late} calls timed out, not counted" if late else "") + ")")
        lines += ["", f"Summed over the {len(measured)} files: ours {total:.2f} s "
                  f"(the inner loop {inner:.2f} s of it), " + ", ".join(sums) + "."]
        small = [r for r in measured if r["case"].split(".")[0] not in LARGE]
        if small and len(small) < len(measured):
            base = sum(r["ours"]["seconds"] for r in small)
            parts = [f"{label[c]} {sum(r[c]['seconds'] for r in small) / base:.2f}x"
                     for c in configs if all(r[c] for r in small)]
            lines.append(f"Without {', '.join(sorted(LARGE))}: ours {base:.2f} s; "
                         + ", ".join(parts) + " ours.")
    lines += ["", "Answers that differ from ours, or are missing: "
              + ("none." if not disagreements else "")] + disagreements
    return lines


def section(quick: bool = False, log=lambda text: None
            ) -> tuple[list[str], list[tuple[str, bool, str]]]:
    """The section of ``bench/RESULTS.md`` and its target: verifypn answers as we do."""
    rows = run(quick, log=log)
    lines = ["## Mission properties: ours, verifypn, LoLA", "",
             f"Measured {datetime.date.today().isoformat()}, one process at a time. Each "
             "example's property files (`NAME.props`, which hold; `NAME.false.props`, "
             "which fail" + (f"; {', '.join(sorted(LARGE))} left out by --quick" if quick
                             else "") + "). Ours: "
             "`mcl2pnml analyze MISSION --untimed --state-space --properties FILE --json`, "
             "the command a user runs (start-up, compiling, the state space's facts, every "
             "property checked on the fly), a fresh process, the median of 3 runs when under "
             "5 s; the inner loop (`check_properties`: each property's product with its observer "
             "searched on the fly in C, stopping at a counterexample; compiling excluded) "
             "timed apart, in-process, and beside it the reference method (every marking "
             "first, then each product in Python). The peers: the "
             "queries `compile --properties` writes (every property in LTL, those with an "
             "exact CTL or reachability form also there), verifypn in one call per category "
             "file, LoLA in one call per query, each call a fresh process, each tool with "
             "its defaults (structural reductions, stubborn sets) and with them off "
             "(`-r 0 -p`; `--netreduction=off --stubborn=off`); verifypn with `-q 0` either "
             "way (its query simplification can run 30 s on our bounded-existence queries). "
             "A peer's seconds are summed over its calls on the file, its memory the largest "
             "peak; \"/ ours\": its seconds over our whole command's (above 1: ours is "
             f"faster). A call past {TIMEOUT:.0f} s counts as timed out. \"verdicts\": every "
             "answer compared with our verdict, per property. Ours and the peers search on "
             "the fly and stop at a counterexample.", "", *table(rows)]
    agrees = all(differs(r, r["verifypn", name]) in ("agree", "-")
                 for r in rows for name, _ in CONFIGS["verifypn"])
    targets = [("mission properties: verifypn answers every query as we do", agrees,
                "every example's property files" if agrees else "see the section")]
    return lines, targets + _targets(rows)


def _targets(rows: list[dict]) -> list[tuple[str, bool, str]]:
    """The targets of the whole command against verifypn with its defaults, on the
    largest example (whose state space the peers take seconds on): failing files within
    2x its time, holding ones at least as fast, peak memory within 2x."""
    out = []
    for r in rows:
        o, v = r["ours"], r["verifypn", "defaults"]
        if r["case"].split(".")[0] not in LARGE or not o or not v:
            continue
        fails = r["case"].endswith(".false.props")
        bound = 2.0 if fails else 1.0
        out.append((f"properties: {r['case']} within {bound:g}x verifypn's time",
                    o["seconds"] <= bound * v["seconds"],
                    f"{o['seconds']:.2f} s against {v['seconds']:.2f} s "
                    f"({o['seconds'] / v['seconds']:.2f}x)"))
        out.append((f"properties: {r['case']} peak memory within 2x verifypn's",
                    o["peak_mb"] <= 2 * v["peak_mb"],
                    f"{o['peak_mb']:.0f} MiB against {v['peak_mb']:.0f} MiB"))
    return out


if __name__ == "__main__":
    lines, _ = section("--quick" in sys.argv, log=lambda t: print(t, file=sys.stderr, flush=True))
    print("\n".join(lines))
