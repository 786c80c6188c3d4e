"""What several test files share: where things are, the command line, golden files,
the two engines, and a net with every feature of the core.

Golden files hold what the code gives for fixed inputs: ``*.golden`` (the
compiler's verdicts), ``*.expected`` (the message of each invalid input) and
the console blocks of the tutorial (tests/support/tutorial.py). ``MCL2PNML_REGOLD=1``
rewrites every one of them after a deliberate change; review the diff before
committing it.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import forkcli

from mcl2pnml.core.errors import Mcl2PnmlError
from mcl2pnml.core.net import Net, NetBuilder, Timing
from mcl2pnml.language.compiler import compile_checked
from mcl2pnml.runtime.aal import ScriptedVehicle
from mcl2pnml.runtime.engine import run
from mcl2pnml.runtime.executor import PetriEngine
from mcl2pnml.runtime.reference import ReferenceEngine

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parents[1] / "data"
REGOLD = os.environ.get("MCL2PNML_REGOLD") == "1"
#: The official PNML grammar (pnml.org's grammar.zip, not ours to ship) where a checkout
#: keeps it, beside it: validate never looks for it, so the tests pass it explicitly.
GRAMMAR = ROOT.parent / "shared" / "pnml-grammar"
#: Why a test that needs the official grammar is skipped without it.
NO_GRAMMAR = (f"the official PNML grammar is not at {GRAMMAR} (pnml.org's version-2009 "
              "grammar.zip, not ours to ship); our own schema is applied without it")


def official_grammar_dir() -> Path | None:
    """:data:`GRAMMAR`, where it holds the grammar; else None."""
    return GRAMMAR if (GRAMMAR / "ptnet.pntd").is_file() else None

#: The engines, as ``mcl2pnml run --engine`` names them.
ENGINES = ("petri", "reference")
#: Virtual seconds after which a run of a generated mission is cut (it may wait for ever).
MAX_TIME = 2_000.0


def run_cli(*args, cwd=None, env=None, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python -m mcl2pnml ARGS`` as a process of its own, its output captured as text.

    The process is forked from one that has imported the command already
    (tests/support/forkcli.py: the same exit status, streams and tracebacks, without a
    quarter of a second of imports per command). The interpreter is the one
    running the tests, so the command is this checkout's; the timeout only
    guards against a hang, nothing is timed.
    """
    return forkcli.run(args, cwd=cwd, env=env, timeout=timeout)


def cli(*args):
    """The command in this process (click's runner): fast, and its exit status."""
    from click.testing import CliRunner

    from mcl2pnml.cli import main
    return CliRunner().invoke(main, [str(a) for a in args])


def one_error(out, *pieces: str) -> str:
    """Exit status 2, one message (its first line holds ``pieces``), no traceback."""
    text = getattr(out, "output", None) or out.stderr
    code = getattr(out, "exit_code", None)
    code = out.returncode if code is None else code
    assert code == 2, text
    assert "Traceback" not in text, text
    error = getattr(out, "exception", None)     # in process: only the CLI's own exit
    assert error is None or isinstance(error, SystemExit), repr(error)
    first = text.strip().splitlines()[0]
    for piece in pieces:
        assert piece in first, text
    return text


def assert_golden(path: Path, text: str) -> None:
    """``text`` is what the golden file ``path`` holds.

    With ``MCL2PNML_REGOLD=1`` the file is rewritten instead; a missing one
    is written and the test fails, so that a new case is reviewed before it
    counts.
    """
    if REGOLD or not path.exists():
        path.write_text(text)
        if not REGOLD:
            pytest.fail(f"wrote the missing golden file {path}; review it and commit it")
    assert text == path.read_text(), f"not what {path.name} holds (MCL2PNML_REGOLD=1 rewrites it)"


def assert_error_golden(path: Path, error: BaseException) -> None:
    """The error an invalid input gives is the message its ``.expected`` file holds."""
    assert_golden(path.with_suffix(".expected"), str(error) + "\n")


# -- the engines ----------------------------------------------------------------------

class Engine:
    """One engine, named as ``mcl2pnml run --engine`` names it. Called on a checked
    mission, it builds that engine: the executor on the compiled net (``net`` when the
    caller has compiled it already), or the reference engine on the MCL itself."""

    def __init__(self, name: str):
        if name not in ENGINES:
            raise ValueError(f"no engine {name!r}; the engines are {', '.join(ENGINES)}")
        self.name = name

    def __call__(self, checked, net=None):
        if self.name == "petri":
            return PetriEngine(net or compile_checked(checked))
        return ReferenceEngine(checked)

    def __repr__(self) -> str:
        return self.name


def engines(checked, net=None) -> list:
    """Both engines on one checked mission, the executor first."""
    return [Engine(name)(checked, net) for name in ENGINES]


def both(checked, script: dict, net=None) -> tuple[dict, dict]:
    """The ``--json`` run of the executor and of the reference engine, with one script.

    ``net`` is the compiled mission when the caller has it already.
    """
    text = json.dumps(script)
    out = []
    for engine in engines(checked, net):
        try:
            out.append(run(engine, ScriptedVehicle.from_json(text),
                           max_time=MAX_TIME).as_json())
        except Mcl2PnmlError as e:   # a zero-time loop: both must say so
            out.append({"error": e.message})
    return out[0], out[1]


# -- nets -----------------------------------------------------------------------------

def everything() -> Net:
    """A net with every feature of the core."""
    b = NetBuilder("everything")
    b.place("B", 1, interface="B", payload={"role": "begin"})
    b.place("AchieveDepth.MTX", 1, interface="MTX")
    b.place("({'a'}, {'b'})", name="a place pm4py could name")
    b.place("heap", 3)
    b.transition("t03", name="timeout", timing=Timing.delay(60),
                 payload={"action": "disable", "primitive": "KeepDepth", "args": [4.0]})
    b.transition("t_window", timing=Timing(1.5, None))
    b.arc("B", "t03")
    b.read("AchieveDepth.MTX", "t03")
    b.arc("t03", "({'a'}, {'b'})", 2)
    b.arc("heap", "t_window", 3)
    b.arc("t_window", "B")
    return b.build()


#: What a property's comment says when it holds in time only (docs/time.md).
UNTIMED_ONLY = "fails on the untimed net"


def untimed_only(props: Path) -> set[str]:
    """The properties of ``props`` whose comment (the ``//`` lines just above them) says
    they fail on the untimed net: they hold in the time the mission runs in only."""
    import re
    names, block = set(), []
    for line in props.read_text().splitlines():
        if line.startswith("//"):
            block.append(line[2:].strip())
            continue
        found = re.match(r"property\s+(\w+)\s*:", line)
        if found and UNTIMED_ONLY in " ".join(block):
            names.add(found.group(1))
        block = []
    return names
