"""docs/tutorial.md and docs/interop.md, run: every command of their console blocks,
and what it prints.

The tutorial's blocks are golden files: each ``$ command`` is followed by
what it prints (standard output and standard error, as a terminal shows
them). A block preceded by ``<!-- lines: N -->`` keeps the first N lines and
then ``...``. The commands run in order, in one scratch directory holding a
copy of ``examples/``, so that a later step uses what an earlier one wrote.

    python tests/tutorial.py            # check: exit 1 and a diff if one is stale
    python tests/tutorial.py --update   # rewrite the outputs, and the pictures in
                                        # docs/tutorial/ (the PNG files the commands write)
"""
from __future__ import annotations

import difflib
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "tutorial.md"
#: The documents whose ``console`` blocks are checked (other tools' commands,
#: which cannot run here, are in ``sh`` blocks).
DOCS = (DOC, ROOT / "docs" / "interop.md")
PICTURES = ROOT / "docs" / "tutorial"
BLOCK = re.compile(r"(?:<!-- lines: (\d+) -->\n)?```console\n(.*?)```", re.S)


def run_command(line: str, cwd: Path) -> str:
    """One ``$`` line, as a shell would run it; ``mcl2pnml`` is this checkout's."""
    args = shlex.split(line, comments=True)
    if args and args[0] == "mcl2pnml":
        args = [sys.executable, "-m", "mcl2pnml", *args[1:]]
    env = {**os.environ, "COLUMNS": "100", "PYTHONPATH": str(ROOT)}
    out = subprocess.run(args, cwd=cwd, capture_output=True, text=True, env=env, timeout=600)
    return (out.stdout + out.stderr).rstrip("\n")


def render(text: str, cwd: Path) -> str:
    """The tutorial with every block's output as the commands print it now."""
    def block(m: re.Match) -> str:
        limit = int(m.group(1)) if m.group(1) else None
        lines = []
        for line in m.group(2).split("\n"):
            if line.startswith("$ "):
                lines.append(line)
                out = run_command(line[2:], cwd).split("\n") if line[2:].strip() else []
                out = [o for o in out if o != ""] if out == [""] else out
                if limit is not None and len(out) > limit:
                    out = out[:limit] + ["..."]
                lines += out
        head = f"<!-- lines: {limit} -->\n" if limit is not None else ""
        return head + "```console\n" + "\n".join(lines) + "\n```"
    return BLOCK.sub(block, text)


def main(argv: list[str]) -> int:
    update = "--update" in argv
    stale = 0
    for doc in DOCS:
        text = doc.read_text()
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp)
            shutil.copytree(ROOT / "examples", work / "examples")
            fresh = render(text, work)
            if update:
                doc.write_text(fresh)
                if doc == DOC:
                    PICTURES.mkdir(exist_ok=True)
                    for png in work.glob("*.png"):
                        shutil.copy(png, PICTURES / png.name)
                continue
        if fresh != text:
            name = str(doc.relative_to(ROOT))
            sys.stdout.writelines(difflib.unified_diff(text.splitlines(True),
                                                       fresh.splitlines(True), name,
                                                       "as run now"))
            stale = 1
    return stale


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
