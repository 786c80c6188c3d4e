"""docs/tutorial.md and docs/interop.md, run: every command of their console blocks,
and what it prints.

The documents' blocks are golden files: each ``$ command`` is followed by
what it prints (standard output and standard error, as a terminal shows
them). A block preceded by ``<!-- lines: N -->`` keeps the first N lines and
then ``...``. The commands run in order, in one scratch directory holding a
copy of ``examples/`` and of ``docs/interop/`` (the scripts interop.md runs),
so that a later step uses what an earlier one wrote.

A ``$`` line is a bash command line (pipes and redirections work), with
these names first on PATH: ``mcl2pnml`` is this checkout's, ``python`` this
interpreter (the virtualenv's, with pm4py and SNAKES), and
``verifypn-linux64`` and ``lola`` the peer tools, found as tests/support/peers.py
finds them (``$MCL2PNML_PEERS``, ``../shared/peers/bin``, PATH), and
``woped-pnml-import`` and ``pipe-pnml-import`` the editors' readers, run as
tests/support/editors.py runs them (Java and ``../shared/peers``). A block that
calls a peer that is not there is left as it is and not compared; the check
says which blocks and why (tests/commands/test_tutorial.py skips with that reason),
and the rest of the documents is still checked.

    python tests/support/tutorial.py            # check: exit 1 and a diff if one is stale
    python tests/support/tutorial.py --update   # rewrite the outputs, and the pictures in
                                        # docs/tutorial/ (the PNG files the commands write)
"""
from __future__ import annotations

import difflib
import os
import re
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import forkcli  # noqa: E402  (tests/ is not a package)
from editors import archived as archived_editor, find as find_editor  # noqa: E402
from peers import LOLA, VERIFYPN, find  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "tutorial.md"
#: The documents whose ``console`` blocks are checked (other tools' commands,
#: which cannot run here, are in ``sh`` blocks).
DOCS = (DOC, ROOT / "docs" / "interop.md")
PICTURES = ROOT / "docs" / "tutorial"
#: What the commands find in their scratch directory, copied from the checkout.
COPIED = ("examples", "docs/interop")
BLOCK = re.compile(r"(?:<!-- lines: (\d+) -->\n)?```console\n(.*?)```", re.S)
#: The editors' PNML readers a ``$`` line may call, headless (tests/support/editors.py), by the
#: name the documents give them.
EDITORS = {"woped-pnml-import": "woped", "pipe-pnml-import": "pipe"}
#: The peer tools a ``$`` line may call.
PEERS = (VERIFYPN, LOLA, *EDITORS)
#: A peer called by a command line: first, or after a pipe, ``;``, ``&&`` or ``(``.
CALLS = re.compile(r"(?:^|[|;&(]\s*)(" + "|".join(map(re.escape, PEERS)) + r")(?=\s|$)")


@dataclass
class Report:
    """What one check found: stale documents and their diff, and what it could not run."""

    stale: bool = False
    diff: list[str] = field(default_factory=list)
    #: blocks that call a peer, compared
    peer_blocks: int = 0
    #: blocks not compared, each with the reason
    unchecked: list[str] = field(default_factory=list)


def tool_dir(work: Path) -> tuple[Path, dict[str, str]]:
    """A ``bin`` directory of the names a ``$`` line may call, and why each absent peer is."""
    bin_ = work / ".bin"
    bin_.mkdir()
    # forked from a server that has imported the command (tests/support/forkcli.py)
    served = forkcli.server()
    command = (f'exec "{sys.executable}" -m mcl2pnml "$@"' if served is None else
               f'{forkcli.ENV}="{served}" exec "{sys.executable}" -S "{forkcli.__file__}" run "$@"')
    wrappers = {"mcl2pnml": command,
                "python": f'exec "{sys.executable}" "$@"'}
    absent = {}
    for peer in PEERS:
        if peer in EDITORS:
            command, why = find_editor(EDITORS[peer])
            # its class-data archive, where the editors' tests left one: a third off its start
            command = command and archived_editor(EDITORS[peer])
            path = command and " ".join(f'"{c}"' for c in command)
        else:
            path, why = find(peer)
            path = path and f'"{path}"'
        if path is None:
            absent[peer] = why
        else:
            wrappers[peer] = f'exec {path} "$@"'
    for name, body in wrappers.items():
        (bin_ / name).write_text(f"#!/bin/sh\n{body}\n")
        (bin_ / name).chmod(0o755)
    return bin_, absent


def run_command(line: str, cwd: Path, bin_: Path) -> str:
    """One ``$`` line, run by bash with ``bin_`` first on PATH."""
    env = {**os.environ, "COLUMNS": "100", "PYTHONPATH": str(ROOT),
           "PATH": f"{bin_}{os.pathsep}{os.environ.get('PATH', '')}"}
    out = subprocess.run(["bash", "-c", line], cwd=cwd, capture_output=True, text=True,
                         env=env, timeout=600)
    return (out.stdout + out.stderr).rstrip("\n")


def render(text: str, cwd: Path, bin_: Path, absent: dict[str, str], report: Report,
           name: str) -> str:
    """The document with every block's output as the commands print it now; a block
    that calls an absent peer is kept as it is, and said in ``report``."""
    def block(m: re.Match) -> str:
        commands = [line[2:] for line in m.group(2).split("\n") if line.startswith("$ ")]
        called = {c.group(1) for line in commands for c in CALLS.finditer(line)}
        if called:
            missing = sorted(called & set(absent))
            if missing:
                report.unchecked.append(f"{name}, the block of `$ {commands[0]}`: "
                                        + "; ".join(absent[p] for p in missing))
                return m.group(0)
            report.peer_blocks += 1
        limit = int(m.group(1)) if m.group(1) else None
        lines = []
        for line in m.group(2).split("\n"):
            if line.startswith("$ "):
                lines.append(line)
                out = run_command(line[2:], cwd, bin_).split("\n") if line[2:].strip() else []
                out = [o for o in out if o != ""] if out == [""] else out
                if limit is not None and len(out) > limit:
                    out = out[:limit] + ["..."]
                lines += out
        head = f"<!-- lines: {limit} -->\n" if limit is not None else ""
        return head + "```console\n" + "\n".join(lines) + "\n```"
    return BLOCK.sub(block, text)


def check(update: bool = False, docs=DOCS) -> Report:
    """Run every document's blocks; with ``update``, write what they print now."""
    report = Report()
    for doc in docs:
        text = doc.read_text()
        name = str(doc.relative_to(ROOT))
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp)
            for copied in COPIED:
                shutil.copytree(ROOT / copied, work / copied)
            bin_, absent = tool_dir(work)
            fresh = render(text, work, bin_, absent, report, name)
            if update:
                doc.write_text(fresh)
                if doc == DOC:
                    PICTURES.mkdir(exist_ok=True)
                    for png in work.glob("*.png"):
                        shutil.copy(png, PICTURES / png.name)
                continue
        if fresh != text:
            report.diff += difflib.unified_diff(text.splitlines(True), fresh.splitlines(True),
                                                name, "as run now")
            report.stale = True
    return report


def main(argv: list[str]) -> int:
    report = check("--update" in argv)
    sys.stdout.writelines(report.diff)
    for reason in report.unchecked:
        print(f"not compared: {reason}", file=sys.stderr)
    return int(report.stale)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
