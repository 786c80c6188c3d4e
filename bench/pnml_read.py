"""Reading PNML: ours against LoLA and verifypn reading the same files, side by side.

Run:  .venv/bin/python -m bench.pnml_read [--quick]   (prints the section of bench/RESULTS.md)

Each command is the whole process a user runs, under GNU ``time``: wall seconds and
the process's peak memory, the three tools one after the other on each file, in the
same run (:func:`bench.real_models.timed`):

* the 10,000-call survey's PNML (:func:`bench.missions.survey`, 201 MB with every
  arc's inscription, a million arcs) with its certificate: ours ``mcl2pnml certify
  CERT --check NET.pnml`` (the strict reading, then the certificate checked: the
  proof a user re-checks), LoLA ``lola --pnmlnet NET.pnml --check=none`` (it reads
  and builds its net, then stops), verifypn ``verifypn-linux64 -r 0 --noverify
  NET.pnml -x 1 Q.xml`` (it reads the net and the query, then stops);
* the larger contest models of ``../shared/external-nets/bench-models``: ours
  ``mcl2pnml validate`` (our schema, the official grammar where it is found, and the
  strict reading), and the peers as above.

Targets: on the survey, ours within 1.5 times LoLA's time and within LoLA's peak
memory; on the contest models, which every tool reads in well under a second,
ours under a second.
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from bench.missions import survey
from bench.real_models import ROOT, timed

PEERS = ROOT.parent / "shared" / "peers" / "bin"
MODELS = ROOT.parent / "shared" / "external-nets" / "bench-models"
TOOLS = ("ours", "LoLA", "verifypn")
_QUERY = ('<?xml version="1.0"?><property-set xmlns="http://mcc.lip6.fr/"><property>'
          '<id>d</id><description>d</description><formula><exists-path><finally><deadlock/>'
          '</finally></exists-path></formula></property></property-set>\n')
#: Each command's limit: a tool past it is said to have given no answer.
TIMEOUT = 300.0


def _peers(net: Path, scratch: Path) -> dict[str, list[str] | None]:
    query = scratch / "deadlock.xml"
    query.write_text(_QUERY)
    lola, verifypn = PEERS / "lola", PEERS / "verifypn-linux64"
    return {"LoLA": [str(lola), "--pnmlnet", str(net), "--check=none"]
            if lola.is_file() else None,
            "verifypn": [str(verifypn), "-r", "0", "--noverify", str(net), "-x", "1", str(query)]
            if verifypn.is_file() else None}


def _row(name: str, commands: dict[str, list[str] | None], log) -> dict:
    row = {"file": name}
    for tool in TOOLS:
        command = commands.get(tool)
        log(f"  {name}: {tool}")
        ran = timed(command, TIMEOUT) if command else None
        # verifypn exits 255 after reading, for want of a verification: the read counts
        row[tool] = ran and {"seconds": ran[0], "peak_mb": ran[1],
                             "ok": ran[3] == 0 or tool == "verifypn"}
    return row


def measure(quick: bool = False, log=lambda text: None) -> list[dict]:
    ours = str(Path(sys.executable).with_name("mcl2pnml"))
    rows = []
    with tempfile.TemporaryDirectory(prefix="pnml-read-") as tmp:
        scratch = Path(tmp)
        calls = 1_000 if quick else 10_000
        mission = scratch / f"survey-{calls}.mcl"
        mission.write_text(survey(calls))
        net, cert = mission.with_suffix(".pnml"), mission.with_name(f"survey-{calls}.cert.json")
        log(f"  compiling and certifying the survey of {calls:,} calls")
        timed([ours, "compile", str(mission), "-o", str(net), "--layout", "none"], TIMEOUT)
        timed([ours, "certify", str(mission)], TIMEOUT)
        size = net.stat().st_size / 2 ** 20 if net.is_file() else 0
        rows.append(_row(f"survey of {calls:,} calls ({size:.0f} MB)",
                         {"ours": [ours, "certify", str(cert), "--check", str(net)],
                          **_peers(net, scratch)}, log))
        models = sorted(MODELS.glob("*.pnml"), key=lambda p: -p.stat().st_size) \
            if MODELS.is_dir() else []
        for model in models[:2 if quick else None]:
            rows.append(_row(model.stem, {"ours": [ours, "validate", str(model)],
                                          **_peers(model, scratch)}, log))
    return rows


def section(rows: list[dict]) -> tuple[list[str], list[tuple[str, bool, str]]]:
    lines = ["## Reading PNML: ours against LoLA and verifypn", "",
             "The whole command, a fresh process each, the three tools one after the other "
             "in this run: ours `certify CERT --check` on the survey (the strict reading, "
             "then the certificate checked), `validate` on the contest models; LoLA "
             "`--check=none`; verifypn `-r 0 --noverify` (`bench/pnml_read.py`).", "",
             "| file | ours (s) | ours (MB) | LoLA (s) | LoLA (MB) | verifypn (s) "
             "| verifypn (MB) | ours / LoLA (time) | ours / LoLA (memory) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]

    def cell(r, key, fmt):
        return format(r[key], fmt) if r else "—"
    for row in rows:
        ours, lola = row["ours"], row["LoLA"]
        ratio = (f"{ours['seconds'] / lola['seconds']:.2f}", f"{ours['peak_mb'] / lola['peak_mb']:.2f}") \
            if ours and lola else ("—", "—")
        lines.append(f"| {row['file']} | {cell(ours, 'seconds', '.2f')} | "
                     f"{cell(ours, 'peak_mb', '.0f')} | {cell(lola, 'seconds', '.2f')} | "
                     f"{cell(lola, 'peak_mb', '.0f')} | {cell(row['verifypn'], 'seconds', '.2f')} | "
                     f"{cell(row['verifypn'], 'peak_mb', '.0f')} | {ratio[0]} | {ratio[1]} |")
    targets = []
    first = rows[0] if rows else None
    if first and first["ours"] and first["LoLA"]:
        ours, lola = first["ours"], first["LoLA"]
        targets.append((f"{first['file']}: certify --check within 1.5x LoLA's read",
                        ours["ok"] and ours["seconds"] <= 1.5 * lola["seconds"],
                        f"{ours['seconds']:.1f} s against {lola['seconds']:.1f} s"))
        targets.append((f"{first['file']}: peak memory within LoLA's",
                        ours["peak_mb"] <= lola["peak_mb"],
                        f"{ours['peak_mb']:.0f} MB against {lola['peak_mb']:.0f} MB"))
    for row in rows[1:]:
        if row["ours"]:
            targets.append((f"{row['file']}: read under a second", row["ours"]["ok"]
                            and row["ours"]["seconds"] < 1.0, f"{row['ours']['seconds']:.2f} s"))
    lines += ["", "| target | holds | measured |", "|---|---|---|"]
    lines += [f"| {name} | {'yes' if ok else '**no**'} | {said} |" for name, ok, said in targets]
    return lines, targets


def main(argv: list[str]) -> None:
    rows = measure("--quick" in argv, log=lambda text: print(text, file=sys.stderr))
    print("\n".join(section(rows)[0]))


if __name__ == "__main__":
    main(sys.argv[1:])
