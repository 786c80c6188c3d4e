"""The real Petri-net tools the tests compare us with: TAPAAL's verifypn and verifydtapn, LoLA.

They are looked for in ``$MCL2PNML_PEERS``, then in ``../shared/peers/bin`` beside
the repository, then on PATH. A test that needs one calls :func:`need`, which
skips with the reason when the tool is absent (a clone without ``../shared``) or
cannot start (verifypn without GLPK). Every call has a timeout.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path

import pytest

from helpers import ROOT

VERIFYPN = "verifypn-linux64"
VERIFYDTAPN = "verifydtapn"
LOLA = "lola"
TIMEOUT = 120.0

_DEADLOCK_QUERY = """<?xml version="1.0"?>
<property-set xmlns="http://mcc.lip6.fr/">
  <property><id>deadlock</id><description>EF deadlock</description>
    <formula><exists-path><finally><deadlock/></finally></exists-path></formula></property>
</property-set>
"""


def _places() -> list[tuple[str, Path]]:
    found = []
    if os.environ.get("MCL2PNML_PEERS"):
        found.append(("$MCL2PNML_PEERS", Path(os.environ["MCL2PNML_PEERS"])))
    found.append(("../shared/peers/bin", ROOT.parent / "shared" / "peers" / "bin"))
    return found


@lru_cache(maxsize=None)
def find(name: str) -> tuple[Path | None, str]:
    """The tool's path, or None and why it is not usable."""
    for _, folder in _places():
        if (folder / name).is_file():
            path = folder / name
            break
    else:
        on_path = shutil.which(name)
        if not on_path:
            where = ", ".join(label for label, _ in _places())
            return None, f"{name} not found in {where} or on PATH"
        path = Path(on_path)
    try:
        probe = subprocess.run([str(path), "--help"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as e:
        return None, f"{path} does not start: {e}"
    if "error while loading shared libraries" in probe.stderr:
        return None, f"{path} does not start: {probe.stderr.strip()} (verifypn needs libglpk40)"
    return path, ""


def need(name: str) -> Path:
    """The tool's path; skips the calling test, saying why, when it is not usable."""
    path, why = find(name)
    if path is None:
        pytest.skip(why)
    return path


def _run(args: list[str]) -> str:
    r = subprocess.run(args, capture_output=True, text=True, timeout=TIMEOUT)
    return r.stdout + r.stderr


def verifypn_states(net: Path) -> int | None:
    """verifypn's count of reachable markings, reductions off; None if it gives none."""
    out = _run([str(need(VERIFYPN)), "-n", "1", "-e", "-r", "0", "-p", str(net)])
    m = re.search(r"STATE_SPACE STATES (\d+)", out)
    return int(m.group(1)) if m else None


def verifypn_deadlock(net: Path, scratch: Path, reductions: bool = False) -> bool | None:
    """verifypn's answer to EF deadlock, reductions off (``reductions``: its defaults, the
    structural reductions and stubborn sets a user gets); None if it gives none."""
    query = scratch / "deadlock.xml"
    query.write_text(_DEADLOCK_QUERY)
    off = [] if reductions else ["-r", "0", "-p", "-s", "BFS"]
    out = _run([str(need(VERIFYPN)), "-x", "1", *off, str(net), str(query)])
    m = re.search(r"FORMULA \S+ (TRUE|FALSE)", out)
    return None if m is None else m.group(1) == "TRUE"


def _lola_net(net: Path) -> list[str]:
    """How LoLA is told to read ``net``: PNML by option, its own format (.lola) as is."""
    return [str(net)] if net.suffix in (".lola", ".llnet") else ["--pnmlnet", str(net)]


def lola_states(net: Path) -> int | None:
    """LoLA's count of reachable markings, stubborn sets off; None if it gives none."""
    out = _run([str(need(LOLA)), *_lola_net(net), "--check=full", "--stubborn=off"])
    m = re.search(r"markings\s*:\s*(\d+)", out)
    return int(m.group(1)) if m else None


def lola_deadlock(net: Path, reductions: bool = False) -> bool | None:
    """LoLA's answer to EF DEADLOCK, stubborn sets off (``reductions``: its default
    stubborn sets); None if it gives none.

    LoLA's net reduction is off either way: with it, this build's EF DEADLOCK
    never answers false (on two markings in a cycle it counts millions and
    stays unknown), and its deadlock check (``--check=deadlockfreedom``)
    finds a deadlock in a net that has none: places a (marked) and b,
    transitions a -> b, b -> a, and 2a -> 2a, never enabled.
    """
    stubborn = [] if reductions else ["--stubborn=off"]
    out = _run([str(need(LOLA)), *_lola_net(net), "--formula=EF DEADLOCK", *stubborn,
                "--netreduction=off"])
    # the final table, which also holds a verdict reached while preprocessing
    m = re.search(r"^\s*formula #\s*0:.*?\s(true|false)\s",
                  out.partition("FINAL RESULTS")[2], re.M)
    return None if m is None else m.group(1) == "true"


# -- the Model Checking Contest's XML queries (tests/io/test_queries.py) --------------------

def _verdicts(pattern: str, out: str) -> dict[str, bool]:
    return {m.group(1): m.group(2).lower() == "true" for m in re.finditer(pattern, out, re.M)}


def verifypn_queries(net: Path, queries: Path, count: int) -> dict[str, bool]:
    """verifypn's answer to each of the ``count`` properties of ``queries``, reductions off."""
    numbers = ",".join(str(i) for i in range(1, count + 1))
    out = _run([str(need(VERIFYPN)), "-x", numbers, "-r", "0", "-p", "-s", "BFS",
                str(net), str(queries)])
    return _verdicts(r"^FORMULA (\S+) (TRUE|FALSE)", out)


def lola_queries(net: Path, queries: Path, reductions: bool = True) -> dict[str, bool]:
    """LoLA's answer to each property of ``queries`` (``--xmlformula``), from its final table
    (``  ID:  CATEGORY  true|false  PRODUCED BY``; ``unknown`` is left out); ``reductions``:
    with its net reduction (its default) or without."""
    off = [] if reductions else ["--netreduction=off"]
    out = _run([str(need(LOLA)), "--pnmlnet", str(net), "--xmlformula", f"--formula={queries}",
                *off])
    table = out.partition("FINAL RESULTS")[2]
    return _verdicts(r"^\s*(\S+):.*?\s(true|false)\s", table)


# -- a mission's own properties, one category file at a time (test_properties_peers.py) ----

def verifypn_category(net: Path, queries: Path, count: int, ltl: bool) -> dict[str, bool]:
    """verifypn's answer to each of the ``count`` queries of one category file (``ltl``: the
    LTL category, which it reads only when told; otherwise CTL or reachability), with the
    net reductions and stubborn sets a user gets (its defaults).

    Its query simplification is off (``-q 0``): on some generated properties (a bounded
    existence between two scopes' predicates) its linear programs run to their 30 s
    time-out, and the whole call past two minutes, for an answer it gives in a tenth
    of a second without them.
    """
    numbers = ",".join(str(i) for i in range(1, count + 1))
    out = _run([str(need(VERIFYPN)), *(["-ltl"] if ltl else []), "-q", "0", "-x", numbers,
                str(net), str(queries)])
    return _verdicts(r"^FORMULA (\S+) (TRUE|FALSE)", out)


def lola_each(net: Path, queries: Path, scratch: Path, only: str | None = None,
              reductions: bool = True) -> dict[str, bool]:
    """LoLA's answer to each query of ``queries`` (``only``: to that one), one call per
    query: given several, this build's portfolio idles for the time limit of one before it
    takes the next (85 s on the paper's mission, for answers it has in a tenth of a second
    alone). ``reductions``: with its net reduction (its default) or without."""
    from lxml import etree
    tree = etree.parse(str(queries))
    answers: dict[str, bool] = {}
    for k, prop in enumerate(tree.getroot()):
        if only is not None and prop.findtext("{*}id") != only:
            continue
        single = etree.Element(tree.getroot().tag, nsmap=tree.getroot().nsmap)
        single.append(prop)
        path = scratch / f"{queries.stem}.{k}{'' if reductions else '.unreduced'}.xml"
        path.write_bytes(etree.tostring(single, xml_declaration=True, encoding="utf-8"))
        answers.update(lola_queries(net, path, reductions))
    return answers


# -- TAPAAL's timed engine on our timed-arc nets (tests/io/test_tapn.py) -----------------------

#: The address space a verifydtapn call may take: past it the call fails, and gives no verdict
#: (a discrete-time state space with long time-outs can take all the memory there is).
VERIFYDTAPN_MEMORY = 4 << 30


def _limit_memory() -> None:
    import resource
    resource.setrlimit(resource.RLIMIT_AS, (VERIFYDTAPN_MEMORY, VERIFYDTAPN_MEMORY))


def verifydtapn(net: Path, query: Path, bound: int, timeout: float = 60.0,
                ptrie: bool = False) -> tuple[bool | None, str]:
    """verifydtapn's verdict on the text query ``query`` for the timed-arc net ``net``, and its
    output; None when it gives none: out of time or memory, or a verdict for the ``-k bound``
    part of the state space only (``Max number of tokens found ...: >K``), which does not count.
    Its exit status is 0 whatever the verdict: the verdict is the line it prints.
    ``ptrie``: its PTrie store (``-p 1``), about 9 times less memory for twice the time."""
    args = [str(need(VERIFYDTAPN)), "-k", str(bound), *(["-p", "1"] if ptrie else []),
            str(net), str(query)]
    try:
        r = subprocess.run(args, capture_output=True, text=True, timeout=timeout,
                           preexec_fn=_limit_memory)
    except subprocess.TimeoutExpired:
        return None, f"no verdict within {timeout:g} s"
    out = r.stdout + r.stderr
    verdict = re.search(r"^Query is (NOT )?satisfied\.", out, re.M)
    tokens = re.search(r"^Max number of tokens found in any reachable marking: *(\S+)", out, re.M)
    if verdict is None or tokens is None or tokens.group(1).startswith(">"):
        return None, out
    return verdict.group(1) is None, out
