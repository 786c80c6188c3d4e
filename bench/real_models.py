"""Full state spaces of Model Checking Contest models: ``mcl2pnml analyze --state-space``
against TAPAAL's verifypn and LoLA, each a fresh process, measured in the same run.

Run:  .venv/bin/python -m bench.real_models

The models are the PNML files of ``../shared/external-nets/bench-models/``
beside the checkout where it is there, else of ``bench/models/`` (where each
comes from: ``bench/models/PROVENANCE.md``); each row says which folder its
file was read from (:func:`models`). Each tool runs as the command a user types,
start-up included, under GNU ``time``: wall-clock seconds and the peak
resident memory of the process (its ``ru_maxrss``, the kernel's VmHWM at
exit; ``time`` itself is a small parent, so the fork does not inflate it).
The peers run without reductions, to compare exploration with exploration:
``verifypn-linux64 -n 1 -e -r 0 -p`` and ``lola --check=full --stubborn=off``
(``../shared/peers/README.md``). A tool that is not installed, fails or
passes :data:`TIMEOUT` seconds gets ``None``.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: Where the models are looked for, in order: the shared folder beside the checkout, then
#: the benchmark's own (git ignores PNML there: other projects' data are not kept here).
FOLDERS = (ROOT.parent / "shared" / "external-nets" / "bench-models", ROOT / "bench" / "models")
PEERS = ROOT.parent / "shared" / "peers" / "bin"
TIMEOUT = 120.0


def _tool(name: str) -> str | None:
    local = PEERS / name
    return str(local) if local.exists() else shutil.which(name)


def commands(model: Path) -> dict[str, list[str] | None]:
    verifypn, lola = _tool("verifypn-linux64"), _tool("lola")
    ours = Path(sys.executable).with_name("mcl2pnml")
    return {
        "ours": [str(ours), "analyze", "--state-space", "--json", str(model)],
        "verifypn": verifypn and [verifypn, "-n", "1", "-e", "-r", "0", "-p", str(model)],
        "lola": lola and [lola, "--pnmlnet", str(model), "--check=full", "--stubborn=off"],
    }


def states_of(tool: str, text: str) -> int | None:
    """The number of markings each tool prints."""
    pattern = {"ours": r'"states": (\d+)', "verifypn": r"STATE_SPACE STATES (\d+)",
               "lola": r"markings\s*:\s*(\d+)"}[tool]
    found = re.search(pattern, text)
    return int(found.group(1)) if found else None


#: What each peer prints of its exploration alone (start-up, parsing and output
#: aside): verifypn in seconds, LoLA in whole seconds.
EXPLORATION = {"verifypn": r"Spent ([\d.]+) on verification",
               "lola": r"time used\s*:\s*([\d.]+)"}


def timed(command: list[str], timeout: float = TIMEOUT) -> tuple[float, float, str, int] | None:
    """One run of ``command`` under GNU ``time``: (wall seconds, peak MB, its output
    (standard output, then standard error), exit status); None if it timed out or
    ``time`` printed no peak."""
    timer = shutil.which("time") or "/usr/bin/time"
    start = time.perf_counter()
    try:
        out = subprocess.run([timer, "-f", "PEAK_KB %M", *command], capture_output=True,
                             text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    seconds = time.perf_counter() - start
    peak = re.search(r"PEAK_KB (\d+)", out.stderr)
    if peak is None:
        return None
    return seconds, int(peak.group(1)) / 1024, out.stdout + out.stderr, out.returncode


def measure(tool: str, command: list[str]) -> dict | None:
    """Seconds, peak MB and markings of one run, or None if it failed or timed out.

    ``explore_seconds`` is the exploration alone where the tool reports it.
    """
    ran = timed(command)
    if ran is None:
        return None
    seconds, peak_mb, output, status = ran
    states = states_of(tool, output)
    if states is None:
        return None
    inner = re.search(EXPLORATION[tool], output) if tool in EXPLORATION else None
    return {"seconds": seconds, "peak_mb": peak_mb, "states": states,
            "partial": status == 3,
            "explore_seconds": float(inner.group(1)) if inner else None}


def models() -> list[Path]:
    """Each model once, from the first folder of :data:`FOLDERS` that has it."""
    found: dict[str, Path] = {}
    for folder in FOLDERS:
        for model in sorted(folder.glob("*.pnml")) if folder.is_dir() else ():
            found.setdefault(model.stem, model)
    return [found[name] for name in sorted(found)]


def folder_of(model: Path) -> str:
    """The folder a model was read from, as the table says it."""
    for base, shown in ((ROOT, ""), (ROOT.parent, "../")):
        try:
            return shown + str(model.parent.relative_to(base)) + "/"
        except ValueError:
            continue
    return str(model.parent) + "/"


def run(log=lambda text: None) -> list[dict]:
    """One row a model: each tool's measurement (None where it did not finish)."""
    rows = []
    for model in models():
        row = {"model": model.stem, "from": folder_of(model)}
        for tool, command in commands(model).items():
            log(f"  {model.stem}: {tool}")
            row[tool] = measure(tool, command) if command else None
        rows.append(row)
    return rows


def table(rows: list[dict]) -> list[str]:
    lines = ["| model | read from | markings | ours (s) | ours (MB) | verifypn (s) "
             "| verifypn (MB) | LoLA (s) | LoLA (MB) | ours / faster peer (time) |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        o = r["ours"]
        cells = [r["model"], f"`{r['from']}`", f"{o['states']:,}" if o else "-"]
        for tool in ("ours", "verifypn", "lola"):
            m = r[tool]
            cells += [f"{m['seconds']:.2f}", f"{m['peak_mb']:.0f}"] if m else ["-", "-"]
        peers = [r[t]["seconds"] for t in ("verifypn", "lola") if r[t]]
        cells.append(f"{o['seconds'] / min(peers):.1f}x" if o and peers else "-")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


if __name__ == "__main__":
    print("\n".join(table(run(log=lambda t: print(t, file=sys.stderr)))))
