"""docs/tutorial.md and docs/interop.md are true: every command in them prints what
they show, and every picture is there (python tests/tutorial.py --update, or this
test under MCL2PNML_REGOLD=1, rewrites the outputs and the tutorial's pictures)."""
import re

from helpers import REGOLD, ROOT
from tutorial import DOC, main


def test_every_command_prints_what_the_tutorial_shows(capsys):
    stale = main(["--update"] if REGOLD else [])
    assert stale == 0, ("the docs no longer match what their commands print "
                        "(python tests/tutorial.py --update):\n" + capsys.readouterr().out)


def test_every_picture_is_there():
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", DOC.read_text())
    assert len(pictures) >= 5
    for picture in pictures:
        path = DOC.parent / picture
        assert path.is_file() and path.read_bytes().startswith(b"\x89PNG"), picture
    assert (ROOT / "docs" / "interop.md").is_file()
