"""Mission properties: our checker against verifypn and LoLA, on the same queries.

Run:  .venv/bin/python -m bench.properties_peers [--quick]

For each example mission and each of its property files (``NAME.props``,
which hold, and ``NAME.false.props``, which do not; ``--quick`` leaves out
dam_inspection, whose 197,331 markings take the peers minutes), measured in
the same run, each as a fresh process under GNU ``time`` (wall-clock seconds,
the whole process's peak resident memory):

* ours, the command a user runs: ``mcl2pnml analyze MISSION --state-space
  --properties FILE --json`` (start-up, compiling, exploring once, every
  property checked, each failing one's counterexample told in the mission's
  terms and replayed on both engines, the JSON printed); and, in this
  process, the inner loop alone: :func:`analysis.properties.check_all` on
  the compiled net and properties (exploring once and the product with each
  property's observer), the median of :data:`RUNS` when under 5 s;
* verifypn and LoLA on the queries ``compile --properties`` writes (every
  property in LTLCardinality; those with an exact CTL or reachability form
  also in those categories), each tool with its defaults (its structural
  reductions and stubborn sets, what a user gets) and with them off
  (verifypn ``-r 0 -p``, LoLA ``--netreduction=off --stubborn=off``).
  verifypn answers a category file in one call (``-x 1,2,...``, ``-ltl``
  for LTL), with its query simplification off (``-q 0``: with it, some of
  our bounded-existence queries run its linear programs to their 30 s
  time-out); LoLA answers one query per call, since given several this build
  idles a scheduling tick between them. A tool's time is the sum of its
  calls, its memory the largest peak.

Every answer is compared with ours; the table says where one differs (LoLA
with its net reduction answers some ``A <> P`` wrongly, tests/
test_properties_peers.py). A call that passes :data:`TIMEOUT` seconds, or
gives no answer, is reported as such.
"""
from __future__ import annotations

import json
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

from bench.real_models import ROOT, _tool, timed

EXAMPLES = ROOT / "examples"
TIMEOUT = 300.0
RUNS = 3
#: The examples whose state spaces take the peers minutes: left out by ``--quick``.
LARGE = {"dam_inspection"}
#: Each peer's configurations: (name, extra arguments).
CONFIGS = {"verifypn": (("defaults", ["-q", "0"]), ("no reductions", ["-q", "0", "-r", "0", "-p"])),
           "lola": (("defaults", []), ("no reductions", ["--netreduction=off", "--stubborn=off"]))}


def cases(quick: bool = False) -> list[tuple[str, Path, Path]]:
    """(label, mission, property file) of every example's property files."""
    out = []
    for mission in sorted(EXAMPLES.glob("*.mcl")):
        if quick and mission.stem in LARGE:
            continue
        for suffix in (".props", ".false.props"):
            out.append((f"{mission.stem}{suffix}", mission, EXAMPLES / f"{mission.stem}{suffix}"))
    return out


def ours(mission: Path, props: Path) -> dict | None:
    """Our whole command (median of a few runs when fast), and the inner loop in-process."""
    from analysis.properties import Status, check_all
    from mcl2pnml import pipeline
    command = [str(Path(sys.executable).with_name("mcl2pnml")), "analyze", str(mission),
               "--state-space", "--no-progress", "--properties", str(props), "--json"]
    runs = []
    for _ in range(RUNS):
        ran = timed(command, TIMEOUT)
        if ran is None:
            return None
        runs.append(ran)
        if ran[0] > 5:
            break
    seconds, peak, output, _ = sorted(runs)[len(runs) // 2]
    result = json.loads(output[:output.rindex("}") + 1])
    net, properties = pipeline.properties_of(mission, extra=props)
    inner = []
    for _ in range(RUNS):
        t0 = time.perf_counter()
        verdicts = check_all(net, properties)
        inner.append(time.perf_counter() - t0)
        if inner[-1] > 5:
            break
    return {"seconds": seconds, "peak_mb": peak, "inner_seconds": statistics.median(inner),
            "markings": result.get("states"),
            "verdicts": {v.property.name: v.status is Status.HOLDS for v in verdicts}}


def _answers(pattern: str, text: str) -> dict[str, bool]:
    return {m.group(1): m.group(2).lower() == "true" for m in re.finditer(pattern, text, re.M)}


def peer(tool: str, extra: list[str], pnml: Path, files: dict[str, Path],
         scratch: Path) -> dict | None:
    """One peer in one configuration on every category file: summed seconds, the largest
    peak, and its answers; None if it is not installed."""
    path = _tool("verifypn-linux64" if tool == "verifypn" else "lola")
    if path is None:
        return None
    from lxml import etree
    seconds, peak, answers, failed = 0.0, 0.0, {}, []
    for category, queries in files.items():
        ids = [p.findtext("{*}id") for p in etree.parse(str(queries)).getroot()]
        if tool == "verifypn":
            calls = [([path, *(["-ltl"] if category.startswith("LTL") else []), *extra,
                       "-x", ",".join(str(k) for k in range(1, len(ids) + 1)), str(pnml),
                       str(queries)], ids)]
        else:
            calls = []
            root = etree.parse(str(queries)).getroot()
            for k, prop in enumerate(list(root)):
                single = etree.Element(root.tag, nsmap=root.nsmap)
                single.append(prop)
                one = scratch / f"{queries.stem}.{k}.xml"
                one.write_bytes(etree.tostring(single, xml_declaration=True, encoding="utf-8"))
                calls.append(([path, "--pnmlnet", str(pnml), "--xmlformula",
                               f"--formula={one}", *extra], [ids[k]]))
        for command, asked in calls:
            ran = timed(command, TIMEOUT)
            if ran is None:
                failed += [f"{category} {q}: timed out" for q in asked]
                continue
            seconds += ran[0]
            peak = max(peak, ran[1])
            got = (_answers(r"^FORMULA (\S+) (TRUE|FALSE)", ran[2]) if tool == "verifypn" else
                   _answers(r"^\s*(\S+):.*?\s(true|false)\s", ran[2].partition("FINAL RESULTS")[2]))
            for q in asked:
                if q in got:
                    answers[category, q] = got[q]
                else:
                    failed.append(f"{category} {q}: no answer")
    return {"seconds": seconds, "peak_mb": peak, "answers": answers, "failed": failed}


def run(quick: bool = False, log=lambda text: None) -> list[dict]:
    """One row per (example, property file): ours, and each peer in each configuration."""
    from mcl2pnml import pipeline
    from mcl2pnml.io.mccquery import property_queries, to_xml
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, mission, props in cases(quick):
            log(f"  {label}")
            folder = Path(tmp) / label
            folder.mkdir()
            net, properties = pipeline.properties_of(mission, extra=props)
            pnml = pipeline.save_pnml(net, folder / "net.pnml", "none")
            files = {}
            for category, queries in property_queries(properties).items():
                files[category] = folder / f"net.{category}.xml"
                files[category].write_text(to_xml(queries))
            row = {"case": label, "properties": len(properties), "ours": ours(mission, props)}
            for tool, configs in CONFIGS.items():
                for name, extra in configs:
                    row[tool, name] = peer(tool, extra, pnml, files, folder)
            rows.append(row)
    return rows


def differs(row: dict, result: dict | None) -> str:
    """What a peer answered otherwise than we did, or that it agreed."""
    if result is None:
        return "-"
    verdicts = row["ours"]["verdicts"] if row["ours"] else {}
    wrong = [f"{q} ({c[:3]})" for (c, q), a in sorted(result["answers"].items())
             if verdicts.get(q) is not None and a != verdicts[q]]
    return "; ".join(wrong + result["failed"]) or "agree"


def table(rows: list[dict]) -> list[str]:
    """The Markdown table of RESULTS.md: seconds (peak MB) of each, then the ratios."""
    head = ["case", "properties", "markings", "ours: command", "ours: inner loop"]
    for tool in CONFIGS:
        head += [f"{tool}: {name}" for name, _ in CONFIGS[tool]]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    disagreements = []
    for r in rows:
        o = r["ours"]
        cells = [r["case"], str(r["properties"]),
                 f"{o['markings']:,}" if o and o["markings"] else "-",
                 f"{o['seconds']:.2f} s ({o['peak_mb']:.0f} MB)" if o else "-",
                 f"{o['inner_seconds']:.3f} s" if o else "-"]
        for tool, configs in CONFIGS.items():
            for name, _ in configs:
                m = r[tool, name]
                if m is None:
                    cells.append("not installed")
                    continue
                ratio = f", {m['seconds'] / o['seconds']:.1f}x ours" if o else ""
                cells.append(f"{m['seconds']:.2f} s ({m['peak_mb']:.0f} MB{ratio})")
                said = differs(r, m)
                if said != "agree":
                    disagreements.append(f"- {r['case']}, {tool} ({name}): {said}")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Answers that differ from ours, or are missing: "
              + ("none." if not disagreements else "")] + disagreements
    return lines


if __name__ == "__main__":
    print("\n".join(table(run("--quick" in sys.argv, log=lambda t: print(t, file=sys.stderr)))))
