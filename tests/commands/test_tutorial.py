"""docs/tutorial.md and docs/interop.md are true: every command in them prints what
they show, and every picture is there (python tests/support/tutorial.py --update, or this
test under MCL2PNML_REGOLD=1, rewrites the outputs and the tutorial's pictures).

The blocks that run verifypn or LoLA are compared where those tools are found;
where one is not, the documents are still checked without those blocks, and
a test of its own skips saying which blocks were not compared and why.
"""
import re
import sys

import pytest

from helpers import REGOLD, ROOT
from tutorial import DOC, DOCS, Report, check, render, tool_dir


def _fresh(doc) -> Report:
    report = check(update=REGOLD, docs=[doc])
    assert not report.stale, (f"{doc.name} no longer matches what its commands print "
                              "(python tests/support/tutorial.py --update):\n" + "".join(report.diff))
    return report


def test_every_command_prints_what_the_tutorial_shows():
    _fresh(DOC)


def test_every_command_prints_what_the_interop_page_shows_and_so_do_the_peers():
    """interop.md, its own commands and those of the peers (verifypn, LoLA, pm4py,
    SNAKES, the editors); the blocks of a peer not found here are kept, and said."""
    (interop,) = [d for d in DOCS if d != DOC]
    report = _fresh(interop)
    if report.unchecked:
        pytest.skip("the rest matches; not compared: " + " | ".join(report.unchecked))
    # verifypn's and LoLA's blocks of interop.md were run and compared above
    assert report.peer_blocks >= 2, report


def test_a_block_of_an_absent_peer_is_kept_and_said(tmp_path):
    text = ("```console\n$ echo one | lola --check=full x.lola\nas the doc says\n```\n\n"
            "```console\n$ python -c 'import sys; print(sys.executable)'\n$ echo two | cat\n```\n")
    report = Report()
    bin_, _ = tool_dir(tmp_path)
    fresh = render(text, tmp_path, bin_, {"lola": "lola not found (here on purpose)"}, report,
                   "doc.md")
    kept, ran = fresh.split("\n\n")
    assert kept == text.split("\n\n")[0]           # not run, not rewritten
    assert ran == (f"```console\n$ python -c 'import sys; print(sys.executable)'\n"
                   f"{sys.executable}\n$ echo two | cat\ntwo\n```\n")
    assert report.unchecked == ["doc.md, the block of `$ echo one | lola --check=full x.lola`: "
                                "lola not found (here on purpose)"]
    assert report.peer_blocks == 0


def test_every_picture_is_there():
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", DOC.read_text())
    assert len(pictures) >= 5
    for picture in pictures:
        path = DOC.parent / picture
        assert path.is_file() and path.read_bytes().startswith(b"\x89PNG"), picture
    assert (ROOT / "docs" / "interop.md").is_file()
